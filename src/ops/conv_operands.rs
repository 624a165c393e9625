//! Which family of tiled conv kernels a device runs: buffers or textures ([`Operands`]),
//! chosen once per machine by timing both on a small conv ([`calibrated`]); and whether the
//! texture family's packings copy their texels in ([`copies_win`]).

use super::conv::Geometry;
use super::conv_fast::forward;
use crate::error::Result;
use crate::gpu::{Gpu, Tensor};
use std::cell::Cell;

/// Where the tiled kernels read their packed operands: storage buffers
/// (`shaders/conv_fast.wgsl`), or textures shared across lanes by subgroup shuffles
/// (`shaders/conv_tex.wgsl`; far cheaper loads on lavapipe, needs subgroups of 8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Operands {
    /// Channels-last storage buffers, one register tile per invocation.
    Buffers,
    /// rgba32f read-only storage textures, one register tile per subgroup of 8 lanes.
    Textures,
}

/// The operands `ConvKernel::Auto` uses on `gpu`: buffers without subgroups of 8 or read-only
/// rgba32f storage textures; otherwise `RENDERNET_CONV_OPERANDS` (`buffers` or `textures`) if
/// set, else textures if they ran a small conv faster and identically (see `measure`), measured once per machine and cached
/// (`Gpu::calibrated_choice`): which family wins depends on the driver and on the CPU
/// lavapipe runs on (texture fetches against per-lane buffer loads).
pub(crate) fn calibrated(gpu: &Gpu) -> Operands {
    let textures = *gpu.conv_textures.get_or_init(|| {
        if !gpu.has_subgroups_of_8() || !gpu.reads_rgba32f_storage() {
            return false;
        }
        match std::env::var("RENDERNET_CONV_OPERANDS").as_deref() {
            Ok("buffers") => false,
            Ok("textures") => true,
            // A failed measurement keeps the buffers, which work everywhere.
            _ => gpu.calibrated_choice("conv-textures-v2", || measure(gpu).unwrap_or(false)),
        }
    });
    if textures { Operands::Textures } else { Operands::Buffers }
}

/// Whether the texture kernels ran the calibration conv faster than the buffer kernels (best
/// of 3 wall-clock runs each, after a first run that compiles the pipelines) and gave the same
/// result: the texture kernels assume subgroups made of consecutive invocations, which no
/// specification promises, so a device where they disagree keeps the buffers.
fn measure(gpu: &Gpu) -> Result<bool> {
    let g = Geometry { n: 1, ci: 16, co: 16, input: [16; 3], output: [16; 3], kernel: [3; 3], stride: [1; 3], pad: [1; 3], rank: 5 };
    let ops = [Operands::Buffers, Operands::Textures];
    second_wins(gpu, &g, |k, pass, x, w, y| forward(gpu, pass, &g, x, w, None, y, ops[k]))
}

thread_local! {
    /// [`copies_win`]'s answer while it measures (stores, then copies).
    static FORCED: Cell<Option<bool>> = const { Cell::new(None) };
}

/// Whether the texture family's packings on a CPU adapter write a staging buffer and copy it
/// into their texture (src/gpu/passes.rs) rather than store every texel (never elsewhere:
/// there texture stores are not the dear ones): `RENDERNET_PACK_COPIES`
/// (`copy` or `store`) if set, else whether copying packed a conv's input faster and to the
/// same bits (see `measure_copies`), measured once per machine and cached. On an Intel Xeon
/// (family 6 model 167, Mesa 22.3.6) an rgba32f texture store cost ~130 ns per 8 lanes, a
/// vec4 buffer store ~40, on an AMD Zen 3 142 and 117 (`bench --operands`): what a copy
/// saves depends on the CPU.
pub(crate) fn copies_win(gpu: &Gpu) -> bool {
    if let Some(forced) = FORCED.with(Cell::get) {
        return forced;
    }
    // Only the texture family packs into textures: without it there is nothing to measure.
    if gpu.info.device_type != wgpu::DeviceType::Cpu || !gpu.has_subgroups_of_8() || !gpu.reads_rgba32f_storage() {
        return false;
    }
    *gpu.pack_copies.get_or_init(|| match std::env::var("RENDERNET_PACK_COPIES").as_deref() {
        Ok("copy") => true,
        Ok("store") => false,
        _ => gpu.calibrated_choice("conv-pack-copies", || measure_copies(gpu).unwrap_or(false)),
    })
}

/// Whether a 1x1 conv 16->4 on 16x32x32 (its input packed through uniform windows, 65536
/// texels; its small weights are stored either way) ran 4 times in a pass faster with its
/// packings copied in than stored, to the same bits.
fn measure_copies(gpu: &Gpu) -> Result<bool> {
    let g = Geometry { n: 1, ci: 16, co: 4, input: [16, 32, 32], output: [16, 32, 32], kernel: [1; 3], stride: [1; 3], pad: [0; 3], rank: 5 };
    // Textures, not `calibrated`: this may run inside that calibration (its texture kernels
    // pack), and only the texture family packs into textures.
    second_wins(gpu, &g, |k, pass, x, w, y| {
        let _forced = Forced::new(k == 1);
        (0..4).try_for_each(|_| forward(gpu, pass, &g, x, w, None, y, Operands::Textures))
    })
}

/// [`copies_win`]'s answer while alive (cleared on drop, a panic included).
struct Forced;

impl Forced {
    fn new(copies: bool) -> Forced {
        FORCED.with(|f| f.set(Some(copies)));
        Forced
    }
}

impl Drop for Forced {
    fn drop(&mut self) {
        FORCED.with(|f| f.set(None));
    }
}

/// Whether the second of two ways `run(k, pass, x, w, y)` (k = 0, 1) to compute the forward
/// conv `g` ran faster than the first (best of 3 wall-clock runs each, after a first run that
/// compiles the pipelines) and gave the same bits. The inputs are small integers times 1/8:
/// every product and sum is exact in f32, so two correct kernels agree to the bit.
pub(super) fn second_wins(
    gpu: &Gpu,
    g: &Geometry,
    run: impl Fn(usize, &mut wgpu::ComputePass<'_>, &Tensor, &Tensor, &Tensor) -> Result<()>,
) -> Result<bool> {
    let ramp = |len: usize, k: usize| (0..len).map(|i| ((i * k) % 7) as f32 / 8.0 - 0.375).collect::<Vec<_>>();
    let ramped = |shape: Vec<usize>, k: usize| Tensor::from_slice(gpu, &shape, &ramp(shape.iter().product(), k));
    let x = ramped(g.shape(g.n, g.ci, g.input), 5)?;
    let w = ramped(g.shape(g.co, g.ci, g.kernel), 3)?;
    let ys = [Tensor::zeros(gpu, &g.y_shape())?, Tensor::zeros(gpu, &g.y_shape())?];
    let mut best = [f64::INFINITY; 2];
    for round in 0..4 {
        for (k, y) in ys.iter().enumerate() {
            let t = std::time::Instant::now();
            gpu.run(|pass| run(k, pass, &x, &w, y))?;
            if round > 0 {
                best[k] = best[k].min(t.elapsed().as_secs_f64());
            }
        }
    }
    Ok(best[1] < best[0] && ys[0].to_vec(gpu)? == ys[1].to_vec(gpu)?)
}
