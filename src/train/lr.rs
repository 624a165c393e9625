//! Learning-rate schedules for training.

/// The original code's schedule (TensorFlow's `exponential_decay`): `lr0 * rate^(step /
/// decay_steps)`, with the exponent floored when `staircase` is set.
pub fn exponential_decay(lr0: f32, rate: f32, decay_steps: u64, step: u64, staircase: bool) -> f32 {
    let e = step as f64 / decay_steps.max(1) as f64;
    let e = if staircase { e.floor() } else { e };
    (lr0 as f64 * (rate as f64).powf(e)) as f32
}
