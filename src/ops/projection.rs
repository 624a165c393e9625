//! The projection unit's 1x1 convolution over depth-folded channels (binds
//! `shaders/projection.wgsl`). The camera-aligned grid `[N, C, D, H, W]` is read as
//! `[N, C*D, H, W]` (channel `c*D + d`, a free view), then mixed by weights `[O, C*D, 1, 1]`
//! (PyTorch's 1x1 conv layout) and bias `[O]` into `[N, O, H, W]`. PReLU follows as its own op.
//! The network runs the tiled conv kernels as a matmul (`ConvKernel::Auto`);
//! `shaders/projection.wgsl`, one invocation per output, is `ConvKernel::Reference`: the
//! oracle the tiled kernels are compared with, and `bench --kernel reference`.

use super::conv::{self, ConvKernel, Geometry, Pass};
use super::{expect_shape, reduce};
use crate::error::{Error, Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("projection");

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    k: u32,
    o: u32,
    s: u32,
}

/// Batch, folded channels K = C*D, output channels O, and the image size H, W.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionDims {
    /// Batch size.
    pub n: usize,
    /// Input channels after folding depth in (C*D).
    pub k: usize,
    /// Output channels.
    pub o: usize,
    /// Image height.
    pub h: usize,
    /// Image width.
    pub w: usize,
}

impl ProjectionDims {
    /// Reads the dims from an input `[N, C, D, H, W]` (or already folded `[N, K, H, W]`) and
    /// weights `[O, K, 1, 1]`, checking that K agrees.
    pub fn new(x: &[usize], w: &[usize]) -> Result<Self> {
        let (n, k, h, wd) = match *x {
            [n, c, d, h, wd] => (n, c * d, h, wd),
            [n, k, h, wd] => (n, k, h, wd),
            _ => return Err(shape_err("projection", format!("input {x:?} must be [N,C,D,H,W] or [N,K,H,W]"))),
        };
        match *w {
            [o, wk, 1, 1] if wk == k => Ok(ProjectionDims { n, k, o, h, w: wd }),
            _ => Err(shape_err(
                "projection",
                format!("weights {w:?} must be [O, {k}, 1, 1] for input {x:?} (K = C*D = {k})"),
            )),
        }
    }

    /// The output shape `[N, O, H, W]`.
    pub fn output_shape(&self) -> Vec<usize> {
        vec![self.n, self.o, self.h, self.w]
    }

    /// The 1x1 conv this projection is, for the conv kernels' `Auto` choice (the tiled conv
    /// kernels do a 1x1 conv as a plain matmul: one tap, stride 1, no padding).
    fn geometry(&self) -> Geometry {
        let sp = [1, self.h, self.w];
        Geometry { n: self.n, ci: self.k, co: self.o, input: sp, output: sp, kernel: [1; 3], stride: [1; 3], pad: [0; 3], rank: 4 }
    }

    fn params(&self) -> Params {
        Params { n: self.n as u32, k: self.k as u32, o: self.o as u32, s: (self.h * self.w) as u32 }
    }
}

/// The dimensions of a forward, its bias and output checked against them.
fn checked(x: &Tensor, w: &Tensor, b: &Tensor, y: &Tensor) -> Result<ProjectionDims> {
    let d = ProjectionDims::new(x.shape(), w.shape())?;
    expect_shape("projection", "bias", b, &[d.o])?;
    expect_shape("projection", "output", y, &d.output_shape())?;
    Ok(d)
}

/// `y[n,o] = Σ_k w[o,k] x[n,k] + b[o]` per pixel, on `kernel` (see [`ConvKernel`]; `Auto`
/// unless comparing; `Reference` is `projection.wgsl`).
pub fn forward(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    w: &Tensor,
    b: &Tensor,
    y: &Tensor,
) -> Result<()> {
    let d = checked(x, w, b, y)?;
    let g = d.geometry();
    if conv::use_fast(kernel, Pass::Forward, &g) {
        return conv::dispatch_forward(kernel, gpu, pass, &g, x, w, Some(b), y);
    }
    let args = [Arg::R(x), Arg::R(w), Arg::R(b), Arg::W(y)];
    gpu.dispatch(pass, SHADER, "projection_forward", &d.params(), &args, grid_1d(y.numel() as u64, 64)?)
}

