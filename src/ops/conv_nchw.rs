//! The narrow 3x3 heads' forward on the unpacked input (`shaders/conv_nchw.wgsl`): 2D, stride
//! 1, padding 1, at most 8 output channels (a dispatch per group of 4), W a multiple of 4.
//! The texture family packs x into a texture first, and on lavapipe the texture stores cost
//! more than the conv (README
//! "Measured: Intel Xeon (family 6 model 167)"); this kernel reads x where it lies, or where
//! x's rows are whole staging rows, copied as it lies into the direct kernels' stage texture
//! (README "The heads on x in place"). Whether it
//! beats the packed kernel depends on the driver and the CPU (its storage loads are gathers,
//! slow on an AMD Zen 3 with Mesa 22.3), so [`ConvKernel::Auto`](super::conv::ConvKernel)
//! takes it only where a timing on this machine says so ([`wins`]); `ConvKernel::Nchw`
//! forces it.

use super::conv::Geometry;
use super::conv_fast;
use super::conv_pack::{stage_in_place, stage_x};
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Packing, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("conv_nchw");

/// Input channels the kernel's weight block holds (`wk`: 576 vec4s = 64 x 9 taps).
const MAX_CI: usize = 64;

/// Output channels: two groups of 4, each a dispatch that reads the whole input (measured
/// only up to the joint Phong head's 5; past 8, each more group reads the input again).
const MAX_CO: usize = 8;

#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct NchwParams {
    n: u32,
    ci: u32,
    co: u32,
    h: u32,
    w4: u32,
    /// Blocks of 8 output rows.
    hb: u32,
    has_bias: u32,
    /// Invocations: one per vec4 column, block of rows and item.
    total: u32,
    /// The dispatch's first output channel (its group of 4).
    og: u32,
    /// The uniform block's size is a multiple of 16 bytes.
    pad: [u32; 3],
}

/// Whether the kernel computes the forward of `g`: a 2D 3x3 conv at stride 1 with padding 1
/// (output as large as the input), 1 to 8 output channels, 1 to 64 input channels, the width
/// a multiple of 4.
pub(crate) fn fits(g: &Geometry) -> bool {
    g.input[0] == 1
        && g.kernel == [1, 3, 3]
        && g.stride == [1, 1, 1]
        && g.pad == [0, 1, 1]
        && g.output == g.input
        && (1..=MAX_CO).contains(&g.co)
        && (1..=MAX_CI).contains(&g.ci)
        && g.input[2].is_multiple_of(4)
}

fn params(g: &Geometry, has_bias: bool) -> NchwParams {
    let (h, w4) = (g.input[1] as u32, (g.input[2] / 4) as u32);
    let hb = h.div_ceil(8);
    NchwParams { n: g.n as u32, ci: g.ci as u32, co: g.co as u32, h, w4, hb, has_bias: has_bias as u32, total: g.n as u32 * hb * w4, ..Default::default() }
}

/// `w` ([co, ci, 3, 3]) packed for the kernel's dispatch `p` (its group of output channels):
/// kept from one run of a graph to the next while the parameters do not change, like the
/// tiled kernels' weight packings.
fn packed_weights(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, p: NchwParams, w: &Tensor) -> Result<Tensor> {
    let shape = [MAX_CI * 9 * 4];
    let key = [b"conv_nchw".as_slice(), &p.og.to_le_bytes()].concat();
    let kept = gpu.constant_packing(w, &key, (shape[0] * 4) as u64, || Ok(Packing::Buffer(Tensor::zeros(gpu, &shape)?)))?;
    let (t, valid) = match kept {
        Some((Packing::Buffer(t), valid)) => (t, valid),
        // A buffer of its own (pooled inside a recording) at offset 0: the uniform binding
        // takes all of its 9216 bytes, the block the shader declares.
        _ => (gpu.scratch(&shape)?, false),
    };
    if !valid {
        gpu.dispatch(pass, SHADER, "conv_nchw_pack_weights", &p, &[Arg::R(w), Arg::W(&t)], [(p.ci * 9).div_ceil(64), 1, 1])?;
    }
    Ok(t)
}

