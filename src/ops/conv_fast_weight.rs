//! The tiled conv kernels' weight gradients (`conv_fast`): on textures, the channel-quad tiles of
//! `conv_tex_weight.wgsl` and the direct kernels of `conv_direct_weight.wgsl`, which read x in
//! place in its stage texture; else the buffer family's tile. Each adds partial sums per chunk of
//! output rows that `conv_fast_weight_sum` then adds in a fixed order.

use super::conv::{Geometry, Params};
use super::conv_fast::{Folded, Operands, TEX_SHADER, dispatch, direct_fits, fold, params, volume, x_texture_fits, textures_wanted};
use super::conv_pack::{Packed, pack_folded, pack_input, pack_x, stage_in_place, stage_x};
use crate::error::Result;
use crate::gpu::{Gpu, Tensor, grid_1d, Arg};

/// `dy` packed as the texture kernels pack an input: dy's channels over the output extent
/// (at most 4 channels: one quad per voxel, for the 4-channel kernel).
fn pack_dy_tex(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, dy: &Tensor) -> Result<Packed> {
    let dy_geom = Geometry { ci: g.co, input: g.output, ..*g };
    pack_x(gpu, pass, &dy_geom, &Folded::none(dy_geom), dy, dy_tex_channels(g), true)
}

/// Channels of dy as packed for the texture weight gradient (part keeps `copad`): 4 or 8
/// for the narrow kernels, which then share the packing of `conv_fast::backward_input` (`backward`),
/// else whole groups of 16. The shaders' `dy_quads` reads it back.
fn dy_tex_channels(g: &Geometry) -> usize {
    if g.co <= 8 { g.co.div_ceil(4) * 4 } else { g.co.div_ceil(16) * 16 }
}

/// Whether `backward_weight` of `g` runs on textures for `ops`, with the fold and packed
/// input channels it uses and dy's packed channels.
pub(super) fn weight_textures(gpu: &Gpu, g: &Geometry, ops: Operands) -> Option<(Folded, usize, usize)> {
    let f = fold(g, 4);
    let cpad = f.g.ci.div_ceil(4) * 4;
    // Two activation textures (x folded or staged, dy) and no weight texture.
    let x_fits = if f.fold() > 1 { direct_fits(gpu, ops, g, &f) } else { x_texture_fits(gpu, g.n, cpad, f.g.input) };
    let fits = textures_wanted(gpu, ops) && x_fits && x_texture_fits(gpu, g.n, dy_tex_channels(g), g.output);
    fits.then(|| (f, cpad, dy_tex_channels(g)))
}

/// `backward_weight` on textures (see `conv_fast_backward_weight_tex`), dy packed by
/// [`pack_dy_tex`].
#[allow(clippy::too_many_arguments)]
pub(super) fn backward_weight_tex(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    f: &Folded,
    x: &Tensor,
    dyp: &Packed,
    dw: &Tensor,
    cpad: usize,
) -> Result<()> {
    if f.fold() > 1 || stage_w3(gpu, pass, g, x) {
        return backward_weight_direct(gpu, pass, g, x, dyp, dw, f.fold() == 1);
    }
    let xp = pack_x(gpu, pass, g, f, x, cpad, true)?;
    let copad = g.co.div_ceil(16) * 16;
    let g = &f.g;
    let taps = volume(g.kernel);
    let t = tex_tiling(g, cpad, target_tiles(gpu, 128));
    let part = gpu.scratch(&[t.nchunks, taps, cpad, copad])?;
    let tiles = t.nchunks * t.groups;
    let p = Params { nchunks: t.nchunks as u32, chunk: t.chunk as u32, fold: f.fold() as u32, total: tiles as u32, ..params(g, cpad) };
    let args = [xp.arg(), dyp.arg(), Arg::W(&part)];
    // One or two dy texels a position instead of four where there are at most 4 or 8 outputs.
    let entry = match (g.co, t.w3) {
        (..=4, false) => "conv_fast_backward_weight_tex4",
        (..=4, true) => "conv_fast_backward_weight_tex4_w3",
        (5..=8, false) => "conv_fast_backward_weight_tex8",
        (_, true) if t.wide => "conv_fast_backward_weight_tex16_w3",
        (_, true) => "conv_fast_backward_weight_tex8_w3",
        _ => "conv_fast_backward_weight_tex",
    };
    let (whole, halves) = tex_dispatches(g, cpad, &t);
    if whole > 0 {
        gpu.dispatch(pass, TEX_SHADER, entry, &Params { total: whole as u32, ..p }, &args, tile_grid(whole)?)?;
    }
    if halves > 0 {
        let entry = "conv_fast_backward_weight_tex16_w3_halves";
        gpu.dispatch(pass, TEX_SHADER, entry, &Params { total: halves as u32, ..p }, &args, tile_grid(halves)?)?;
    }
    dispatch(gpu, pass, "conv_fast_weight_sum", p, &[Arg::R(&part), Arg::W(dw)], dw.numel())
}

