//! Elementwise product with a channel-broadcast mask: y[n, c, s] = x[n, c, s] * m[n, mc, s],
//! mc = 0 for a one-channel mask, else c.

pub fn mul(x: &[f64], m: &[f64], n: usize, c: usize, cm: usize, s: usize) -> Vec<f64> {
    let mut y = vec![0.0; n * c * s];
    for b in 0..n {
        for ch in 0..c {
            let mc = if cm == 1 { 0 } else { ch };
            for i in 0..s {
                y[(b * c + ch) * s + i] = x[(b * c + ch) * s + i] * m[(b * cm + mc) * s + i];
            }
        }
    }
    y
}
