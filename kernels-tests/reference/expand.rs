//! Broadcast over space: y[r, s] = x[r] for `rows` rows of `s` values.

pub fn expand(x: &[f64], rows: usize, s: usize) -> Vec<f64> {
    (0..rows * s).map(|i| x[i / s]).collect()
}
