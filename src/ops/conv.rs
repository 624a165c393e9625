//! 3D and 2D convolution (binds `shaders/conv.wgsl`): any kernel size, per-axis stride,
//! asymmetric padding, optional bias. A 2D conv is the 3D kernel with depth 1 (NCHW seen as
//! NC1HW, OIHW as OI1HW), so one shader serves both. `conv.wgsl` holds the reference kernels
//! (one invocation per output value, deterministic), the tests' oracle; the tiled kernels of
//! `shaders/conv_fast.wgsl` (module `conv_fast`) run behind the same methods where
//! [`ConvKernel::Auto`] picks them. Both are deterministic.

use super::{conv_fast, conv_nchw, expect_rank, expect_shape};
use crate::error::{Error, Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("conv");

/// Which kernels a conv, transposed-conv or projection call runs. Pass `Auto` (the
/// `Default`, what the graph executor uses): the tiled kernels, reading textures or buffers
/// by a per-device calibration (cached on disk; `RENDERNET_CONV_OPERANDS=buffers|textures`
/// overrides it), and the narrow heads' forward unpacked where a second calibration says so
/// (`RENDERNET_CONV_HEADS=nchw|packed` overrides it). The others force a choice so tests and
/// `rendernet bench` can compare them on the same call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ConvKernel {
    /// The tiled kernels, textures or buffers by the device's calibration; the narrow 3x3
    /// heads' forward unpacked (as `Nchw`) where that measured faster and no weight gradient
    /// will reuse its packing (runs without one: render, eval, invert).
    #[default]
    Auto,
    /// The reference kernels: one invocation per output value.
    Reference,
    /// The tiled kernels reading storage buffers (`rendernet bench --kernel fast`).
    Buffers,
    /// The tiled kernels reading textures, sharing loads across a subgroup. Falls back to
    /// the buffer kernels where the device lacks subgroups of 8 or the textures would exceed
    /// its limits.
    Texture,
    /// As `Texture`, but the forward of the narrow 3x3 heads (2D, stride 1, padding 1, at
    /// most 8 output channels and 64 input channels, width a multiple of 4) reads its input
    /// unpacked (`shaders/conv_nchw.wgsl`), and so does a transposed conv's input gradient
    /// of that shape (a forward conv).
    Nchw,
}

/// How a conv pads its input, per spatial axis (depth, height, width).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Padding {
    /// TensorFlow's `SAME`: `out = ceil(in / stride)`, `pad_total = max((out - 1) * stride +
    /// k - in, 0)`, `before = pad_total / 2`, `after` the rest (one more than `before` for
    /// even kernels at stride 1: the original RenderNet relies on this asymmetry).
    Same,
    /// Zero padding of `before` and `after` values on each axis.
    Explicit {
        /// Padding before each axis (depth, height, width).
        before: [usize; 3],
        /// Padding after each axis.
        after: [usize; 3],
    },
}

impl Padding {
    /// Explicit 2D padding `[top, left]`, `[bottom, right]` (no depth padding).
    pub fn explicit_2d(before: [usize; 2], after: [usize; 2]) -> Padding {
        Padding::Explicit { before: [0, before[0], before[1]], after: [0, after[0], after[1]] }
    }

    /// `(before, after)` on one axis for an input of length `len`.
    fn resolve(&self, axis: usize, len: usize, k: usize, s: usize) -> (usize, usize) {
        match *self {
            Padding::Same => {
                let out = len.div_ceil(s);
                let total = ((out - 1) * s + k).saturating_sub(len);
                (total / 2, total - total / 2)
            }
            Padding::Explicit { before, after } => (before[axis], after[axis]),
        }
    }
}

/// A convolution's hyper-parameters, for 3D (`NCDHW` input, `OIDHW` weights) or 2D (`NCHW`,
/// `OIHW`, stored with kernel depth 1). Input and weight shapes come with each call, so one
/// `Conv` serves any batch size and resolution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conv {
    /// Kernel size (depth, height, width).
    pub kernel: [usize; 3],
    /// Stride (depth, height, width).
    pub stride: [usize; 3],
    /// Padding rule.
    pub padding: Padding,
}

