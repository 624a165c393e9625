//! Transposed 3D and 2D convolution (PyTorch's `ConvTranspose3d/2d`: weights
//! `[Cin, Cout, kD, kH, kW]` / `[Cin, Cout, kH, kW]`), with optional bias. It has no shader of
//! its own: a transposed conv is the adjoint of the forward conv that maps its output shape
//! back to its input shape, so it binds `shaders/conv.wgsl` with roles swapped.
//!
//! The mapping, with `C` the "equivalent forward conv" (same kernel, stride and padding,
//! whose input is this op's output `y` and whose output is this op's input `x`; PyTorch's
//! weight layout `[Cin, Cout, k]` is exactly `C`'s `[Cout_C, Cin_C, k]`):
//!
//! | transposed conv             | binds                  | with                          |
//! |-----------------------------|------------------------|-------------------------------|
//! | forward `y = C^T x + b`     | `conv_backward_input`  | `dy := x`, `dx := y`, bias on |
//! | backward_input `dx = C dy`  | `conv_forward`         | `x := dy`, `y := dx`, no bias |
//! | backward_weight             | `conv_backward_weight` | `x := dy_t`, `dy := x_t`      |
//! | backward_bias               | [`conv::backward_bias`] over `dy`'s channels           |

use super::conv::{self, Conv, ConvKernel, Geometry, Padding, check_bias};
use super::{conv_fast, expect_shape};
use crate::error::{Error, Result, shape_err};
use crate::gpu::{Gpu, Tensor};

/// A transposed convolution, described by its equivalent forward conv.
///
/// Padding: [`Padding::Same`] is TensorFlow's `conv*d_transpose` with `SAME` (output
/// `in * stride`, padded as a SAME forward conv of that output would be);
/// [`Padding::Explicit`] is the padding of the equivalent forward conv (PyTorch's `padding`,
/// split per side). The output size must be one the equivalent forward conv maps back onto
/// the input size; [`ConvTranspose::output_shape`] gives the smallest such size, and a
/// caller may pass a larger `y` (PyTorch's `output_padding`) as long as that holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConvTranspose {
    /// The forward conv this op is the transpose of.
    pub conv: Conv,
}

impl ConvTranspose {
    /// A 3D transposed conv: kernel, stride, padding per axis (depth, height, width).
    pub fn conv3d(kernel: [usize; 3], stride: [usize; 3], padding: Padding) -> ConvTranspose {
        ConvTranspose { conv: Conv::conv3d(kernel, stride, padding) }
    }

    /// A 2D transposed conv: kernel `[kh, kw]`, stride `[sh, sw]`.
    pub fn conv2d(kernel: [usize; 2], stride: [usize; 2], padding: Padding) -> ConvTranspose {
        ConvTranspose { conv: Conv::conv2d(kernel, stride, padding) }
    }

    /// The default output shape for input `x_shape` (`NCDHW` / `NCHW`) and weights `w_shape`
    /// (`[Cin, Cout, k...]`): `in * stride` for `Same`, `(in - 1) * stride + k - before -
    /// after` for `Explicit`. Errors if the shapes disagree.
    pub fn output_shape(&self, x_shape: &[usize], w_shape: &[usize]) -> Result<Vec<usize>> {
        const OP: &str = "conv_transpose";
        let rank = x_shape.len();
        if (rank != 4 && rank != 5) || w_shape.len() != rank {
            return Err(shape_err(OP, format!("input {x_shape:?} and weights {w_shape:?}: expected rank 4 or 5 both")));
        }
        if w_shape[0] != x_shape[1] {
            return Err(shape_err(
                OP,
                format!("input {x_shape:?} has {} channels but weights {w_shape:?} expect {}", x_shape[1], w_shape[0]),
            ));
        }
        let mut y = vec![x_shape[0], w_shape[1]];
        let first = if rank == 4 { 1 } else { 0 };
        for a in first..3 {
            let (len, k, s) = (x_shape[a + rank - 3], self.conv.kernel[a], self.conv.stride[a]);
            let out = match self.conv.padding {
                Padding::Same => Some(len * s),
                Padding::Explicit { before, after } => {
                    (len.saturating_sub(1) * s + k).checked_sub(before[a] + after[a]).filter(|&o| o > 0)
                }
            };
            let out = out.ok_or_else(|| {
                shape_err(OP, format!("padding {:?} leaves no output for input {x_shape:?}", self.conv.padding))
            })?;
            y.push(out);
        }
        self.geometry(OP, x_shape, w_shape, &y)?;
        Ok(y)
    }