/// The grid of a weight-gradient dispatch of `tiles` tiles: a workgroup a tile (8 invocations,
/// `lane_tile1`). lavapipe hands whole workgroups to its threads, and these dispatches have
/// few tiles (~16 a thread, `target_tiles`): at 8 tiles a workgroup, the 35 tiles of conv3d
/// 16->16 made 5 workgroups (four of 8 tiles, one of 3), so one of 2 threads took 19 tiles or
/// more, against 17.5 for an even share (README "A workgroup a tile").
fn tile_grid(tiles: usize) -> Result<[u32; 3]> {
    grid_1d(tiles as u64 * 8, 8)
}

/// The tiles of the two weight-gradient dispatches of tiling `t` of `g`: of its kernel over
/// every group of pairs, or, where `_tex16_w3` leaves 1-4 pairs past its whole groups, over
/// the whole ones, and of `_tex16_w3_halves` (one tile a chunk and output channel group,
/// two lanes a pair: see the shader) over the rest.
fn tex_dispatches(g: &Geometry, cpad: usize, t: &TexTiling) -> (usize, usize) {
    let tiles = t.nchunks * t.groups;
    if !t.wide || leftover_pairs(g, cpad) == 0 {
        return (tiles, 0);
    }
    let halves = t.nchunks * g.co.div_ceil(16);
    (tiles - halves, halves)
}

/// The (tap row, channel quad) pairs of a `_w3` tiling of `g` past its whole groups of 8, where
/// they are 1-4 (a tile of them would leave half its lanes or more idle), else 0: 4 for 3^3
/// taps on 16 channels (36 pairs) or 3x3 on 16 (12). README "Two lanes a pair past the whole
/// groups".
fn leftover_pairs(g: &Geometry, cpad: usize) -> usize {
    let left = g.kernel[0] * g.kernel[1] * cpad / 4 % 8;
    if left <= 4 { left } else { 0 }
}

/// How a texture weight-gradient dispatch of `g` (not folded, `cpad` packed input channels)
/// tiles its work for `tiles` tiles in all (`target_tiles`).
#[derive(Debug, PartialEq)]
struct TexTiling {
    /// Three W taps a lane (`_w3`), where they read overlapping x: 8 output channels a lane at
    /// most; past 8 only with 4+ input channel quads (README "Three W taps a lane", an AMD Zen 4).
    w3: bool,
    /// 16 output channels a lane (`_tex16_w3`; `w3` past 8 output channels) where its tiles
    /// still walk 64 steps of 8 columns or more: each x fetch then feeds twice the
    /// multiply-adds (README "Weight gradients an accumulator at a time": 1.16x on conv3d
    /// 16->16, 1.08x on conv2d 256->256, 0.91x on conv2d 32->32 on 32x32, whose tiles would walk
    /// 24 steps, on an AMD EPYC Zen 3), and whose rows take an even count of those steps: it
    /// walks steps of 16 columns, and a row of an odd count would multiply a last half step of
    /// zeros (README "Steps of 16 columns").
    wide: bool,
    /// Tiles a chunk of output rows.
    groups: usize,
    /// Output rows a chunk.
    chunk: usize,
    /// Chunks (partial sums for `conv_fast_weight_sum`).
    nchunks: usize,
}

fn tex_tiling(g: &Geometry, cpad: usize, tiles: usize) -> TexTiling {
    let taps = volume(g.kernel);
    let rows = g.n * g.output[0] * g.output[1];
    let w3 = g.kernel[2] == 3 && g.stride[2] == 1 && (g.co <= 8 || cpad >= 16);
    let tiling = |lane_taps: usize, co_groups: usize, wide: bool| {
        let groups = (lane_taps * cpad / 4).div_ceil(8) * co_groups;
        let (chunk, nchunks) = weight_chunks(rows, groups, tiles);
        TexTiling { w3, wide, groups, chunk, nchunks }
    };
    let copad = g.co.div_ceil(16) * 16;
    if !w3 {
        return tiling(taps, copad / 16, false);
    }
    let wide = tiling(taps / 3, copad / 16, true);
    let steps8 = g.output[2].div_ceil(8);
    if g.co > 8 && steps8 % 2 == 0 && wide.chunk * steps8 >= 64 { wide } else { tiling(taps / 3, g.co.div_ceil(8), false) }
}