/// Everything the kernels need about one conv call, resolved from the shapes: the "input"
/// and "output" are those of the forward conv (for a transposed conv, its output and input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Geometry {
    /// Batch size.
    pub n: usize,
    /// Forward input channels.
    pub ci: usize,
    /// Forward output channels.
    pub co: usize,
    /// Forward input spatial size (depth 1 for 2D).
    pub input: [usize; 3],
    /// Forward output spatial size.
    pub output: [usize; 3],
    /// Kernel size.
    pub kernel: [usize; 3],
    /// Stride.
    pub stride: [usize; 3],
    /// Padding before each axis (the padding after is implied by `output`).
    pub pad: [usize; 3],
    /// 5 for 3D, 4 for 2D: how shapes are written back.
    pub rank: usize,
}

impl Geometry {
    /// `[a, b, sp...]`, the depth dropped for 2D: an input, weight or output shape.
    pub(super) fn shape(&self, a: usize, b: usize, sp: [usize; 3]) -> Vec<usize> {
        if self.rank == 4 { vec![a, b, sp[1], sp[2]] } else { vec![a, b, sp[0], sp[1], sp[2]] }
    }
    /// The forward conv's output shape.
    pub fn y_shape(&self) -> Vec<usize> {
        self.shape(self.n, self.co, self.output)
    }
    /// The parameter block with this geometry filled in, everything else zero.
    pub(crate) fn params(&self) -> Params {
        let u = |v: usize| v as u32;
        let [id, ih, iw] = self.input.map(u);
        let [od, oh, ow] = self.output.map(u);
        let [kd, kh, kw] = self.kernel.map(u);
        let [sd, sh, sw] = self.stride.map(u);
        let [pd, ph, pw] = self.pad.map(u);
        Params {
            n: u(self.n),
            ci: u(self.ci),
            co: u(self.co),
            id, ih, iw, od, oh, ow, kd, kh, kw, sd, sh, sw, pd, ph, pw,
            ..Default::default()
        }
    }
}

/// The parameter block of every conv kernel: mirrors `Params` in `shaders/conv_fast.wgsl`,
/// whose first 20 fields `shaders/conv.wgsl` (the reference kernels) declares as its own.
/// The shaders document the fields.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Params {
    pub n: u32,
    pub ci: u32,
    pub co: u32,
    pub id: u32,
    pub ih: u32,
    pub iw: u32,
    pub od: u32,
    pub oh: u32,
    pub ow: u32,
    pub kd: u32,
    pub kh: u32,
    pub kw: u32,
    pub sd: u32,
    pub sh: u32,
    pub sw: u32,
    pub pd: u32,
    pub ph: u32,
    pub pw: u32,
    pub has_bias: u32,
    pub total: u32,
    // The tiled kernels only, from here on.
    pub cpad: u32,
    pub co16: u32,
    pub flip: u32,
    pub nchunks: u32,
    pub chunk: u32,
    pub fold: u32,
    pub ycs: u32,
    pub ysd: u32,
    pub ysh: u32,
    pub ysw: u32,
    pub yoff: u32,
    /// `conv_fast_pack_weights_tex_window`: where each window's first vec4 lies in its binding.
    pub wat: [u32; 4],
}

impl Conv {
    /// A 3D conv: kernel and stride per axis (depth, height, width).
    pub fn conv3d(kernel: [usize; 3], stride: [usize; 3], padding: Padding) -> Conv {
        Conv { kernel, stride, padding }
    }

    /// A 2D conv: kernel `[kh, kw]`, stride `[sh, sw]`; use [`Padding::explicit_2d`] for
    /// explicit padding.
    pub fn conv2d([kh, kw]: [usize; 2], [sh, sw]: [usize; 2], padding: Padding) -> Conv {
        Conv { kernel: [1, kh, kw], stride: [1, sh, sw], padding }
    }

