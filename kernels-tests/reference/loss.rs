//! Losses and PSNR's per-image MSE in f64.

/// `mean((p - t)^2)`.
pub fn mse(p: &[f64], t: &[f64]) -> f64 {
    p.iter().zip(t).map(|(a, b)| (a - b) * (a - b)).sum::<f64>() / p.len() as f64
}

/// `mean(-(t ln q + (1 - t) ln(1 - q)))`, `q = clamp(p, lo, hi)`. Tests pass the f32 values
/// of the GPU's bounds (`1 - 1e-7` is 0.99999988 in f32).
pub fn bce(p: &[f64], t: &[f64], lo: f64, hi: f64) -> f64 {
    p.iter()
        .zip(t)
        .map(|(&x, &y)| {
            let q = x.clamp(lo, hi);
            -(y * q.ln() + (1.0 - y) * (1.0 - q).ln())
        })
        .sum::<f64>()
        / p.len() as f64
}

/// MSE of each of the `n` images (equal-sized consecutive chunks).
pub fn per_image_mse(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let per = a.len() / n;
    (0..n).map(|i| mse(&a[i * per..(i + 1) * per], &b[i * per..(i + 1) * per])).collect()
}
