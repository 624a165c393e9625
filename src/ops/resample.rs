//! Rigid-body resampling of a voxel grid into a camera-aligned grid, RenderNet's first layer
//! (binds `shaders/resample.wgsl`), with gradients to the grid and to the pose.
//!
//! Coordinates: a point is `(d, h, w)` in voxel-index units with voxel centres at integer
//! indices; `c = (size - 1) / 2` per axis is a grid's centre. D is the viewing direction (later
//! folded into channels), H the image rows, W the image columns. A pose is six numbers
//! `(s, az, el, t_d, t_h, t_w)`: scale, azimuth and elevation in radians, translation in
//! output voxels. The forward map from input point `q` to output point `p` is
//!
//! `p = c_out + t + s * R_el * R_az * (q - c_in)`
//!
//! with `R_az` a rotation about H that turns the +W axis towards +D (rows `[ca 0 sa; 0 1 0;
//! -sa 0 ca]`) and `R_el` a rotation about W that turns +H towards +D (rows `[ce se 0; -se ce 0;
//! 0 0 1]`). So at `az = 90°` the input's W axis becomes the output's D axis. Each output voxel
//! samples the input trilinearly at the inverse image `q = c_in + R_az^T R_el^T (p - c_out - t)
//! / s`; the transform is orthographic, as in the paper (no perspective divide).
//!
//! Outside the input grid samples read **zero**. The original TensorFlow code clamps indices
//! to the edge instead; we differ on purpose: an occupancy grid is empty outside, zero keeps
//! the resampling continuous in the pose, and it bounds the backward gather (each input voxel
//! feeds only outputs whose sample lies within one voxel of it, where an edge clamp would make
//! border voxels feed unboundedly many). Nor do we swap H/W and flip H afterwards as that code
//! does: our axes are image axes from the start.
//!
//! The scale must be positive (it divides); poses live on the GPU so this is not checked.
//!
//! The forward and the pose gradient read the grid either from its storage buffer or, where
//! the device reads textures fast (the one-off conv calibration chose textures: lavapipe),
//! from a zero-bordered rgba32f texture it is first packed into ([`Sampling`]); the two agree
//! to f32 rounding (the texture path blends the corners in another order and maps output
//! points to sample points by a precomputed affine map). On lavapipe 22.3 / AMD Zen 3
//! the texture path runs the tiny preset's resampling 32^3 -> 64^3 about 7x faster, forward
//! and pose gradient (`rendernet bench --filter resample`).

use super::{expect_rank, expect_shape, reduce};
use super::conv::{self, Geometry};
use super::conv_fast::{Operands, calibrated};
use super::conv_pack;
use crate::error::{Error, Result, shape_err};
use crate::gpu::{Arg, Gpu, MAX_WORKGROUPS_PER_DIM, Shader, Tensor, grid_1d, wgsl};

const SHADER: Shader = wgsl!("resample");

/// Values per pose: scale, azimuth, elevation, translation (d, h, w).
pub const POSE_LEN: usize = 6;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    n: u32,
    c: u32,
    inp: [u32; 3],
    out: [u32; 3],
}

impl Params {
    fn new(n: usize, c: usize, inp: &[usize], out: &[usize]) -> Params {
        let u = |s: &[usize]| [s[0] as u32, s[1] as u32, s[2] as u32];
        Params { n: n as u32, c: c as u32, inp: u(inp), out: u(out) }
    }
}

/// A pose for the paper's camera conventions (its datasets sample azimuth in [0, 359]°,
/// elevation in [10, 170]° as a polar angle so 90° is horizontal, camera radius in [3, 6.3]):
/// scale `3.3 / radius` as the original code, azimuth in radians, elevation rotation
/// `elevation - 90°` in radians, no translation. The original code also offsets azimuth by
/// -90°; we do not, so azimuth 0 is the grid's own orientation (a fixed turn of the canonical
/// frame, which only has to agree with the renderer that makes the ground truth).
pub fn pose_from_view(azimuth_deg: f32, elevation_deg: f32, radius: f32) -> [f32; POSE_LEN] {
    [3.3 / radius, azimuth_deg.to_radians(), (elevation_deg - 90.0).to_radians(), 0.0, 0.0, 0.0]
}

/// Checks `grid` is `[N, C, D, H, W]` and `pose` is `[N, 6]`; returns `(N, C)`.
fn check_grid_pose(op: &str, arg: &str, grid: &Tensor, pose: &Tensor) -> Result<(usize, usize)> {
    expect_rank(op, arg, grid, 5)?;
    let (n, c) = (grid.shape()[0], grid.shape()[1]);
    expect_shape(op, "pose", pose, &[n, POSE_LEN])?;
    Ok((n, c))
}

