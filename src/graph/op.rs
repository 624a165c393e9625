//! The ops a graph can hold, each with its shape rule, its forward, and its backward rule
//! (which saved values it reads and which gradients it writes). Inputs are positional:
//!
//! | op | inputs | saved for backward |
//! |---|---|---|
//! | `Sigmoid` | x | output |
//! | `Elu` | x | x |
//! | `Prelu` | x, alpha[C] | x, alpha |
//! | `Dropout` | x | nothing (the mask is a function of the seed) |
//! | `Add` | a, b | nothing |
//! | `Projection` | x[N,C,D,H,W], w[O,C*D,1,1], b[O] | x, w |
//! | `Conv(c)` | x, w[O,I,k..], b[O] | x, w |
//! | `ConvTranspose(c)` | x, w[I,O,k..], b[O] | x, w |
//! | `Resample(out)` | x[N,C,D,H,W], pose[N,6] | x, pose |
//! | `Phong` | normal[N,3,H,W], albedo[N,C,H,W], mask[N,1,H,W], light[N,6] | all four |
//! | `Loss` | prediction, target (no gradient) | both |
//! | `Concat` | a[N,C1,S..], b[N,C2,S..] | nothing |
//! | `ConcatAxis0(sizes)` | one or more [Ok,R..] | nothing |
//! | `Narrow(start, len)` | x[N,C,S..] | nothing |
//! | `Reshape(shape)` | x (same size as `shape`) | nothing |
//! | `Mul` | x[N,C,S..], m[N,1|C,S..] | both |
//! | `Composite` | x[N,C,D,H,W] (channel 0 occupancy) | x |
//! | `Expand(spatial)` | x[N,C,1..] | nothing |

use crate::error::{Result, shape_err};
use crate::gpu::{Gpu, Tensor};
use crate::ops::{self, conv::Conv, conv::ConvKernel, conv_transpose::ConvTranspose, dropout::Dropout, loss::Loss, phong::Phong};

/// Graphs run the conv kernels the device is calibrated for.
const AUTO: ConvKernel = ConvKernel::Auto;

/// An op in a graph, with its configuration.
#[derive(Clone, Debug)]
pub enum Op {
    /// Logistic sigmoid.
    Sigmoid,
    /// ELU with the given alpha.
    Elu(f32),
    /// PReLU with per-channel slopes (second input).
    Prelu,
    /// Inverted dropout with this keep probability while training; identity in evaluation.
    Dropout(f32),
    /// Elementwise sum of two equal-shaped values (residual connections).
    Add,
    /// Projection unit: fold depth into channels, 1x1 conv with bias.
    Projection,
    /// 3D or 2D convolution with bias.
    Conv(Conv),
    /// 3D or 2D transposed convolution with bias (output size from its padding rule).
    ConvTranspose(ConvTranspose),
    /// Rigid-body resampling of a grid into a camera-aligned grid of spatial size `[Do, Ho, Wo]`.
    Resample([usize; 3]),
    /// Phong shading of predicted normal/albedo/mask maps under an input light.
    Phong(Phong),
    /// A scalar loss `[1]` of a prediction against a target.
    Loss(Loss),
    /// Concatenation of two values along axis 1 (channels).
    Concat,
    /// Concatenation of one or more values along axis 0, of the given sizes along it (inputs
    /// are not kept for backward, which needs them): sibling layers' weights `[O, ...]` and
    /// biases `[O]`, so one conv computes all their outputs (the Phong heads).
    ConcatAxis0(Vec<usize>),
    /// Channels `start .. start + len` of `[N, C, ...]` (one layer's share of a conv that
    /// computes several).
    Narrow(usize, usize),
    /// The same values in another shape of the same size (row-major order kept): from a
    /// conv's `[N, C, D, H, W]` to a fully-connected layer's `[N, K, 1, 1]` and back.
    Reshape(Vec<usize>),
    /// Elementwise product, the second input broadcast over channels when it has one
    /// (a texture times the occupancy it paints).
    Mul,
    /// Front-to-back compositing along depth, `[N, C, D, H, W]` to `[N, C, H, W]`: what each
    /// pixel sees through its column (channel 0 the occupancy; `ops::composite`).
    Composite,
    /// `[N, C, 1...]` repeated over the given spatial shape (`[N, C, S...]`): a per-item
    /// value painted over a whole grid.
    Expand(Vec<usize>),
}

