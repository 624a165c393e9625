//! Which family of tiled conv kernels a device runs: buffers or textures ([`Operands`]),
//! chosen once per machine by timing both on a small conv ([`calibrated`]); and whether the
//! texture family's packings copy their texels in ([`copy_min_texels`]).

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
    /// [`copy_min_texels`]'s answer while it measures (stores, then copies).
    static FORCED: Cell<Option<bool>> = const { Cell::new(None) };
}

/// The fewest texels a texture packing on a CPU adapter must write to go through a staging
/// buffer and a copy (src/gpu/passes.rs) rather than texture stores (`usize::MAX`: none; never
/// elsewhere, where texture stores are not the dear ones). A copy ends the compute pass and
/// begins another, which costs the same whatever the size, and what that costs depends on the
/// CPU: ~100 us on an AMD Zen 4 (the tiny training step's 51 copies: 14.5 against 9.7 ms with
/// every kernel emptied), little on an Intel Xeon (family 6 model 167: 8192 texels copied in
/// 0.10 ms, stored in 0.16), whose texture stores are dear (~130 ns per 8 lanes against ~40 for
/// a vec4 buffer store; an AMD Zen 3: 142 and 117, `bench --operands`). So
/// `RENDERNET_PACK_COPIES` (`copy`: every packing, `store`: none) if set, else the smaller of
/// the two sizes [`COPY_SIZES`] at which copying packed a conv's input faster and to the same
/// bits, none if neither (see `measure_copies`; measured once per machine and cached).
pub(crate) fn copy_min_texels(gpu: &Gpu) -> usize {
    let never = usize::MAX;
    if let Some(forced) = FORCED.with(Cell::get) {
        return if forced { 0 } else { never };
    }
    // Only the texture family packs into textures: without it there is nothing to measure.
    if gpu.info.device_type != wgpu::DeviceType::Cpu || !gpu.has_subgroups_of_8() || !gpu.reads_rgba32f_storage() {
        return never;
    }
    *gpu.pack_copies.get_or_init(|| match std::env::var("RENDERNET_PACK_COPIES").as_deref() {
        Ok("copy") => 0,
        Ok("store") => never,
        _ => {
            let wins = |name: &str, size: CopySize| gpu.calibrated_choice(name, || measure_copies(gpu, &size).unwrap_or(false));
            copy_threshold(|| wins("conv-pack-copies", COPY_SIZES[1]), || wins("conv-pack-copies-small", COPY_SIZES[0]))
        }
    })
}

/// The fewest texels copied in, given whether copies won at `COPY_SIZES`' large size and, asked
/// only where they did, at the small one.
fn copy_threshold(large: impl FnOnce() -> bool, small: impl FnOnce() -> bool) -> usize {
    if !large() {
        usize::MAX
    } else if small() {
        COPY_SIZES[0].texels
    } else {
        COPY_SIZES[1].texels
    }
}

/// One of the two packings `copy_min_texels` times copied and stored: that of a 1x1 conv
/// 16->4 on 16 x `ih` x 32, `texels` = 32 x `ih` x 16 * 16 / 4, run `runs` times a pass.
#[derive(Clone, Copy)]
struct CopySize {
    texels: usize,
    ih: usize,
    runs: usize,
    /// The share of the stores' time the copies must save.
    margin: f64,
}

/// `copy_min_texels`'s sizes, small then large. The small one runs 4 times as many convs, so
/// that both take about as long, and copies must save 5% there: on an AMD Zen 4 the two timed
/// within 1% of each other in 3 of 4 calibrations, the large one 4-12% apart, and at a tie the
/// stores keep the pass whole (the whole training step was 18% faster with copies from 65536
/// texels only, than with every packing copied).
const COPY_SIZES: [CopySize; 2] =
    [CopySize { texels: 16384, ih: 8, runs: 16, margin: 0.05 }, CopySize { texels: 65536, ih: 32, runs: 4, margin: 0.0 }];

/// Whether `size`'s conv (its input packed through uniform windows; its small weights are
/// stored either way) ran its runs in a pass faster by its margin with its packings copied in
/// than stored, to the same bits.
fn measure_copies(gpu: &Gpu, size: &CopySize) -> Result<bool> {
    let g = Geometry { n: 1, ci: 16, co: 4, input: [16, size.ih, 32], output: [16, size.ih, 32], kernel: [1; 3], stride: [1; 3], pad: [0; 3], rank: 5 };
    // Textures, not `calibrated`: this may run inside that calibration (its texture kernels
    // pack), and only the texture family packs into textures.
    second_wins_by(gpu, &g, size.margin, |k, pass, x, w, y| {
        let _forced = Forced::new(k == 1);
        (0..size.runs).try_for_each(|_| forward(gpu, pass, &g, x, w, None, y, Operands::Textures))
    })
}

/// [`copy_min_texels`]'s answer while alive (cleared on drop, a panic included).
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
    second_wins_by(gpu, g, 0.0, run)
}

/// [`second_wins`], the second having to take at most `1 - margin` of the first's time.
fn second_wins_by(
    gpu: &Gpu,
    g: &Geometry,
    margin: f64,
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
    Ok(best[1] < best[0] * (1.0 - margin) && ys[0].to_vec(gpu)? == ys[1].to_vec(gpu)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_start_at_the_smallest_size_they_won_at_and_the_small_one_is_timed_only_after_the_large() {
        let never = || panic!("the small size timed where the large one lost");
        assert_eq!(copy_threshold(|| false, never), usize::MAX);
        assert_eq!(copy_threshold(|| true, || false), 65536);
        assert_eq!(copy_threshold(|| true, || true), 16384);
        // The sizes' texels are what their convs' input packings write: 32 x H x (16 channels / 4).
        for s in COPY_SIZES {
            assert_eq!(s.texels, 32 * s.ih * 4 * 16);
        }
    }
}
