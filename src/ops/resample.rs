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

use super::{expect_rank, expect_shape, reduce};
use crate::error::{Result, shape_err};
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d, wgsl};

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

/// `y[n, c] = x[n, c]` resampled under `pose[n]`: trilinear, zero outside the input.
/// `x` is `[N, C, D, H, W]`, `pose` `[N, 6]`, `y` `[N, C, Do, Ho, Wo]` (any output size; the
/// paper embeds 64³ into 128³ so a rotated object is not cut off).
pub fn forward(gpu: &Gpu, pass: &mut wgpu::ComputePass<'_>, x: &Tensor, pose: &Tensor, y: &Tensor) -> Result<()> {
    let op = "resample_forward";
    let nc = check_grid_pose(op, "x", x, pose)?;
    check_nc(op, "y", y, nc)?;
    let params = Params::new(nc.0, nc.1, &x.shape()[2..], &y.shape()[2..]);
    let threads = nc.0 as u64 * y.shape()[2..].iter().product::<usize>() as u64;
    gpu.dispatch(pass, SHADER, "resample_forward", &params, &[Arg::R(pose), Arg::R(x), Arg::W(y)], grid_1d(threads, 64)?)
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
/// output gradient `dy`. Per-voxel partials go to an internal `[N*6, Do*Ho*Wo]` scratch tensor,
/// summed deterministically by [`reduce::sum_outer_inner`], so reruns are bit-identical.
pub fn backward_pose(
    gpu: &Gpu,
    pass: &mut wgpu::ComputePass<'_>,
    x: &Tensor,
    pose: &Tensor,
    dy: &Tensor,
    dpose: &Tensor,
) -> Result<()> {
    let op = "resample_backward_pose";
    let nc = check_grid_pose(op, "x", x, pose)?;
    check_nc(op, "dy", dy, nc)?;
    expect_shape(op, "dpose", dpose, &[nc.0, POSE_LEN])?;
    let vo: usize = dy.shape()[2..].iter().product();
    let scratch = gpu.scratch(&[nc.0 * POSE_LEN, vo])?;
    let params = Params::new(nc.0, nc.1, &x.shape()[2..], &dy.shape()[2..]);
    let args = [Arg::R(pose), Arg::R(x), Arg::R(dy), Arg::W(&scratch)];
    gpu.dispatch(pass, SHADER, "resample_backward_pose", &params, &args, grid_1d((nc.0 * vo) as u64, 64)?)?;
    reduce::sum_outer_inner(gpu, pass, &scratch, [1, nc.0 * POSE_LEN, vo], 1.0, dpose)
}
