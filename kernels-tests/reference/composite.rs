//! Front-to-back compositing along depth: x [N, C, D, H, W] (channel 0 the occupancy o) to
//! y[n, c, h, w] = Σ_k T_k x[n, c, d_k, h, w], k counted from the camera (d_k = D-1-k),
//! T_0 = 1, T_{k+1} = T_k (1 - o at d_k).

pub fn composite(x: &[f64], n: usize, c: usize, d: usize, hw: usize) -> Vec<f64> {
    let at = |b: usize, ch: usize, z: usize, s: usize| ((b * c + ch) * d + z) * hw + s;
    let mut y = vec![0.0; n * c * hw];
    for b in 0..n {
        for s in 0..hw {
            for ch in 0..c {
                let mut t = 1.0;
                for k in 0..d {
                    let z = d - 1 - k;
                    y[(b * c + ch) * hw + s] += t * x[at(b, ch, z, s)];
                    t *= 1.0 - x[at(b, 0, z, s)];
                }
            }
        }
    }
    y
}