    /// The output shape for input `x_shape` (`NCDHW`, or `NCHW` for 2D) and weights
    /// `w_shape` (`OIDHW` / `OIHW`). Errors if ranks, channels or kernel sizes disagree, or
    /// the kernel does not fit the padded input.
    pub fn output_shape(&self, x_shape: &[usize], w_shape: &[usize]) -> Result<Vec<usize>> {
        Ok(self.geometry("conv", x_shape, w_shape)?.y_shape())
    }

    /// Whether `kernel` runs the tiled kernels for `pass` of this conv on input `x_shape`
    /// and weights `w_shape` (for benchmarks and tests; see `use_fast` for the rule).
    pub fn runs_fast(&self, kernel: ConvKernel, pass: Pass, x_shape: &[usize], w_shape: &[usize]) -> Result<bool> {
        Ok(use_fast(kernel, pass, &self.geometry("conv", x_shape, w_shape)?))
    }

    /// Whether `kernel` runs this conv's forward on input `x_shape` and weights `w_shape`
    /// with the input unpacked (`ConvKernel::Nchw`; `Auto` where it measured faster), for
    /// benchmarks and tests.
    pub fn forward_reads_unpacked(&self, kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize]) -> Result<bool> {
        self.forward_unpacked(kernel, gpu, x_shape, w_shape, false)
    }

    /// [`Conv::forward_reads_unpacked`] where the input is copied into the direct kernels'
    /// stage texture, which the kernel then reads (a CPU adapter, rows of whole staging rows,
    /// a pass that can split: README "The heads on x in place"), for tests.
    pub fn forward_reads_staged_unpacked(&self, kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize]) -> Result<bool> {
        self.forward_unpacked(kernel, gpu, x_shape, w_shape, true)
    }

    fn forward_unpacked(&self, kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize], staged: bool) -> Result<bool> {
        let g = self.geometry("conv", x_shape, w_shape)?;
        Ok(use_fast(kernel, Pass::Forward, &g) && uses_nchw(kernel, gpu, &g, staged))
    }

    /// Resolves the shapes of a call, checking everything the kernels rely on.
    pub(crate) fn geometry(&self, op: &str, x_shape: &[usize], w_shape: &[usize]) -> Result<Geometry> {
        let rank = x_shape.len();
        if rank != 4 && rank != 5 {
            return Err(shape_err(op, format!("input has shape {x_shape:?}, expected NCDHW or NCHW")));
        }
        if w_shape.len() != rank {
            return Err(shape_err(op, format!("weights {w_shape:?} and input {x_shape:?} differ in rank")));
        }
        if x_shape.contains(&0) || w_shape.contains(&0) || self.stride.contains(&0) || self.kernel.contains(&0) {
            return Err(shape_err(op, format!("zero size in input {x_shape:?}, weights {w_shape:?} or {self:?}")));
        }
        let lift = |s: &[usize]| if rank == 4 { [1, s[2], s[3]] } else { [s[2], s[3], s[4]] };
        let (input, wk) = (lift(x_shape), lift(w_shape));
        if rank == 4 && (self.kernel[0] != 1 || self.stride[0] != 1) {
            return Err(shape_err(op, format!("a 2D input {x_shape:?} needs kernel and stride depth 1, got {self:?}")));
        }
        if wk != self.kernel {
            return Err(shape_err(op, format!("weights {w_shape:?} do not have kernel size {:?}", self.kernel)));
        }
        if w_shape[1] != x_shape[1] {
            return Err(shape_err(
                op,
                format!("input {x_shape:?} has {} channels but weights {w_shape:?} expect {}", x_shape[1], w_shape[1]),
            ));
        }
        let (mut output, mut pad) = ([0; 3], [0; 3]);
        for a in 0..3 {
            let (before, after) = self.padding.resolve(a, input[a], self.kernel[a], self.stride[a]);
            let padded = input[a] + before + after;
            if padded < self.kernel[a] {
                return Err(shape_err(
                    op,
                    format!("kernel {:?} is larger than the padded input {x_shape:?} on axis {a}", self.kernel),
                ));
            }
            output[a] = (padded - self.kernel[a]) / self.stride[a] + 1;
            pad[a] = before;
        }
        if rank == 4 && output[0] != 1 {
            return Err(shape_err(op, format!("depth padding on a 2D input {x_shape:?}: {:?}", self.padding)));
        }
        let (n, ci, co) = (x_shape[0], x_shape[1], w_shape[0]);
        Ok(Geometry { n, ci, co, input, output, kernel: self.kernel, stride: self.stride, pad, rank })
    }

    /// `y = conv(x, w) + b` on `kernel` (see [`ConvKernel`]; `Auto` unless comparing).
    /// `y` must have [`Conv::output_shape`]; `b`, when given, `[Cout]`.
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
        const OP: &str = "conv_forward";
        let g = self.geometry(OP, x.shape(), w.shape())?;
        expect_shape(OP, "y", y, &g.y_shape())?;
        check_bias(OP, b, g.co)?;
        dispatch_forward(kernel, gpu, pass, &g, x, w, b, y)
    }

    /// `y = prelu(conv(x, w) + b, alpha)`, one slope per output channel (`alpha` `[Cout]`),
    /// in the conv's own dispatch: the conv's output never goes through memory (what a
    /// forward-only graph run does with a conv followed by a PReLU). Only where
    /// [`Conv::fuses_prelu`] holds: elsewhere an error.
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
        const OP: &str = "conv_forward_prelu";
        let g = self.geometry(OP, x.shape(), w.shape())?;
        expect_shape(OP, "y", y, &g.y_shape())?;
        expect_shape(OP, "alpha", alpha, &[g.co])?;
        check_bias(OP, b, g.co)?;
        if !fuses_prelu(kernel, gpu, &g) {
            return Err(Error::Invalid(format!("{OP}: this conv's forward on {kernel:?} does not run the texture kernels, which alone apply a PReLU (see Conv::fuses_prelu)")));
        }
        conv_fast::forward_act(gpu, pass, &g, x, w, b, Some(alpha), y, operands(gpu, kernel))
    }

    /// Whether [`Conv::forward_prelu`] runs this conv on `kernel` and `gpu` for input
    /// `x_shape` and weights `w_shape`: where its forward runs the texture kernels (on
    /// lavapipe, every conv of the RenderNet presets).
    pub fn fuses_prelu(&self, kernel: ConvKernel, gpu: &Gpu, x_shape: &[usize], w_shape: &[usize]) -> Result<bool> {
        Ok(fuses_prelu(kernel, gpu, &self.geometry("conv_forward_prelu", x_shape, w_shape)?))
    }

    /// `dx = dL/dx` from `dy = dL/dy` (shape of `y`) and the weights on `kernel`; `dx` has
    /// `x`'s shape.
    pub fn backward_input(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        dy: &Tensor,
        w: &Tensor,
        dx: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_backward_input";
        let g = self.geometry(OP, dx.shape(), w.shape())?;
        expect_shape(OP, "dy", dy, &g.y_shape())?;
        dispatch_backward_input(kernel, gpu, pass, &g, dy, w, None, dx)
    }

    /// `dw = dL/dw` from the forward input `x` and `dy` on `kernel`; `dw` has the weights'
    /// shape.
    pub fn backward_weight(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Tensor,
        dy: &Tensor,
        dw: &Tensor,
    ) -> Result<()> {
        const OP: &str = "conv_backward_weight";
        let g = self.geometry(OP, x.shape(), dw.shape())?;
        expect_shape(OP, "dy", dy, &g.y_shape())?;
        dispatch_backward_weight(kernel, gpu, pass, &g, x, dy, dw)
    }

    /// The gradients `dx` and `dw` wanted (either may be `None`) from `x`, `w` and `dy` on
    /// `kernel`: [`Conv::backward_input`] and [`Conv::backward_weight`] in one call, which
    /// lets the tiled kernels pack `dy` once for both (one dispatch and one pass over dy
    /// fewer); the results are the same.
    #[allow(clippy::too_many_arguments)]
    pub fn backward(
        &self,
        kernel: ConvKernel,
        gpu: &Gpu,
        pass: &mut wgpu::ComputePass<'_>,
        x: &Tensor,
        w: &Tensor,
        dy: &Tensor,
        dx: Option<&Tensor>,
        dw: Option<&Tensor>,
    ) -> Result<()> {
        const OP: &str = "conv_backward";
        let g = self.geometry(OP, x.shape(), w.shape())?;
        expect_shape(OP, "dy", dy, &g.y_shape())?;
        match (dx, dw) {
            (Some(dx), Some(dw)) if use_fast(kernel, Pass::BackwardInput, &g) && use_fast(kernel, Pass::BackwardWeight, &g) => {
                expect_shape(OP, "dx", dx, x.shape())?;
                expect_shape(OP, "dw", dw, w.shape())?;
                conv_fast::backward(gpu, pass, &g, x, dy, w, dx, dw, operands(gpu, kernel))
            }
            _ => {
                if let Some(dx) = dx {
                    self.backward_input(kernel, gpu, pass, dy, w, dx)?;
                }
                dw.map_or(Ok(()), |dw| self.backward_weight(kernel, gpu, pass, x, dy, dw))
            }
        }
    }
}