/// Checks that `other` is a 5D grid with batch and channels `(n, c)`.
fn check_nc(op: &str, arg: &str, other: &Tensor, (n, c): (usize, usize)) -> Result<()> {
    expect_rank(op, arg, other, 5)?;
    if other.shape()[..2] != [n, c] {
        return Err(shape_err(op, format!("{arg} has shape {:?}, expected batch and channels [{n}, {c}, ..]", other.shape())));
    }
    Ok(())
}

/// Where the forward and the pose gradient read the grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sampling {
    /// The texture where the conv kernels read textures (`ConvKernel::Auto`'s one-off
    /// calibration chose them on this device) and the packed grid fits a 3D texture, else the
    /// buffer.
    #[default]
    Auto,
    /// Trilinear loads from the grid's storage buffer (on lavapipe each a loop over the 8
    /// SIMD lanes).
    Buffer,
    /// The grid packed first into a zero-bordered rgba32f 3D texture (4 channels a texel; with
    /// one channel, the 4 corners of a cell's face), read as a read-only storage texture: ~7x
    /// cheaper loads on lavapipe. An error where the adapter cannot ([`textures_supported`])
    /// or the grid does not fit its textures.
    Texture,
}

/// Size (width, height, depth) of the packed grid's texture: each (item, channel quad) volume
/// with a one-voxel zero border.
fn texture_size(n: usize, c: usize, [d, h, w]: [usize; 3]) -> [usize; 3] {
    [w + 2, h + 2, n * c.div_ceil(4) * (d + 2)]
}

/// Whether `gpu` can run the texture path: read-only rgba32float storage textures, and
/// subgroups of 8 (its staging shares a shader module with the texture conv kernels, which
/// use them).
pub fn textures_supported(gpu: &Gpu) -> bool {
    gpu.reads_rgba32f_storage() && gpu.has_subgroups_of_8()
}

/// Whether `sampling` reads the grid `[n, c, inp...]` from a texture on `gpu`. An empty grid
/// never does (nothing to sample, and no zero-sized texture).
fn uses_texture(gpu: &Gpu, op: &str, sampling: Sampling, n: usize, c: usize, inp: [usize; 3]) -> Result<bool> {
    if n * c * inp.iter().product::<usize>() == 0 || sampling == Sampling::Buffer {
        return Ok(false);
    }
    let size = texture_size(n, c, inp);
    let limit = gpu.limits.max_texture_dimension_3d as usize;
    // The grid's texture and the stage's (inp[2] / 4, inp[1], n * c * inp[0]); the maps' 2D
    // texture (3, n) fits whenever they do (n <= the grid texture's depth <= the 3D limit,
    // and 2D limits are at least 3D's).
    let side = size.into_iter().chain([n * c * inp[0]]).max().unwrap_or(0);
    // The packing's workgroups along x: one per 64 texel columns of a layer.
    let groups = (size[0] * size[1]).div_ceil(64);
    let fits = side <= limit && groups <= MAX_WORKGROUPS_PER_DIM as usize;
    match sampling {
        Sampling::Auto => Ok(fits && calibrated(gpu) == Operands::Textures),
        _ if !textures_supported(gpu) => Err(Error::Device(format!(
            "{op}: Sampling::Texture needs read-only rgba32float storage textures and subgroups of 8 lanes, which this adapter lacks"
        ))),
        _ if side > limit => Err(Error::Limit {
            what: format!("{op}: side of the packed grid's 3D textures (grid {inp:?}, {n} items of {c} channels)"),
            value: side as u64,
            limit: limit as u64,
            name: "max_texture_dimension_3d",
        }),
        _ if !fits => Err(Error::Limit {
            what: format!("{op}: workgroups of the grid's packing (grid {inp:?})"),
            value: groups as u64,
            limit: MAX_WORKGROUPS_PER_DIM as u64,
            name: "max_compute_workgroups_per_dimension",
        }),
        _ => Ok(true),
    }
}

/// `x` ([n, c, inp...]) staged 4 voxels along W a texel, as the direct conv kernels stage
/// their input (`ops::conv_pack::stage_x`: through uniform windows where they pay), for
/// `resample_pack` to read.
fn stage(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, n: usize, c: usize, inp: [usize; 3], x: &Tensor) -> Result<wgpu::TextureView> {
    let g = Geometry { n, ci: c, co: c, input: inp, output: inp, kernel: [1; 3], stride: [1; 3], pad: [0; 3], rank: 5 };
    let u = |v: usize| v as u32;
    let p = conv::Params { n: u(n), ci: u(c), id: u(inp[0]), ih: u(inp[1]), iw: u(inp[2]), ..Default::default() };
    conv_pack::stage_x(gpu, pass, &g, x, &p)
}

