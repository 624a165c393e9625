//! Phong shading of image-space maps in f64, written straight from the formula (no shared
//! code with the shader) so that finite differences of it test the GPU backward.

/// Scalar coefficients, as `rendernet::ops::phong::Phong` (f64 here).
#[derive(Clone, Copy)]
pub struct Coeffs {
    pub ambient: f64,
    pub kd: f64,
    pub ks: f64,
    pub shininess: f64,
}

/// `image [N,3,H,W]` from `normal [N,3,H,W]` (encoded in [0,1]), `albedo [N,C,H,W]`
/// (C = 1 broadcast, or 3), `mask [N,1,H,W]`, `light [N,6]`.
pub fn phong(
    k: Coeffs,
    [n, c, h, w]: [usize; 4],
    normal: &[f64],
    albedo: &[f64],
    mask: &[f64],
    light: &[f64],
) -> Vec<f64> {
    let hw = h * w;
    let mut out = vec![0.0; n * 3 * hw];
    for b in 0..n {
        let l = &light[b * 6..b * 6 + 3];
        let col = &light[b * 6 + 3..b * 6 + 6];
        for px in 0..hw {
            let u: Vec<f64> = (0..3).map(|i| 2.0 * normal[(b * 3 + i) * hw + px] - 1.0).collect();
            let len = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt().max(1e-6);
            let nv: Vec<f64> = u.iter().map(|x| x / len).collect();
            let d = nv[0] * l[0] + nv[1] * l[1] + nv[2] * l[2];
            // r = 2 d n - l; v = (0, 0, 1) so r.v is r's z component.
            let r = [2.0 * d * nv[0] - l[0], 2.0 * d * nv[1] - l[1], 2.0 * d * nv[2] - l[2]];
            let spec = if r[2] > 0.0 { r[2].powf(k.shininess) } else { 0.0 };
            let m = mask[b * hw + px];
            for ch in 0..3 {
                let a = albedo[(b * c + if c == 3 { ch } else { 0 }) * hw + px];
                out[(b * 3 + ch) * hw + px] = m * col[ch] * (a * (k.ambient + k.kd * d.max(0.0)) + k.ks * spec);
            }
        }
    }
    out
}

/// The pixel's `(n.l, r.v)`, to keep test inputs away from the two clamps' kinks.
pub fn kinks(normal_px: [f64; 3], l: &[f64]) -> (f64, f64) {
    let u: Vec<f64> = normal_px.iter().map(|v| 2.0 * v - 1.0).collect();
    let len = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let d = (u[0] * l[0] + u[1] * l[1] + u[2] * l[2]) / len;
    (d, 2.0 * d * u[2] / len - l[2])
}
