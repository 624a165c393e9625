//! References for the elementwise ops.

pub fn sigmoid(x: &[f64]) -> Vec<f64> {
    x.iter().map(|&v| 1.0 / (1.0 + (-v).exp())).collect()
}

pub fn elu(alpha: f64, x: &[f64]) -> Vec<f64> {
    x.iter().map(|&v| if v > 0.0 { v } else { alpha * (v.exp() - 1.0) }).collect()
}

/// PReLU on x viewed as [N, C, S].
pub fn prelu(x: &[f64], alpha: &[f64], c: usize, s: usize) -> Vec<f64> {
    x.iter().enumerate().map(|(i, &v)| if v > 0.0 { v } else { alpha[(i / s) % c] * v }).collect()
}

/// The dropout kernel's PCG hash, bit for bit.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// Inverted dropout with the kernel's mask.
pub fn dropout(x: &[f64], keep_prob: f64, seed: u32) -> Vec<f64> {
    let threshold = (keep_prob * 4294967296.0).min(u32::MAX as f64) as u32;
    x.iter()
        .enumerate()
        .map(|(i, &v)| if threshold == u32::MAX || pcg(i as u32 ^ pcg(seed)) < threshold { v / keep_prob } else { 0.0 })
        .collect()
}