/// `db[c] = Σ_{n, spatial} dy[n, c, ...]`: the bias gradient of a conv or transposed conv
/// (any `[N, C, spatial...]` tensor); `db` has shape `[C]`.
pub fn backward_bias(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, dy: &Tensor, db: &Tensor) -> Result<()> {
    const OP: &str = "conv_backward_bias";
    let s = dy.shape();
    if s.len() < 3 {
        return Err(shape_err(OP, format!("dy has shape {s:?}, expected [N, C, spatial...]")));
    }
    expect_rank(OP, "db", db, 1)?;
    expect_shape(OP, "db", db, &[s[1]])?;
    super::reduce::sum_outer_inner(gpu, pass, dy, [s[0], s[1], s[2..].iter().product()], 1.0, db)
}

/// Checks an optional bias against `channels`.
pub(crate) fn check_bias(op: &str, b: Option<&Tensor>, channels: usize) -> Result<()> {
    match b {
        Some(b) => expect_shape(op, "bias", b, &[channels]),
        None => Ok(()),
    }
}

fn bias_arg(b: Option<&Tensor>) -> Arg<'_> {
    b.map_or(Arg::Absent, Arg::R)
}

/// The three passes of a conv, each with its own kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// `y = conv(x, w) + b`.
    Forward,
    /// `dx` from `dy` and `w`.
    BackwardInput,
    /// `dw` from `x` and `dy`.
    BackwardWeight,
}