/// Records `y = conv(x, w) + b` for a `g` that [`fits`]: reading x from the direct kernels'
/// stage texture (`conv_nchw_forward3x3_stage`) where `stage_in_place` says so, else from
/// its buffer.
#[allow(clippy::too_many_arguments)]
pub(crate) fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor, w: &Tensor, b: Option<&Tensor>, y: &Tensor) -> Result<()> {
    debug_assert!(fits(g));
    let stage = if stage_in_place(gpu, pass, g, x) {
        Some(stage_x(gpu, pass, g, x, &conv_fast::params(g, g.ci.div_ceil(4) * 4))?)
    } else {
        None
    };
    for og in (0..g.co).step_by(4) {
        let p = NchwParams { og: og as u32, ..params(g, b.is_some()) };
        let wk = packed_weights(gpu, pass, p, w)?;
        let mut args = vec![Arg::R(x), Arg::U(&wk), b.map_or(Arg::Absent, Arg::R), Arg::W(y)];
        let entry = match &stage {
            Some(v) => {
                args.push(Arg::ReadStorageTexture(v, wgpu::TextureViewDimension::D3));
                "conv_nchw_forward3x3_stage"
            }
            None => "conv_nchw_forward3x3",
        };
        gpu.dispatch(pass, SHADER, entry, &p, &args, grid_1d(p.total as u64, 64)?)?;
    }
    Ok(())
}

/// Whether `ConvKernel::Auto` runs this kernel for the heads on `gpu`, reading x from its
/// stage texture where `staged` (`conv_pack::stage_in_place`), else from its buffer: `RENDERNET_CONV_HEADS`
/// (`nchw` or `packed`) if set, else whether it ran a 16->3 head 64 rows high, 64 wide (staged
/// on a CPU adapter) or 60 wide (never staged), faster than the tiled family `Auto` reads
/// (`conv_fast::calibrated`) and to the same bits (best of 3 timed runs each), measured once
/// per machine and cached (`Gpu::calibrated_choice`).
pub(crate) fn wins(gpu: &Gpu, staged: bool) -> bool {
    *gpu.conv_nchw[usize::from(staged)].get_or_init(|| match std::env::var("RENDERNET_CONV_HEADS").as_deref() {
        Ok("nchw") => true,
        Ok("packed") => false,
        // The buffer kernel's key is the one it had before the stage kernel existed.
        _ => gpu.calibrated_choice(if staged { "conv-nchw-heads-staged" } else { "conv-nchw-heads" }, || measure(gpu, staged).unwrap_or(false)),
    })
}

fn measure(gpu: &Gpu, staged: bool) -> Result<bool> {
    let ops = super::conv_fast::calibrated(gpu);
    let w = if staged { 64 } else { 60 };
    let g = Geometry { n: 1, ci: 16, co: 3, input: [1, 64, w], output: [1, 64, w], kernel: [1, 3, 3], stride: [1; 3], pad: [0, 1, 1], rank: 4 };
    // Without a bias: the path a transposed conv's input gradient takes.
    super::conv_operands::second_wins(gpu, &g, 0.0, |k, pass, x, w, y| {
        if k == 0 { super::conv_fast::forward(gpu, pass, &g, x, w, None, y, ops) } else { forward(gpu, pass, &g, x, w, None, y) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(ci: usize, co: usize, input: [usize; 3]) -> Geometry {
        Geometry { n: 2, ci, co, input, output: input, kernel: [1, 3, 3], stride: [1; 3], pad: [0, 1, 1], rank: 4 }
    }

    /// The shapes the kernel computes, and one step past each of its limits.
    #[test]
    fn fits_the_narrow_3x3_heads_only() {
        assert!(fits(&head(16, 3, [1, 128, 128])));
        assert!(fits(&head(1, 1, [1, 1, 4])));
        assert!(fits(&head(64, 4, [1, 7, 12])));
        assert!(!fits(&head(65, 3, [1, 8, 8])), "past the weight block");
        assert!(fits(&head(16, 8, [1, 8, 8])));
        assert!(!fits(&head(16, 9, [1, 8, 8])), "9 output channels");
        assert!(!fits(&head(16, 3, [1, 8, 10])), "width not a multiple of 4");
        assert!(!fits(&head(16, 3, [2, 8, 8])), "3D");
        assert!(!fits(&Geometry { stride: [1, 2, 1], output: [1, 4, 8], ..head(16, 3, [1, 8, 8]) }), "stride 2");
        assert!(!fits(&Geometry { kernel: [1, 5, 5], pad: [0, 2, 2], ..head(16, 3, [1, 8, 8]) }), "5x5");
        assert!(!fits(&Geometry { pad: [0, 0, 0], output: [1, 6, 6], ..head(16, 3, [1, 8, 8]) }), "no padding");
    }

    /// The parameters cover every row and vec4 column of every item once.
    #[test]
    fn one_invocation_per_column_block_and_item() {
        let p = params(&head(5, 3, [1, 17, 12]), true);
        assert_eq!((p.h, p.w4, p.hb, p.total, p.has_bias), (17, 3, 3, 2 * 3 * 3, 1));
    }
}