/// Tiles a weight-gradient dispatch aims at: on a CPU adapter 16 per CPU thread (lavapipe runs
/// one thread per CPU: on a 2-core AMD EPYC Zen 3 this took the weight gradients of the tiny
/// preset's training shapes 5-26% faster (medians) than the 128-256 tiles before, README
/// "Fewer chunks in the weight gradients", and left the large ones unchanged); elsewhere
/// `gpu_tiles`.
fn target_tiles(gpu: &Gpu, gpu_tiles: usize) -> usize {
    // Read once: on Linux the thread count comes from cgroup files, and this runs per recording.
    static CPU_TILES: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    if gpu.info.device_type == wgpu::DeviceType::Cpu {
        *CPU_TILES.get_or_init(|| 16 * std::thread::available_parallelism().map_or(2, |n| n.get()))
    } else {
        gpu_tiles
    }
}

/// The chunks of `rows` output rows a weight-gradient dispatch of `per_chunk` tiles a chunk
/// splits them into for about `tiles` tiles, as (rows a chunk, chunks); never more chunks than
/// rows. Each chunk adds a partial sum that `conv_fast_weight_sum` reads back with storage loads
/// (on lavapipe 22.3 a loop over the 8 lanes each), so more chunks spread the tiles over more
/// threads but cost more in the sum.
fn weight_chunks(rows: usize, per_chunk: usize, tiles: usize) -> (usize, usize) {
    let chunk = rows.div_ceil(tiles.div_ceil(per_chunk).clamp(1, rows));
    (chunk, rows.div_ceil(chunk))
}

/// Whether `g` has the shape of `conv_direct_backward_weight_3x3`: 3 x 3 taps along H and W at
/// stride 1 there, at most 8 output channels (the narrow heads).
fn w3_shape(g: &Geometry) -> bool {
    g.kernel[1..] == [3, 3] && g.stride[1..] == [1, 1] && g.co <= 8
}

/// Whether the weight gradient of `g` (not folded) reads x in place in its stage
/// (`conv_direct_backward_weight_3x3`) rather than packed by channel quads: a [`w3_shape`] whose x
/// is copied into the stage with no dispatch and fits it (`stage_in_place`). On an AMD Zen 4 the
/// 16 -> 3 head at 128 x 128 took 1.02 against 1.72 ms so, and 1.94 with the stage written by a
/// dispatch instead (README "The heads on x in place").
fn stage_w3(gpu: &Gpu, pass: &wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor) -> bool {
    w3_shape(g) && stage_in_place(gpu, pass, g, x)
}

/// The weight gradient of a conv the texture family would fold (few input channels), without
/// folding, or where `w3`, of a [`stage_w3`] conv: `conv_direct_backward_weight*` read the
/// staged input in place (see their shader).
fn backward_weight_direct(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, g: &Geometry, x: &Tensor, dyp: &Packed, dw: &Tensor, w3: bool) -> Result<()> {
    let cpad = g.ci.div_ceil(4) * 4;
    let p = params(g, cpad);
    let stage = stage_x(gpu, pass, g, x, &p)?;
    // Tiles a chunk: of 8 (kernel depth, channel) pairs (`_3x3`), or of 8 output columns per
    // column of taps; 5 x 5 taps (the first layer): `_k5` tiles take them all, sharing each dy fetch.
    let k5 = g.kernel[1] == 5 && g.kernel[2] == 5;
    let (entry, cols) = match (w3, k5) {
        (true, _) => (if g.co <= 4 { "conv_direct_backward_weight_3x3" } else { "conv_direct_backward_weight_3x3x8" }, (g.kernel[0] * g.ci).div_ceil(8)),
        (false, true) => ("conv_direct_backward_weight_k5", g.kernel[0] * g.ci * g.co.div_ceil(8)),
        (false, false) => ("conv_direct_backward_weight", g.kernel[0] * g.ci * g.kernel[1] * g.kernel[2].div_ceil(4) * g.co.div_ceil(8)),
    };
    // `_3x3` walks strips of 16 columns down their rows, `lead` columns early (see the shader).
    let lead = (4 - g.pad[2] % 4) % 4;
    let rows = g.n * g.output[0] * if w3 { (g.output[2] + lead).div_ceil(16) * g.output[1] } else { g.output[1] };
    let (chunk, nchunks) = weight_chunks(rows, cols, target_tiles(gpu, 256));
    let part = gpu.scratch(&[nchunks, volume(g.kernel), cpad, g.co.div_ceil(16) * 16])?;
    let tiles = nchunks * cols;
    let p = Params { nchunks: nchunks as u32, chunk: chunk as u32, total: tiles as u32, ..p };
    let args = [Arg::ReadStorageTexture(&stage, wgpu::TextureViewDimension::D3), dyp.arg(), Arg::W(&part)];
    gpu.dispatch(pass, TEX_SHADER, entry, &p, &args, tile_grid(tiles)?)?;
    dispatch(gpu, pass, "conv_fast_weight_sum", p, &[Arg::R(&part), Arg::W(dw)], dw.numel())
}