/// Whether `kernel` runs the tiled kernel for `pass` of `g`. `Auto` takes them for every
/// shape (they support all): the packing pads channels with zeros (inputs to a multiple of 4,
/// outputs to 16), and even at 1 or 3 channels the padded tile beats the reference kernels
/// (measured with `rendernet bench`: e.g. the 16->3 3x3 head forward 0.34 -> 1.8 GFLOP/s).
pub(crate) fn use_fast(kernel: ConvKernel, _pass: Pass, _g: &Geometry) -> bool {
    kernel != ConvKernel::Reference
}

/// Settles which operands [`ConvKernel::Auto`] reads on `gpu` (see `conv_fast::calibrated`),
/// whether it runs the heads' forward unpacked (`conv_nchw::wins`) and whether the texture
/// packings copy their texels in (`conv_operands::copy_min_texels`): the first call on a
/// machine times both choices on small convs, later calls read the cached answers. Conv calls
/// do this themselves; call it first to keep the cost out of a timed or counted step.
pub fn calibrate(gpu: &Gpu) {
    conv_fast::calibrated(gpu);
    conv_nchw::wins(gpu, false);
    conv_nchw::wins(gpu, true);
    super::conv_operands::copy_min_texels(gpu);
}

/// Whether the forward of `g` on `kernel` runs kernels that apply a PReLU (see
/// [`Conv::fuses_prelu`]).
pub(crate) fn fuses_prelu(kernel: ConvKernel, gpu: &Gpu, g: &Geometry) -> bool {
    use_fast(kernel, Pass::Forward, g) && conv_fast::fuses_prelu(gpu, g, operands(gpu, kernel))
}

