//! Which family of tiled conv kernels a device runs: buffers or textures ([`Operands`]),
//! chosen once per machine by timing both on a small conv ([`calibrated`]); and whether the
//! texture family's packings copy their texels in, by size ([`copy_min_texels`]).

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
    second_wins(gpu, &g, 0.0, |k, pass, x, w, y| forward(gpu, pass, &g, x, w, None, y, ops[k]))
}

thread_local! {
    /// While `measure_copies` times a size: whether every packing copies (`true`) or none.
    static FORCED: Cell<Option<bool>> = const { Cell::new(None) };
}

/// The fewest texels a texture packing on a CPU adapter must write to go through a staging
/// buffer and a copy (src/gpu/passes.rs) rather than texture stores (`usize::MAX`: none; never
/// elsewhere, where texture stores are not the dear ones). A copy ends the compute pass and
/// begins another, which costs the same whatever the size, and what that costs depends on the
/// CPU: ~95 us on an AMD Zen 4 (the tiny training step's 51 copies: 14.5 against 9.7 ms with
/// every kernel emptied), little on an Intel Xeon (family 6 model 167: 8192 texels copied in
/// 0.10 ms, stored in 0.16), whose texture stores are dear (~130 ns per 8 lanes against ~40 for
/// a vec4 buffer store; an AMD Zen 3: 142 and 117, `bench --operands`). So
/// `RENDERNET_PACK_COPIES` (`copy`: every packing, `store`: none) if set, else the smallest of
/// [`COPY_SIZES`] down to which copying packed a conv's input faster, each size to the same
/// bits (see `copy_threshold`; measured once per machine and cached).
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
        _ => copy_threshold(|size| gpu.calibrated_choice(size.name, || measure_copies(gpu, size).unwrap_or(false))),
    })
}

/// The texels of the smallest of [`COPY_SIZES`] down to which `wins` (timed from the largest
/// size down, each smaller one only where the last won) says copies paid; `usize::MAX` if not
/// even at the largest.
fn copy_threshold(mut wins: impl FnMut(&CopySize) -> bool) -> usize {
    COPY_SIZES.iter().take_while(|s| wins(s)).last().map_or(usize::MAX, |s| s.texels)
}

/// One packing `copy_threshold` times copied and stored: that of a 1x1 conv 16->4 on 16 x `ih`
/// x 32 (D x H x W), an x texture of 32 x `ih` x 64 texels (W, H, 16 depths x 4 channel quads),
/// run `runs` times a pass.
struct CopySize {
    /// Its answer's name in the calibration cache.
    name: &'static str,
    texels: usize,
    ih: usize,
    runs: usize,
    /// The share of the stores' time the copies must save.
    margin: f64,
}

/// `copy_threshold`'s sizes, largest first. The smaller ones run more convs, so that each
/// takes about as long, and copies must save 5% there: on an AMD Zen 4 the two ways timed
/// within 1% of each other at 16384 texels in 3 of 4 calibrations (the large size 4-12% apart),
/// and at a tie the stores keep the pass whole (the tiny training step was 18% faster copying
/// from 65536 texels only than copying every packing).
const COPY_SIZES: [CopySize; 3] = [
    CopySize { name: "conv-pack-copies", texels: 65536, ih: 32, runs: 4, margin: 0.0 },
    CopySize { name: "conv-pack-copies-16384", texels: 16384, ih: 8, runs: 16, margin: 0.05 },
    CopySize { name: "conv-pack-copies-4096", texels: 4096, ih: 2, runs: 64, margin: 0.05 },
];

/// Whether `size`'s conv ran its runs in a pass faster by its margin with its packings copied
/// in than stored, to the same bits. The large size packs its input through uniform windows,
/// the smaller ones (planes under `conv_window`'s smallest chunk) with storage loads; the
/// small weights are stored either way.
fn measure_copies(gpu: &Gpu, size: &CopySize) -> Result<bool> {
    let g = Geometry { n: 1, ci: 16, co: 4, input: [16, size.ih, 32], output: [16, size.ih, 32], kernel: [1; 3], stride: [1; 3], pad: [0; 3], rank: 5 };
    // Textures, not `calibrated`: this may run inside that calibration (its texture kernels
    // pack), and only the texture family packs into textures.
    second_wins(gpu, &g, size.margin, |k, pass, x, w, y| {
        let _forced = Forced::new(k == 1);
        (0..size.runs).try_for_each(|_| forward(gpu, pass, &g, x, w, None, y, Operands::Textures))
    })
}

/// Sets [`FORCED`] while alive (cleared on drop, a panic included).
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
/// conv `g` ran faster than the first by at least `margin` of the first's time (best of 3
/// wall-clock runs each, after a first run that compiles the pipelines) and gave the same bits. The inputs are small integers times 1/8:
/// every product and sum is exact in f32, so two correct kernels agree to the bit.
pub(super) fn second_wins(
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
    Ok(faster_by(best, margin) && ys[0].to_vec(gpu)? == ys[1].to_vec(gpu)?)
}

/// Whether the second of two best times is below the first by at least `margin` of it.
fn faster_by(best: [f64; 2], margin: f64) -> bool {
    best[1] < best[0] * (1.0 - margin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_start_at_the_smallest_size_they_won_down_to() {
        for (wins_from, want, timed) in [(usize::MAX, usize::MAX, 1), (65536, 65536, 2), (16384, 16384, 3), (4096, 4096, 3), (0, 4096, 3)] {
            let mut asked = Vec::new();
            let got = copy_threshold(|s| {
                asked.push(s.name);
                s.texels >= wins_from
            });
            assert_eq!(got, want, "copies winning from {wins_from} texels");
            // Largest first, and a size only after every larger one won.
            let names: Vec<_> = COPY_SIZES.iter().map(|s| s.name).take(timed).collect();
            assert_eq!(asked, names, "copies winning from {wins_from} texels");
        }
        // Each size's texels are what its conv's input packing writes.
        for s in COPY_SIZES {
            assert_eq!(s.texels, 32 * s.ih * 64, "{}", s.name);
            // Named by size, but for the first, which keeps its name from before there were more.
            assert!(s.name == "conv-pack-copies" || s.name.ends_with(&format!("-{}", s.texels)), "{}", s.name);
        }
    }

    #[test]
    fn a_margin_is_a_share_of_the_first_time() {
        assert!(faster_by([1.0, 0.99], 0.0));
        assert!(!faster_by([1.0, 1.0], 0.0));
        assert!(!faster_by([1.0, 0.96], 0.05));
        assert!(faster_by([1.0, 0.94], 0.05));
    }
}