/// The texture path's operands: the packed grid (3D) and each item's sampling map (2D, 3
/// texels an item), both written by `resample_pack` (or `resample_pack1`).
struct Packed {
    grid: wgpu::TextureView,
    map: wgpu::TextureView,
}

impl Packed {
    /// `x` packed into scratch textures (see `resample_pack` in the shader); `params` are the
    /// dispatch's, with `x`'s sizes. In a run whose backward wants the pose's gradient, the
    /// forward's packing (the grid from `x`, the sampling map from `pose`) is kept and the pose
    /// gradient reads it instead of packing both again (`Gpu::operand_texture`, gpu/kept.rs).
    fn new(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, params: &Params, pose: &Tensor, x: &Tensor) -> Result<Packed> {
        let (n, c) = (params.n as usize, params.c as usize);
        let [d, h, w] = params.inp.map(|v| v as usize);
        let key = bytemuck::bytes_of(params);
        let (grid, has_grid) = gpu.operand_texture(x, b'g', key, texture_size(n, c, [d, h, w]), wgpu::TextureDimension::D3);
        let (map, has_map) = gpu.operand_texture(pose, b'm', key, [3, n, 1], wgpu::TextureDimension::D2);
        if has_grid && has_map {
            return Ok(Packed { grid, map });
        }
        let stage = stage(gpu, pass, n, c, [d, h, w], x)?;
        let read = Arg::ReadStorageTexture(&stage, wgpu::TextureViewDimension::D3);
        let map_arg = Arg::StorageTexture(&map, wgpu::TextureViewDimension::D2);
        let groups = [((w + 2) * (h + 2)).div_ceil(64) as u32, 1, (n * c.div_ceil(4)) as u32];
        conv_pack::write_texels(
            gpu,
            pass,
            &grid,
            |pass, staging| gpu.dispatch(pass, SHADER, entry(c, "resample_pack_buf"), params, &[Arg::R(pose), read, Arg::W(staging), map_arg], groups),
            |pass| {
                let args = [Arg::R(pose), read, Arg::StorageTexture(&grid, wgpu::TextureViewDimension::D3), map_arg];
                gpu.dispatch(pass, SHADER, entry(c, "resample_pack"), params, &args, groups)
            },
        )?;
        Ok(Packed { grid, map })
    }

    fn grid_arg(&self) -> Arg<'_> {
        Arg::ReadStorageTexture(&self.grid, wgpu::TextureViewDimension::D3)
    }
}

/// `y[n, c] = x[n, c]` resampled under `pose[n]`: trilinear, zero outside the input.
/// `x` is `[N, C, D, H, W]`, `pose` `[N, 6]`, `y` `[N, C, Do, Ho, Wo]` (any output size; the
/// paper embeds 64³ into 128³ so a rotated object is not cut off).
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, pose: &Tensor, y: &Tensor) -> Result<()> {
    forward_with(gpu, pass, x, pose, y, Sampling::Auto)
}

/// [`forward`], reading the grid as `sampling` says.
pub fn forward_with(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, pose: &Tensor, y: &Tensor, sampling: Sampling) -> Result<()> {
    let op = "resample_forward";
    let nc = check_grid_pose(op, "x", x, pose)?;
    check_nc(op, "y", y, nc)?;
    let params = Params::new(nc.0, nc.1, &x.shape()[2..], &y.shape()[2..]);
    let threads = nc.0 as u64 * y.shape()[2..].iter().product::<usize>() as u64;
    if !uses_texture(gpu, op, sampling, nc.0, nc.1, params.inp.map(|v| v as usize))? {
        return gpu.dispatch(pass, SHADER, "resample_forward", &params, &[Arg::R(pose), Arg::R(x), Arg::W(y)], grid_1d(threads, 64)?);
    }
    let tex = Packed::new(gpu, pass, &params, pose, x)?;
    let args = [Arg::R(pose), tex.grid_arg(), Arg::W(y), Arg::ReadStorageTexture(&tex.map, wgpu::TextureViewDimension::D2)];
    let rows = (params.out[0] * params.out[1]) as u64;
    gpu.dispatch(pass, SHADER, entry(nc.1, "resample_forward_tex"), &params, &args, per_item_grid(rows, nc.0)?)
}