/// The operands the tiled kernels read for `kernel`; `Auto` takes the calibrated choice
/// (see `conv_fast::calibrated`).
pub(crate) fn operands(gpu: &Gpu, kernel: ConvKernel) -> conv_fast::Operands {
    match kernel {
        ConvKernel::Buffers => conv_fast::Operands::Buffers,
        ConvKernel::Texture | ConvKernel::Nchw => conv_fast::Operands::Textures,
        _ => conv_fast::calibrated(gpu),
    }
}

/// Whether the forward of `g` on `kernel` reads its input unpacked (`conv_nchw`): forced by
/// `Nchw`; with `Auto` where it measured faster, so read (`conv_nchw::wins`), and either the packing
/// would not be kept for the weight gradient (a training step's texture packing serves the
/// forward and the weight gradient, so skipping it in the forward saves nothing there) or the
/// forward reads x from its stage (`staged`: `conv_pack::stage_in_place`), which the weight gradient
/// then reads too, kept (`conv_direct_backward_weight_3x3`).
fn uses_nchw(kernel: ConvKernel, gpu: &Gpu, g: &Geometry, staged: bool) -> bool {
    conv_nchw::fits(g) && (kernel == ConvKernel::Nchw || (kernel == ConvKernel::Auto && (!gpu.keeping_packs() || staged) && conv_nchw::wins(gpu, staged)))
}

/// Records the forward conv of `g` (shapes already checked by the caller): `y = conv(x, w) + b`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn dispatch_forward(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    y: &Tensor,
) -> Result<()> {
    if use_fast(kernel, Pass::Forward, g) {
        if uses_nchw(kernel, gpu, g, super::conv_pack::stage_in_place(gpu, pass, g, x)) {
            return conv_nchw::forward(gpu, pass, g, x, w, b, y);
        }
        return conv_fast::forward(gpu, pass, g, x, w, b, y, operands(gpu, kernel));
    }
    let args = [Arg::R(x), Arg::R(w), bias_arg(b), Arg::W(y)];
    reference(gpu, pass, "conv_forward", g, b.is_some(), &args, y.numel())
}

/// Records the backward-input conv of `g` (shapes checked by the caller): `dx = conv^T(dy,
/// w) + b`, the bias being added over `dx`'s channels (only the transposed conv passes one).
#[allow(clippy::too_many_arguments)]
pub(crate) fn dispatch_backward_input(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    dy: &Tensor,
    w: &Tensor,
    b: Option<&Tensor>,
    dx: &Tensor,
) -> Result<()> {
    if use_fast(kernel, Pass::BackwardInput, g) {
        return conv_fast::backward_input(gpu, pass, g, dy, w, b, dx, operands(gpu, kernel));
    }
    let args = [Arg::R(dy), Arg::R(w), bias_arg(b), Arg::W(dx)];
    reference(gpu, pass, "conv_backward_input", g, b.is_some(), &args, dx.numel())
}

/// Records the backward-weight conv of `g` (shapes checked by the caller).
#[allow(clippy::too_many_arguments)]
pub(crate) fn dispatch_backward_weight(
    kernel: ConvKernel,
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    dy: &Tensor,
    dw: &Tensor,
) -> Result<()> {
    if use_fast(kernel, Pass::BackwardWeight, g) {
        return conv_fast::backward_weight(gpu, pass, g, x, dy, dw, operands(gpu, kernel));
    }
    let args = [Arg::R(x), Arg::R(dy), Arg::W(dw)];
    reference(gpu, pass, "conv_backward_weight", g, false, &args, dw.numel())
}

/// Records reference kernel `entry` of `g`: one invocation per value of the `total` it writes.
fn reference(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    entry: &'static str,
    g: &Geometry,
    has_bias: bool,
    args: &[Arg],
    total: usize,
) -> Result<()> {
    let params = Params { has_bias: has_bias as u32, total: total as u32, ..g.params() };
    gpu.dispatch(pass, SHADER, entry, &params, args, grid_1d(total as u64, 64)?)
}
