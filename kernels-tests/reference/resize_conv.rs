//! f64 reference of the resize-convolution projection, built independently of the crate's
//! (which inverts AᵀA): Gram-Schmidt on the columns of A gives an orthonormal basis Q of the
//! subspace, and the projection of a kernel w is Q Qᵀ w.

/// Column j = (ky, kx) of A: the 4x4 kernel of a 3x3 kernel that is 1 at (ky, kx) only,
/// nearest-upsampled then convolved: 1 at (ky + a, kx + b) for a, b in {0, 1}.
fn column(ky: usize, kx: usize) -> [f64; 16] {
    let mut c = [0.0; 16];
    for a in 0..2 {
        for b in 0..2 {
            c[(ky + a) * 4 + kx + b] = 1.0;
        }
    }
    c
}

/// Orthonormal basis of the resize-conv subspace (9 vectors of 16).
fn basis() -> Vec<[f64; 16]> {
    let mut q: Vec<[f64; 16]> = Vec::new();
    for j in 0..9 {
        let mut v = column(j / 3, j % 3);
        for u in &q {
            let d: f64 = v.iter().zip(u).map(|(a, b)| a * b).sum();
            for (x, y) in v.iter_mut().zip(u) {
                *x -= d * y;
            }
        }
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        q.push(v.map(|x| x / n));
    }
    q
}

/// Every run of 16 values of `w` projected onto the subspace.
pub fn project(w: &[f64]) -> Vec<f64> {
    let q = basis();
    w.chunks(16)
        .flat_map(|k| {
            let mut out = [0.0; 16];
            for u in &q {
                let d: f64 = k.iter().zip(u).map(|(a, b)| a * b).sum();
                for (o, y) in out.iter_mut().zip(u) {
                    *o += d * y;
                }
            }
            out
        })
        .collect()
}