    /// Whether `kernel` runs the tiled kernels for `pass` of this transposed conv with input
    /// `x_shape`, weights `w_shape` and output `y_shape` (see [`Conv::runs_fast`]).
    pub fn runs_fast(
        &self,
        kernel: ConvKernel,
        pass: conv::Pass,
        x_shape: &[usize],
        w_shape: &[usize],
        y_shape: &[usize],
    ) -> Result<bool> {
        let g = self.geometry("conv_transpose", x_shape, w_shape, y_shape)?;
        // The roles swap as in the module table.
        let bound = match pass {
            conv::Pass::Forward => conv::Pass::BackwardInput,
            conv::Pass::BackwardInput => conv::Pass::Forward,
            conv::Pass::BackwardWeight => conv::Pass::BackwardWeight,
        };
        Ok(conv::use_fast(kernel, bound, &g))
    }

    /// Resolves a call: the equivalent forward conv of `y_shape` must give `x_shape`.
    fn geometry(&self, op: &str, x_shape: &[usize], w_shape: &[usize], y_shape: &[usize]) -> Result<Geometry> {
        let g = self.conv.geometry(op, y_shape, w_shape)?;
        if g.y_shape() != x_shape {
            return Err(shape_err(
                op,
                format!(
                    "output {y_shape:?} does not fit input {x_shape:?}: the equivalent forward conv \
                     maps it to {:?}",
                    g.y_shape()
                ),
            ));
        }
        Ok(g)
    }

    /// `y = conv_transpose(x, w) + b` on `kernel` (see [`ConvKernel`]; `Auto` unless
    /// comparing); `b`, when given, is `[Cout]`.
    #[allow(clippy::too_many_arguments)]
    pub fn forward(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Tensor,
        w: &Tensor,
        b: Option<&Tensor>,
        y: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_transpose_forward";
        let g = self.geometry(OP, x.shape(), w.shape(), y.shape())?;
        check_bias(OP, b, g.ci)?;
        conv::dispatch_backward_input(kernel, gpu, pass, &g, x, w, b, y)
    }

    /// `y = prelu(conv_transpose(x, w) + b, alpha)` (`alpha` `[Cout]`) in the transposed
    /// conv's own dispatches, as [`crate::ops::conv::Conv::forward_prelu`] does for a conv;
    /// only where [`ConvTranspose::fuses_prelu`] holds, elsewhere an error.
    #[allow(clippy::too_many_arguments)]
    pub fn forward_prelu(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Tensor,
        w: &Tensor,
        b: Option<&Tensor>,
        alpha: &Tensor,
        y: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_transpose_forward_prelu";
        let g = self.geometry(OP, x.shape(), w.shape(), y.shape())?;
        check_bias(OP, b, g.ci)?;
        expect_shape(OP, "alpha", alpha, &[g.ci])?;
        if !fuses_prelu(kernel, gpu, &g) {
            return Err(Error::Invalid(format!("{OP}: this transposed conv on {kernel:?} does not run the texture kernels, which alone apply a PReLU (see ConvTranspose::fuses_prelu)")));
        }
        conv_fast::backward_input_act(gpu, pass, &g, x, w, b, Some(alpha), y, conv::operands(gpu, kernel))
    }

    /// Whether [`ConvTranspose::forward_prelu`] runs this transposed conv on `kernel` and
    /// `gpu` (input `x_shape`, weights `w_shape`, output `y_shape`).
    pub fn fuses_prelu(&self, kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize], y_shape: &[usize]) -> Result<bool> {
        Ok(fuses_prelu(kernel, gpu, &self.geometry("conv_transpose_forward_prelu", x_shape, w_shape, y_shape)?))
    }

    /// `dx = dL/dx` from `dy = dL/dy` and the weights on `kernel`: the equivalent forward
    /// conv of `dy`.
    pub fn backward_input(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        dy: &Tensor,
        w: &Tensor,
        dx: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_transpose_backward_input";
        let g = self.geometry(OP, dx.shape(), w.shape(), dy.shape())?;
        conv::dispatch_forward(kernel, gpu, pass, &g, dy, w, None, dx)
    }

    /// `dw = dL/dw` from the forward input `x` and `dy` on `kernel`; `dw` is
    /// `[Cin, Cout, k...]`.
    pub fn backward_weight(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Tensor,
        dy: &Tensor,
        dw: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_transpose_backward_weight";
        let g = self.geometry(OP, x.shape(), dw.shape(), dy.shape())?;
        conv::dispatch_backward_weight(kernel, gpu, pass, &g, dy, x, dw)
    }

    /// `db = dL/db`, summing `dy` over batch and space (same as [`conv::backward_bias`]).
    pub fn backward_bias(&self, gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, db: &Tensor) -> Result<()> {
        conv::backward_bias(gpu, pass, dy, db)
    }
}

/// Whether the transposed conv of equivalent forward conv `g` on `kernel` runs kernels that
/// apply a PReLU (see [`ConvTranspose::fuses_prelu`]).
fn fuses_prelu(kernel: ConvKernel, gpu: &Gpu, g: &Geometry) -> bool {
    conv::use_fast(kernel, conv::Pass::BackwardInput, g) && conv_fast::transposed_fuses_prelu(gpu, g, conv::operands(gpu, kernel))
}