/// What a node's forward or backward gets to work with.
pub(crate) struct Ctx<'a, 'p> {
    pub gpu: &'a Gpu,
    pub pass: &'a mut wgpu::ComputePass<'p>,
    /// Dropout seed for this node and step; 0 when not training.
    pub seed: u32,
    pub training: bool,
}

impl Op {
    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Op::Sigmoid => "sigmoid",
            Op::Elu(_) => "elu",
            Op::Prelu => "prelu",
            Op::Dropout(_) => "dropout",
            Op::Add => "add",
            Op::Projection => "projection",
            Op::Conv(_) => "conv",
            Op::ConvTranspose(_) => "conv_transpose",
            Op::Resample(_) => "resample",
            Op::Phong(_) => "phong",
            Op::Loss(Loss::Mse) => "mse",
            Op::Loss(Loss::Bce) => "bce",
            Op::Concat => "concat",
            Op::ConcatAxis0(_) => "concat_axis0",
            Op::Narrow(..) => "narrow",
            Op::Reshape(_) => "reshape",
            Op::Mul => "mul",
            Op::Composite => "composite",
            Op::Expand(_) => "expand",
        }
    }

    /// How many inputs it takes (`usize::MAX`: one or more).
    fn arity(&self) -> usize {
        match self {
            Op::ConcatAxis0(_) => usize::MAX,
            Op::Sigmoid | Op::Elu(_) | Op::Dropout(_) | Op::Reshape(_) | Op::Composite | Op::Expand(_) | Op::Narrow(..) => 1,
            Op::Prelu | Op::Add | Op::Loss(_) | Op::Resample(_) | Op::Concat | Op::Mul => 2,
            Op::Projection | Op::Conv(_) | Op::ConvTranspose(_) => 3,
            Op::Phong(_) => 4,
        }
    }

    /// The output shape for these input shapes, or why they do not fit.
    pub(crate) fn infer(&self, s: &[&[usize]]) -> Result<Vec<usize>> {
        match self.arity() {
            usize::MAX if s.is_empty() => return Err(shape_err(self.name(), "takes one or more inputs, got none")),
            usize::MAX => {}
            a if s.len() != a => return Err(shape_err(self.name(), format!("takes {a} inputs, got {}", s.len()))),
            _ => {}
        }
        match self {
            Op::Sigmoid | Op::Elu(_) | Op::Dropout(_) => Ok(s[0].to_vec()),
            Op::Prelu => {
                if s[0].len() < 2 || s[1] != [s[0][1]] {
                    return Err(shape_err("prelu", format!("alpha must be [C] = [{}]", s[0].get(1).unwrap_or(&0))));
                }
                Ok(s[0].to_vec())
            }
            Op::Add => {
                if s[0] != s[1] {
                    return Err(shape_err("add", "both inputs must have one shape"));
                }
                Ok(s[0].to_vec())
            }
            Op::Projection => {
                let d = ops::projection::ProjectionDims::new(s[0], s[1])?;
                if s[2] != [d.o] {
                    return Err(shape_err("projection", format!("bias must be [{}]", d.o)));
                }
                Ok(d.output_shape())
            }
            Op::Conv(c) => with_bias(c.output_shape(s[0], s[1])?, s[2]),
            Op::ConvTranspose(c) => with_bias(c.output_shape(s[0], s[1])?, s[2]),
            Op::Resample([d, h, w]) => {
                if s[0].len() != 5 || s[1] != [s[0][0], 6] {
                    return Err(shape_err("resample", "needs a grid [N,C,D,H,W] and a pose [N,6]"));
                }
                Ok(vec![s[0][0], s[0][1], *d, *h, *w])
            }
            Op::Phong(_) => {
                let (n, h, w) = (s[0][0], s[0].get(2).copied().unwrap_or(0), s[0].get(3).copied().unwrap_or(0));
                let c = s[1].get(1).copied().unwrap_or(0);
                let ok = s[0] == [n, 3, h, w] && (c == 1 || c == 3) && s[1] == [n, c, h, w] && s[2] == [n, 1, h, w] && s[3] == [n, 6];
                if !ok {
                    return Err(shape_err("phong", "needs normal [N,3,H,W], albedo [N,1|3,H,W], mask [N,1,H,W], light [N,6]"));
                }
                Ok(vec![n, 3, h, w])
            }
            Op::Loss(_) => {
                if s[0] != s[1] {
                    return Err(shape_err(self.name(), "prediction and target must have one shape"));
                }
                Ok(vec![1])
            }
            Op::Concat => ops::concat::output_shape(s),
            Op::ConcatAxis0(sizes) => {
                if s.iter().map(|p| p.first().copied().unwrap_or(0)).ne(sizes.iter().copied()) {
                    return Err(shape_err("concat_axis0", format!("parts of {sizes:?} along axis 0 expected")));
                }
                ops::concat::output_shape_axis0(s)
            }
            Op::Narrow(start, len) => ops::concat::narrow_shape(s[0], *start, *len),
            Op::Mul => ops::mul::output_shape(s[0], s[1]),
            Op::Composite => ops::composite::output_shape(s[0]),
            Op::Expand(to) => ops::expand::output_shape(s[0], to),
            Op::Reshape(to) => {
                if to.iter().product::<usize>() != s[0].iter().product::<usize>() || to.contains(&0) {
                    return Err(shape_err("reshape", format!("{:?} cannot become {to:?}: the sizes differ", s[0])));
                }
                Ok(to.clone())
            }
        }
    }

    /// Multiply-adds of the forward pass (convolutions and the projection; elementwise
    /// ops are negligible next to them), for GFLOP/s figures.
    pub(crate) fn macs(&self, ins: &[&[usize]], out: &[usize]) -> u64 {
        let n = |s: &[usize]| s.iter().product::<usize>() as u64;
        match self {
            // y elements x (w elements / output channels): every output sums cin x taps.
            Op::Conv(_) | Op::Projection => n(out) * n(&ins[1][1..]),
            // Every input scatters into cout x taps outputs.
            Op::ConvTranspose(_) => n(ins[0]) * n(&ins[1][1..]),
            _ => 0,
        }
    }

    /// Whether input `j` can receive a gradient (a loss's target cannot).
    pub(crate) fn differentiable(&self, j: usize) -> bool {
        !matches!(self, Op::Loss(_)) || j == 0
    }

    /// Which inputs (by position) and whether the output must be kept for backward.
    pub(crate) fn saves(&self) -> (&'static [usize], bool) {
        match self {
            Op::Sigmoid => (&[], true),
            Op::Elu(_) | Op::Composite => (&[0], false),
            Op::Prelu => (&[0, 1], false),
            Op::Dropout(_) | Op::Add | Op::Concat | Op::ConcatAxis0(_) | Op::Narrow(..) | Op::Reshape(_) | Op::Expand(_) => (&[], false),
            Op::Projection => (&[0, 1], false),
            Op::Resample(_) | Op::Conv(_) | Op::ConvTranspose(_) => (&[0, 1], false),
            Op::Phong(_) => (&[0, 1, 2, 3], false),
            Op::Loss(_) | Op::Mul => (&[0, 1], false),
        }
    }

    fn dropout(&self, training: bool) -> Dropout {
        match self {
            Op::Dropout(k) if training => Dropout { keep_prob: *k },
            _ => Dropout { keep_prob: 1.0 },
        }
    }

    /// Whether this node's forward, on inputs of `shapes`, can apply a PReLU that follows it
    /// (slopes `[Cout]`) in its own dispatches: a conv, transposed conv or projection whose
    /// forward runs the texture kernels (`Conv::fuses_prelu`, `ConvTranspose::fuses_prelu`,
    /// `projection::fuses_prelu`).
    pub(crate) fn fuses_prelu(&self, gpu: &Gpu, shapes: &[&[usize]]) -> bool {
        match self {
            Op::Conv(cv) => cv.fuses_prelu(AUTO, gpu, shapes[0], shapes[1]).unwrap_or(false),
            Op::Projection => ops::projection::fuses_prelu(AUTO, gpu, shapes[0], shapes[1]).unwrap_or(false),
            Op::ConvTranspose(cv) => cv.output_shape(shapes[0], shapes[1]).and_then(|y| cv.fuses_prelu(AUTO, gpu, shapes[0], shapes[1], &y)).unwrap_or(false),
            _ => false,
        }
    }

    /// Records the forward of this op followed by a PReLU of slopes `alpha`, writing the
    /// PReLU's output `y`; only where [`Op::fuses_prelu`] holds.
    pub(crate) fn forward_prelu(&self, c: &mut Ctx, x: &[&Tensor], alpha: &Tensor, y: &Tensor) -> Result<()> {
        match self {
            Op::Conv(cv) => cv.forward_prelu(AUTO, c.gpu, c.pass, x[0], x[1], Some(x[2]), alpha, y),
            Op::Projection => ops::projection::forward_prelu(AUTO, c.gpu, c.pass, x[0], x[1], x[2], alpha, y),
            Op::ConvTranspose(cv) => cv.forward_prelu(AUTO, c.gpu, c.pass, x[0], x[1], Some(x[2]), alpha, y),
            _ => Err(crate::error::Error::Invalid(format!("internal: {} does not fuse a PReLU", self.name()))),
        }
    }

    /// Records the forward of this op.
    pub(crate) fn forward(&self, c: &mut Ctx, x: &[&Tensor], y: &Tensor) -> Result<()> {
        let (g, p) = (c.gpu, &mut *c.pass);
        match self {
            Op::Sigmoid => ops::sigmoid::forward(g, p, x[0], y),
            Op::Elu(a) => ops::elu::forward(g, p, *a, x[0], y),
            Op::Prelu => ops::prelu::forward(g, p, x[0], x[1], y),
            Op::Dropout(_) => self.dropout(c.training).forward(g, p, c.seed, x[0], y),
            Op::Add => ops::add::forward(g, p, x[0], x[1], y),
            Op::Projection => ops::projection::forward(AUTO, g, p, x[0], x[1], x[2], y),
            Op::Conv(cv) => cv.forward(AUTO, g, p, x[0], x[1], Some(x[2]), y),
            Op::ConvTranspose(cv) => cv.forward(AUTO, g, p, x[0], x[1], Some(x[2]), y),
            Op::Resample(_) => ops::resample::forward(g, p, x[0], x[1], y),
            Op::Phong(ph) => ph.forward(g, p, &phong_inputs(x), y),
            Op::Loss(l) => l.forward(g, p, x[0], x[1], y),
            Op::Concat => ops::concat::forward(g, p, x, y),
            Op::ConcatAxis0(_) => ops::concat::forward_axis0(g, p, x, y),
            Op::Narrow(start, _) => ops::concat::narrow(g, p, x[0], *start, y),
            Op::Reshape(_) => ops::add::reshape(g, p, x[0], y),
            Op::Mul => ops::mul::forward(g, p, x[0], x[1], y),
            Op::Composite => ops::composite::forward(g, p, x[0], y),
            Op::Expand(_) => ops::expand::forward(g, p, x[0], y),
        }
    }

    /// Records the backward of this op: writes the gradient of every input whose slot in
    /// `dx` is `Some`. `x` holds the inputs (those not saved are absent only if unused).
    pub(crate) fn backward(
        &self,
        c: &mut Ctx,
        x: &[&Tensor],
        y: &Tensor,
        dy: &Tensor,
        dx: &[Option<&Tensor>],
    ) -> Result<()> {
        let (g, p) = (c.gpu, &mut *c.pass);
        match self {
            Op::Sigmoid => some(dx[0], |d| ops::sigmoid::backward(g, p, y, dy, d)),
            Op::Elu(a) => some(dx[0], |d| ops::elu::backward(g, p, *a, x[0], dy, d)),
            Op::Prelu => {
                // The kernel writes both gradients; scratch takes the one nobody asked for.
                let d = or_scratch(g, x, dx)?;
                ops::prelu::backward(g, p, x[0], x[1], dy, &d[0], &d[1])
            }
            Op::Dropout(_) => some(dx[0], |d| self.dropout(c.training).backward(g, p, c.seed, dy, d)),
            Op::Add => unreachable!("the executor passes add's gradient through without a kernel"),
            Op::Projection => {
                some(dx[0], |d| ops::projection::backward_input(AUTO, g, p, dy, x[1], d))?;
                some(dx[1], |d| ops::projection::backward_weight(AUTO, g, p, x[0], dy, d))?;
                some(dx[2], |d| ops::projection::backward_bias(g, p, dy, d))
            }
            Op::Conv(cv) => {
                cv.backward(AUTO, g, p, x[0], x[1], dy, dx[0], dx[1])?;
                some(dx[2], |d| ops::conv::backward_bias(g, p, dy, d))
            }
            Op::ConvTranspose(cv) => {
                some(dx[0], |d| cv.backward_input(AUTO, g, p, dy, x[1], d))?;
                some(dx[1], |d| cv.backward_weight(AUTO, g, p, x[0], dy, d))?;
                some(dx[2], |d| cv.backward_bias(g, p, dy, d))
            }
            Op::Resample(_) => {
                some(dx[0], |d| ops::resample::backward_input(g, p, x[1], dy, d))?;
                some(dx[1], |d| ops::resample::backward_pose(g, p, x[0], x[1], dy, d))
            }
            Op::Phong(ph) => {
                // The maps kernel writes all three map gradients; the light's is a kernel and a
                // reduction of its own, run only when asked for (inverse rendering, not training).
                let d = or_scratch(g, &x[..3], &dx[..3])?;
                ph.backward_maps(g, p, &phong_inputs(x), dy, [&d[0], &d[1], &d[2]])?;
                some(dx[3], |d| ph.backward_light(g, p, &phong_inputs(x), dy, d))
            }
            Op::Loss(l) => some(dx[0], |d| l.backward(g, p, x[0], x[1], dy, d)),
            Op::Concat => {
                // Inputs are not saved (`x` may hold stand-ins): the parts' shapes follow from
                // dy and whichever gradient is asked for.
                let mut shapes = [dy.shape().to_vec(), dy.shape().to_vec()];
                match (dx[0], dx[1]) {
                    (Some(a), _) => shapes[1][1] -= a.shape()[1],
                    (None, Some(b)) => shapes[0][1] -= b.shape()[1],
                    (None, None) => return Ok(()),
                }
                if let Some(a) = dx[0] {
                    shapes[0][1] = a.shape()[1];
                } else if let Some(b) = dx[1] {
                    shapes[1][1] = b.shape()[1];
                }
                ops::concat::backward(g, p, dy, &[&shapes[0], &shapes[1]], dx)
            }
            Op::ConcatAxis0(sizes) => {
                // Inputs are not saved (`x` may hold stand-ins): the op carries the parts' sizes.
                let shapes: Vec<Vec<usize>> = sizes.iter().map(|&o| [&[o][..], &dy.shape()[1..]].concat()).collect();
                let refs: Vec<&[usize]> = shapes.iter().map(Vec::as_slice).collect();
                ops::concat::backward_axis0(g, p, dy, &refs, dx)
            }
            Op::Narrow(start, _) => some(dx[0], |d| ops::concat::narrow_backward(g, p, dy, *start, d)),
            Op::Reshape(_) => some(dx[0], |d| ops::add::reshape(g, p, dy, d)),
            Op::Mul => {
                some(dx[0], |d| ops::mul::backward_x(g, p, dy, x[1], d))?;
                some(dx[1], |d| ops::mul::backward_mask(g, p, x[0], dy, d))
            }
            Op::Composite => some(dx[0], |d| ops::composite::backward(g, p, x[0], dy, d)),
            Op::Expand(_) => some(dx[0], |d| ops::expand::backward(g, p, dy, d)),
        }
    }
}

/// A conv's output shape once its bias `[O]` is checked against it.
fn with_bias(out: Vec<usize>, b: &[usize]) -> Result<Vec<usize>> {
    if b != [out[1]] {
        return Err(shape_err("conv", format!("bias must be [{}]", out[1])));
    }
    Ok(out)
}

fn phong_inputs<'a>(x: &[&'a Tensor]) -> ops::phong::Inputs<'a> {
    ops::phong::Inputs { normal: x[0], albedo: x[1], mask: x[2], light: x[3] }
}

/// The requested gradient tensors, with scratch standing in for unrequested ones, for
/// kernels that always write every gradient.
fn or_scratch(g: &Gpu, x: &[&Tensor], dx: &[Option<&Tensor>]) -> Result<Vec<Tensor>> {
    dx.iter().zip(x).map(|(d, x)| d.map_or_else(|| g.scratch(x.shape()), |t| Ok(t.clone()))).collect()
}

fn some(t: Option<&Tensor>, f: impl FnOnce(&Tensor) -> Result<()>) -> Result<()> {
    t.map_or(Ok(()), f)
}
