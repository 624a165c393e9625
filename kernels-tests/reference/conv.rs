//! f64 references for convolution and transposed convolution, written independently of
//! the crate: the conv gathers over taps, the transposed conv scatters (PyTorch's
//! definition), so the GPU's gather formulation is checked against a different one. 2D
//! shapes are these with depth 1.

/// One call's sizes. For a conv, `x` is `[n, ci, input]`, `w` `[co, ci, kernel]`, `y`
/// `[n, co, output]`. For a transposed conv, `x` is `[n, ci, input]`, `w` `[ci, co, kernel]`,
/// `y` `[n, co, output]`, and `before` is the padding of the equivalent forward conv.
#[derive(Clone, Copy, Debug)]
pub struct Geom {
    pub n: usize,
    pub ci: usize,
    pub co: usize,
    pub input: [usize; 3],
    pub output: [usize; 3],
    pub kernel: [usize; 3],
    pub stride: [usize; 3],
    pub before: [usize; 3],
}

/// TensorFlow SAME on one axis: `(out, before, after)`.
pub fn same_pads(len: usize, k: usize, s: usize) -> (usize, usize, usize) {
    let out = len.div_ceil(s);
    let total = ((out - 1) * s + k) as i64 - len as i64;
    let total = total.max(0) as usize;
    (out, total / 2, total - total / 2)
}

fn idx(c: usize, sp: [usize; 3], dims: [usize; 3], n: usize, nc: usize) -> usize {
    (((n * nc + c) * dims[0] + sp[0]) * dims[1] + sp[1]) * dims[2] + sp[2]
}

/// Every position of a 3D box.
fn positions(dims: [usize; 3]) -> impl Iterator<Item = [usize; 3]> {
    (0..dims[0]).flat_map(move |a| (0..dims[1]).flat_map(move |b| (0..dims[2]).map(move |c| [a, b, c])))
}

/// `y[n,co,o] = b[co] + Σ x[n,ci,o*s - pad + k] w[co,ci,k]`, zero outside `x`.
pub fn conv(g: &Geom, x: &[f64], w: &[f64], b: Option<&[f64]>) -> Vec<f64> {
    let mut y = vec![0.0; g.n * g.co * g.output.iter().product::<usize>()];
    for n in 0..g.n {
        for co in 0..g.co {
            for o in positions(g.output) {
                let mut acc = b.map_or(0.0, |b| b[co]);
                for ci in 0..g.ci {
                    for k in positions(g.kernel) {
                        let i = [0, 1, 2].map(|a| (o[a] * g.stride[a] + k[a]) as i64 - g.before[a] as i64);
                        if (0..3).all(|a| i[a] >= 0 && i[a] < g.input[a] as i64) {
                            let i = [i[0] as usize, i[1] as usize, i[2] as usize];
                            acc += x[idx(ci, i, g.input, n, g.ci)] * w[idx(ci, k, g.kernel, co, g.ci)];
                        }
                    }
                }
                y[idx(co, o, g.output, n, g.co)] = acc;
            }
        }
    }
    y
}

/// Transposed conv by scattering: every `x[n,ci,i]` adds `x * w[ci,co,k]` to
/// `y[n,co,i*s - pad + k]` when that lies inside `y`; then `b[co]` is added.
pub fn conv_transpose(g: &Geom, x: &[f64], w: &[f64], b: Option<&[f64]>) -> Vec<f64> {
    let mut y = vec![0.0; g.n * g.co * g.output.iter().product::<usize>()];
    for n in 0..g.n {
        for ci in 0..g.ci {
            for i in positions(g.input) {
                let xv = x[idx(ci, i, g.input, n, g.ci)];
                for co in 0..g.co {
                    for k in positions(g.kernel) {
                        let o = [0, 1, 2].map(|a| (i[a] * g.stride[a] + k[a]) as i64 - g.before[a] as i64);
                        if (0..3).all(|a| o[a] >= 0 && o[a] < g.output[a] as i64) {
                            let o = [o[0] as usize, o[1] as usize, o[2] as usize];
                            y[idx(co, o, g.output, n, g.co)] += xv * w[idx(co, k, g.kernel, ci, g.co)];
                        }
                    }
                }
            }
        }
    }
    if let Some(b) = b {
        let sp: usize = g.output.iter().product();
        for (j, v) in y.iter_mut().enumerate() {
            *v += b[(j / sp) % g.co];
        }
    }
    y
}
