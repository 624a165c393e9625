//! f64 reference of rigid-body resampling: for each output voxel p, the sample point
//! q = c_in + (R_el R_az)^T (p - c_out - t) / s, then trilinear interpolation with zero
//! outside the input grid, written as y(p) = Σ_i x[i] Π_k max(0, 1 - |q_k - i_k|).

/// Batch, channels, input and output spatial sizes (d, h, w).
#[derive(Clone, Copy, Debug)]
pub struct Dims {
    pub n: usize,
    pub c: usize,
    pub inp: [usize; 3],
    pub out: [usize; 3],
}

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// The forward rotation R_el R_az of a pose (s, az, el, t_d, t_h, t_w), row-major over (d, h, w).
pub fn rotation(pose: &[f64]) -> M3 {
    let (sa, ca) = pose[1].sin_cos();
    let (se, ce) = pose[2].sin_cos();
    let raz = [[ca, 0.0, sa], [0.0, 1.0, 0.0], [-sa, 0.0, ca]];
    let rel = [[ce, se, 0.0], [-se, ce, 0.0], [0.0, 0.0, 1.0]];
    mul(&rel, &raz)
}

/// The input-space sample point of output voxel `o` under `pose`.
pub fn sample_point(dims: &Dims, pose: &[f64], o: [usize; 3]) -> [f64; 3] {
    let m = rotation(pose);
    let u: Vec<f64> = (0..3).map(|k| (o[k] as f64 - (dims.out[k] as f64 - 1.0) / 2.0 - pose[3 + k]) / pose[0]).collect();
    // M^T u: column k of M dotted with u.
    std::array::from_fn(|k| (dims.inp[k] as f64 - 1.0) / 2.0 + (0..3).map(|j| m[j][k] * u[j]).sum::<f64>())
}

/// Every output voxel (d, h, w) in row-major order.
pub fn out_voxels(dims: &Dims) -> impl Iterator<Item = [usize; 3]> + '_ {
    let [d, h, w] = dims.out;
    (0..d).flat_map(move |a| (0..h).flat_map(move |b| (0..w).map(move |c| [a, b, c])))
}

/// y [N, C, Do, Ho, Wo] from x [N, C, D, H, W] and poses [N, 6].
pub fn forward(dims: &Dims, x: &[f64], poses: &[f64]) -> Vec<f64> {
    let vi: usize = dims.inp.iter().product();
    let vo: usize = dims.out.iter().product();
    let mut y = vec![0.0; dims.n * dims.c * vo];
    for n in 0..dims.n {
        let pose = &poses[n * 6..n * 6 + 6];
        for (v, o) in out_voxels(dims).enumerate() {
            let q = sample_point(dims, pose, o);
            for corner in 0..8 {
                let i: [i64; 3] = std::array::from_fn(|k| q[k].floor() as i64 + ((corner >> (2 - k)) & 1) as i64);
                if (0..3).any(|k| i[k] < 0 || i[k] >= dims.inp[k] as i64) {
                    continue;
                }
                let w: f64 = (0..3).map(|k| (1.0 - (q[k] - i[k] as f64).abs()).max(0.0)).product();
                let off = (i[0] as usize * dims.inp[1] + i[1] as usize) * dims.inp[2] + i[2] as usize;
                for c in 0..dims.c {
                    y[(n * dims.c + c) * vo + v] += w * x[(n * dims.c + c) * vi + off];
                }
            }
        }
    }
    y
}
