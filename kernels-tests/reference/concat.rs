//! Reference for channel concatenation.

/// a [N, C1, S] and b [N, C2, S] -> [N, C1 + C2, S].
pub fn concat(a: &[f64], b: &[f64], n: usize, c1: usize, c2: usize, s: usize) -> Vec<f64> {
    let mut y = Vec::with_capacity(n * (c1 + c2) * s);
    for ni in 0..n {
        y.extend_from_slice(&a[ni * c1 * s..(ni + 1) * c1 * s]);
        y.extend_from_slice(&b[ni * c2 * s..(ni + 1) * c2 * s]);
    }
    y
}

/// Channels `start .. start + len` of x [N, C, S].
pub fn narrow(x: &[f64], n: usize, c: usize, s: usize, start: usize, len: usize) -> Vec<f64> {
    (0..n).flat_map(|ni| x[(ni * c + start) * s..(ni * c + start + len) * s].iter().copied()).collect()
}