/// The texture path's entry point `name` for `c` channels: its "1" twin for one channel, which
/// packs each texel with a cell's 4 corners instead of 4 channels (see the shader).
fn entry(c: usize, name: &'static str) -> &'static str {
    match (c, name) {
        (1, "resample_pack") => "resample_pack1",
        (1, "resample_pack_buf") => "resample_pack1_buf",
        (1, "resample_forward_tex") => "resample_forward_tex1",
        (1, "resample_backward_pose_tex") => "resample_backward_pose_tex1",
        _ => name,
    }
}

/// The texture kernels' grid: `per_item` invocations (one per output row) of each of `n`
/// items, the item along z.
fn per_item_grid(per_item: u64, n: usize) -> Result<[u32; 3]> {
    let [x, y, _] = grid_1d(per_item, 64)?;
    let z = u32::try_from(n).ok().filter(|&z| z <= MAX_WORKGROUPS_PER_DIM).ok_or_else(|| Error::Limit {
        what: "resample: batch items (workgroups along z)".into(),
        value: n as u64,
        limit: MAX_WORKGROUPS_PER_DIM as u64,
        name: "max_compute_workgroups_per_dimension",
    })?;
    Ok([x, y, z])
}

/// Writes `dx`, the gradient w.r.t. the input grid, from the output gradient `dy`. `dx`'s shape
/// gives the input grid size. A deterministic gather (no atomics): each input voxel scans the
/// output voxels whose samples can fall within one voxel of it, a box of about
/// `(2 s sqrt(3) + 1)³` outputs at worst.
pub fn backward_input(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, pose: &Tensor, dy: &Tensor, dx: &Tensor) -> Result<()> {
    let op = "resample_backward_input";
    let nc = check_grid_pose(op, "dy", dy, pose)?;
    check_nc(op, "dx", dx, nc)?;
    let params = Params::new(nc.0, nc.1, &dx.shape()[2..], &dy.shape()[2..]);
    let args = [Arg::R(pose), Arg::R(dy), Arg::W(dx)];
    gpu.dispatch(pass, SHADER, "resample_backward_input", &params, &args, grid_1d(dx.numel() as u64, 64)?)
}

/// Writes `dpose` `[N, 6]`, the gradient w.r.t. the pose, from the forward input `x` and the
/// output gradient `dy`. Per-voxel partials (per output row on the texture path) go to an
/// internal `[N*6, columns]` scratch tensor, summed deterministically by
/// [`reduce::sum_outer_inner`], so reruns are bit-identical.
pub fn backward_pose(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, pose: &Tensor, dy: &Tensor, dpose: &Tensor) -> Result<()> {
    backward_pose_with(gpu, pass, x, pose, dy, dpose, Sampling::Auto)
}

/// [`backward_pose`], reading the grid as `sampling` says.
pub fn backward_pose_with(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    pose: &Tensor,
    dy: &Tensor,
    dpose: &Tensor,
    sampling: Sampling,
) -> Result<()> {
    let op = "resample_backward_pose";
    let nc = check_grid_pose(op, "x", x, pose)?;
    check_nc(op, "dy", dy, nc)?;
    expect_shape(op, "dpose", dpose, &[nc.0, POSE_LEN])?;
    let params = Params::new(nc.0, nc.1, &x.shape()[2..], &dy.shape()[2..]);
    let [od, oh, ow] = params.out.map(|v| v as usize);
    // Columns of the partials: one per output voxel, or per output row on the texture path.
    let (scratch, cols) = if uses_texture(gpu, op, sampling, nc.0, nc.1, params.inp.map(|v| v as usize))? {
        let scratch = gpu.scratch(&[nc.0 * POSE_LEN, od * oh])?;
        let tex = Packed::new(gpu, pass, &params, pose, x)?;
        let args = [Arg::R(pose), tex.grid_arg(), Arg::R(dy), Arg::W(&scratch)];
        gpu.dispatch(pass, SHADER, entry(nc.1, "resample_backward_pose_tex"), &params, &args, per_item_grid((od * oh) as u64, nc.0)?)?;
        (scratch, od * oh)
    } else {
        let scratch = gpu.scratch(&[nc.0 * POSE_LEN, od * oh * ow])?;
        let args = [Arg::R(pose), Arg::R(x), Arg::R(dy), Arg::W(&scratch)];
        gpu.dispatch(pass, SHADER, "resample_backward_pose", &params, &args, grid_1d((nc.0 * od * oh * ow) as u64, 64)?)?;
        (scratch, od * oh * ow)
    };
    reduce::sum_outer_inner(gpu, pass, &scratch, [1, nc.0 * POSE_LEN, cols], 1.0, dpose)
}