/// `y = prelu(projection(x, w) + b, alpha)`, one slope per output channel (`alpha` `[O]`),
/// in the projection's own dispatch, as [`crate::ops::conv::Conv::forward_prelu`] does for a
/// conv; only where [`fuses_prelu`] holds, elsewhere an error.
#[allow(clippy::too_many_arguments)]
pub fn forward_prelu(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    w: &Tensor,
    b: &Tensor,
    alpha: &Tensor,
    y: &Tensor,
) -> Result<()> {
    let d = checked(x, w, b, y)?;
    expect_shape("projection", "alpha", alpha, &[d.o])?;
    let g = d.geometry();
    if !conv::fuses_prelu(kernel, gpu, &g) {
        return Err(Error::Invalid(format!("projection_forward_prelu: this projection on {kernel:?} does not run the texture kernels, which alone apply a PReLU (see projection::fuses_prelu)")));
    }
    super::conv_fast::forward_act(gpu, pass, &g, x, w, Some(b), Some(alpha), y, conv::operands(gpu, kernel))
}

/// Whether [`forward_prelu`] runs the projection of input `x_shape` and weights `w_shape` on
/// `kernel` and `gpu`: where its forward runs the texture kernels.
pub fn fuses_prelu(kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize]) -> Result<bool> {
    Ok(conv::fuses_prelu(kernel, gpu, &ProjectionDims::new(x_shape, w_shape)?.geometry()))
}

/// `dx = wᵀ dy` (shape of `x`) on `kernel`.
pub fn backward_input(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    dy: &Tensor,
    w: &Tensor,
    dx: &Tensor,
) -> Result<()> {
    let d = ProjectionDims::new(dx.shape(), w.shape())?;
    expect_shape("projection", "dy", dy, &d.output_shape())?;
    let g = d.geometry();
    if conv::use_fast(kernel, Pass::BackwardInput, &g) {
        return conv::dispatch_backward_input(kernel, gpu, pass, &g, dy, w, None, dx);
    }
    let args = [Arg::R(dy), Arg::R(w), Arg::W(dx)];
    gpu.dispatch(pass, SHADER, "projection_backward_input", &d.params(), &args, grid_1d(dx.numel() as u64, 64)?)
}

/// `dw = Σ_n dy xᵀ` (shape `[O, K, 1, 1]`) on `kernel`.
pub fn backward_weight(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    dy: &Tensor,
    dw: &Tensor,
) -> Result<()> {
    let d = ProjectionDims::new(x.shape(), dw.shape())?;
    expect_shape("projection", "dy", dy, &d.output_shape())?;
    let g = d.geometry();
    if conv::use_fast(kernel, Pass::BackwardWeight, &g) {
        return conv::dispatch_backward_weight(kernel, gpu, pass, &g, x, dy, dw);
    }
    let args = [Arg::R(x), Arg::R(dy), Arg::W(dw)];
    gpu.dispatch(pass, SHADER, "projection_backward_weight", &d.params(), &args, grid_1d(dw.numel() as u64, 64)?)
}

/// `db[o] = Σ_{n,h,w} dy[n,o,h,w]`.
pub fn backward_bias(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, db: &Tensor) -> Result<()> {
    let &[n, o, h, w] = dy.shape() else {
        return Err(shape_err("projection", format!("dy {:?} must be [N, O, H, W]", dy.shape())));
    };
    expect_shape("projection", "bias gradient", db, &[o])?;
    reduce::sum_outer_inner(gpu, pass, dy, [n, o, h * w], 1.0, db)
}