/// Tiled `dw[co, ci, k] = Σ dy[n, co, o] x[n, ci, o*s - pad + k]`: partial sums per chunk of
/// output rows, then a fixed-order sum over chunks (deterministic, no atomics).
pub(crate) fn backward_weight(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    g: &Geometry,
    x: &Tensor,
    dy: &Tensor,
    dw: &Tensor,
    ops: Operands,
) -> Result<()> {
    if let Some((f, cpad, _)) = weight_textures(gpu, g, ops) {
        let dyp = pack_dy_tex(gpu, pass, g, dy)?;
        return backward_weight_tex(gpu, pass, g, &f, x, &dyp, dw, cpad);
    }
    let f = fold(g, 8);
    let (cpad, copad) = (f.g.ci.div_ceil(8) * 8, g.co.div_ceil(16) * 16);
    let xp = pack_folded(gpu, pass, g, &f, x, cpad)?;
    let g = &f.g;
    let dyp = pack_input(gpu, pass, dy, g.n, g.co, g.output, copad)?;
    let taps = volume(g.kernel);
    let columns = taps * (cpad / 8) * (copad / 16);
    // Chunks of output rows (n, od, oh): enough for ~1024 invocations (lavapipe spreads
    // workgroups over its threads), and about 1024 positions or fewer each so the operands a
    // workgroup streams stay in cache (2x on the 512->256 projection's weight gradient),
    // never more chunks than there are rows.
    let rows = g.n * g.output[0] * g.output[1];
    let nchunks = 1024usize.div_ceil(columns).max((rows * g.output[2]).div_ceil(1024)).clamp(1, rows);
    let chunk = rows.div_ceil(nchunks);
    let nchunks = rows.div_ceil(chunk);
    let part = gpu.scratch(&[nchunks, taps, cpad, copad])?;
    let p = Params { nchunks: nchunks as u32, chunk: chunk as u32, fold: f.fold() as u32, ..params(g, cpad) };
    dispatch(gpu, pass, "conv_fast_backward_weight", p, &[Arg::R(&xp), Arg::R(&dyp), Arg::W(&part)], nchunks * columns)?;
    dispatch(gpu, pass, "conv_fast_weight_sum", p, &[Arg::R(&part), Arg::W(dw)], dw.numel())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geometry(n: usize, ci: usize, co: usize, io: [usize; 3], kernel: [usize; 3]) -> Geometry {
        Geometry { n, ci, co, input: io, output: io, kernel, stride: [1; 3], pad: kernel.map(|k| k / 2), rank: 5 }
    }

    /// `_tex16_w3_halves` takes the 4 pairs past 32 of 3^3 taps on 16 channels (36) and past 8
    /// of 3x3 on 16 (12); none of 3x3 on 32 (24, whole groups), nor 5 past 40 of 3^3 on 20
    /// (a tile of them leaves 3 lanes idle, fewer than halves would).
    #[test]
    fn halves_take_1_to_4_pairs_past_the_whole_groups() {
        let g = |ci: usize, kernel: [usize; 3]| geometry(1, ci, 16, [8, 32, 32], kernel);
        assert_eq!(leftover_pairs(&g(16, [3; 3]), 16), 4);
        assert_eq!(leftover_pairs(&g(16, [1, 3, 3]), 16), 4);
        assert_eq!(leftover_pairs(&g(32, [1, 3, 3]), 32), 0);
        assert_eq!(leftover_pairs(&g(20, [3; 3]), 20), 0);
        assert_eq!(leftover_pairs(&g(4, [1, 3, 3]), 4), 3);
        // kernels-tests/conv/wide.rs's third case: 2 past 16, and `_tex16_w3` runs.
        let third = geometry(2, 24, 12, [1, 96, 64], [1, 3, 3]);
        assert!(leftover_pairs(&third, 24) == 2 && tex_tiling(&third, 24, 32).wide);
        // conv3d 16->16 on 32^3 at 32 tiles: 7 chunks of 4 whole groups, and a halves tile each.
        let bench = geometry(1, 16, 16, [32; 3], [3; 3]);
        assert_eq!(tex_dispatches(&bench, 16, &tex_tiling(&bench, 16, 32)), (28, 7));
        // 36 -> 20 (wide.rs's fourth case): 81 pairs, 1 past 80; 2 output channel groups.
        let fourth = geometry(1, 36, 20, [8, 12, 64], [3; 3]);
        for tiles in [32, 256] {
            let t = tex_tiling(&fourth, 36, tiles);
            assert!(t.wide && leftover_pairs(&fourth, 36) == 1, "{t:?}");
            assert_eq!(tex_dispatches(&fourth, 36, &t), (t.nchunks * 20, t.nchunks * 2));
        }
        // Off `_tex16_w3`, one dispatch.
        let narrow = geometry(1, 32, 32, [1, 32, 32], [1, 3, 3]);
        let t = tex_tiling(&narrow, 32, 32);
        assert_eq!(tex_dispatches(&narrow, 32, &t), (t.nchunks * t.groups, 0));
    }

    /// At the 32 tiles of a 2-thread CPU adapter: 16 output channels a lane for the shapes of
    /// the kernel test `texture_weight_gradient_of_16_output_channels_a_lane`
    /// (kernels-tests/conv/wide.rs), so that test runs `_tex16_w3` and a narrower rule fails
    /// here, and for the benchmark's conv3d 16->16 on 32^3; 8 where the tiles would walk fewer
    /// than 64 steps (conv2d 32->32 on 32x32: 24), and never at 8 output channels or fewer or
    /// off `_w3`.
    #[test]
    fn wide_tiles_where_they_walk_64_steps() {
        let t3d = geometry(1, 16, 20, [8, 32, 57], [3; 3]);
        let t2d = geometry(2, 16, 12, [1, 64, 73], [1, 3, 3]);
        let bench = geometry(1, 16, 16, [32; 3], [3; 3]);
        for g in [t3d, t2d, bench] {
            let t = tex_tiling(&g, 16, 32);
            assert!(t.w3 && t.wide, "{g:?}: {t:?}");
            assert!(t.chunk * g.output[2].div_ceil(8) >= 64 && t.groups * t.nchunks >= 32, "{t:?}");
        }
        // 3D 16 -> 20: 5 groups of 8 (9 tap rows x 4 quads) x 2 output groups a chunk, 4 chunks
        // of 64 rows; at 256 tiles (a 16-thread CPU adapter) 26 chunks of 10 rows, 80 steps.
        assert_eq!(tex_tiling(&t3d, 16, 32), TexTiling { w3: true, wide: true, groups: 10, chunk: 64, nchunks: 4 });
        assert!(tex_tiling(&t3d, 16, 256).wide && tex_tiling(&t3d, 16, 128).wide);
        let narrow = tex_tiling(&geometry(1, 32, 32, [1, 32, 32], [1, 3, 3]), 32, 32);
        assert!(narrow.w3 && !narrow.wide && narrow.groups == 12, "{narrow:?}");
        // More threads, shorter chunks: 8 a lane again.
        assert!(!tex_tiling(&t3d, 16, 512).wide && !tex_tiling(&t2d, 16, 48).wide);
        // 8 output channels: `_tex8_w3`'s groups fill a lane, however long the chunks.
        assert!(!tex_tiling(&Geometry { co: 8, ..bench }, 16, 32).wide);
        // Rows of 3 steps of 8 columns (17-24 wide): 2 steps of 16 would add a third.
        for ow in [17, 24, 40] {
            let odd = Geometry { input: [8, 64, ow], output: [8, 64, ow], ..bench };
            assert!(!tex_tiling(&odd, 16, 32).wide && tex_tiling(&Geometry { input: [8, 64, ow + 8], output: [8, 64, ow + 8], ..odd }, 16, 32).wide);
        }
        assert!(!tex_tiling(&Geometry { kernel: [3, 3, 2], ..t3d }, 16, 32).w3);
        assert!(!tex_tiling(&Geometry { kernel: [3, 3, 2], ..t3d }, 16, 32).wide);
    }
}
