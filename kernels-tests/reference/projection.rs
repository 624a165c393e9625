//! Reference for the projection unit's 1x1 conv over depth-folded channels.

/// x [N, K, S] (K = C*D folded), w [O, K], b [O] -> y [N, O, S].
pub fn projection(x: &[f64], w: &[f64], b: &[f64], n: usize, k: usize, o: usize, s: usize) -> Vec<f64> {
    let mut y = vec![0.0; n * o * s];
    for ni in 0..n {
        for oi in 0..o {
            for si in 0..s {
                let mut acc = b[oi];
                for ki in 0..k {
                    acc += w[oi * k + ki] * x[(ni * k + ki) * s + si];
                }
                y[(ni * o + oi) * s + si] = acc;
            }
        }
    }
    y
}
