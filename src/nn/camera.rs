//! How the network sees a grid: the axis order of its input tensor and the resampling pose
//! for a view, chosen so that the camera-aligned grid lines up with the reference renderer's
//! image (see `reference::camera` for the renderer's frames).
//!
//! The renderer maps object point `p` to camera coordinates `c = Rx(90° - el) Ry(az) p`
//! (x right, y up, z towards the camera). The network's camera grid has axes
//! `(D, H, W) = (c.z, -c.y, c.x)`: depth towards the camera, rows downwards as image rows,
//! columns rightwards. That axis map `P` is a proper rotation and its own inverse, so
//! feeding the grid with its axes permuted by `P` (input `[a, b, c]` = grid
//! `[d = c, h = H-1-b, w = a]`) leaves the resampling op with exactly its own rotation form:
//! `P Rx(t) Ry(az) P = R_el(-t) R_az(-az)` with `t = 90° - el` (checked numerically in the
//! tests). The scale puts `cam_hw * scale / 2` camera voxels per object unit (the image is
//! `2 / scale` units wide, `scale = 3.3 / radius`) and the object unit is the input's side.

use crate::reference::{Light, View};
use crate::voxel::VoxelGrid;

/// The grid as the network's input `[R, R, R]` values, axes permuted as the module says.
pub fn input_values(grid: &VoxelGrid) -> Vec<f32> {
    permuted(grid.dims(), grid.occupancy())
}

/// The input of a network with `channels` input channels ([`Preset::in_channels`]): the
/// occupancy, then for 4 channels RGB times occupancy, so that empty space is 0 in every
/// channel and resampling blends colour as it blends occupancy. A grid without colour
/// counts as white, the albedo the reference renderer gives it.
///
/// [`Preset::in_channels`]: crate::nn::rendernet::Preset::in_channels
pub fn input_values_with(grid: &VoxelGrid, channels: usize) -> Vec<f32> {
    let occ = grid.occupancy();
    let mut out = permuted(grid.dims(), occ);
    if channels == 4 {
        let n = occ.len();
        for c in 0..3 {
            let rgb: Vec<f32> = match grid.colour() {
                Some(col) => col[c * n..(c + 1) * n].iter().zip(occ).map(|(a, o)| a * o).collect(),
                None => occ.to_vec(),
            };
            out.extend(permuted(grid.dims(), &rgb));
        }
    }
    out
}

/// One channel `[D, H, W]` in the network's axis order: (a, b, c) = (w, H-1-h, d), sizes
/// (W, H, D).
fn permuted([d, h, w]: [usize; 3], v: &[f32]) -> Vec<f32> {
    let mut out = vec![0.0; d * h * w];
    for a in 0..w {
        for b in 0..h {
            for c in 0..d {
                out[(a * h + b) * d + c] = v[(c * h + (h - 1 - b)) * w + a];
            }
        }
    }
    out
}

/// The grid whose [`input_values`] are `values` (a cube of side `r`): the inverse
/// permutation, for grids a network produced in its input layout (the shape prior's decoder).
pub fn grid_from_input_values(values: &[f32], r: usize) -> crate::error::Result<VoxelGrid> {
    let mut occ = vec![0.0; r * r * r];
    for a in 0..r {
        for b in 0..r {
            for c in 0..r {
                occ[(c * r + (r - 1 - b)) * r + a] = values[(a * r + b) * r + c];
            }
        }
    }
    VoxelGrid::new([r; 3], occ).map_err(|e| crate::error::Error::Invalid(e.to_string()))
}

/// The input tensor's spatial shape for a grid of `dims` `[D, H, W]`: `[W, H, D]`.
pub fn input_dims(dims: [usize; 3]) -> [usize; 3] {
    [dims[2], dims[1], dims[0]]
}

/// The resampling pose `(scale, azimuth, elevation, t_d, t_h, t_w)` that maps an input grid
/// of side `input` into a camera grid whose image plane is `cam_hw` voxels wide, as the
/// renderer sees it from `view`. `crop` = `(h0, w0, h, w)` picks a window of the full
/// camera grid (patch training): the translation moves that window into the output.
pub fn pose_for_view(view: &View, input: usize, cam_hw: usize, crop: Option<[usize; 4]>) -> [f32; 6] {
    let k = cam_hw as f64 * view.scale() / 2.0; // camera voxels per object unit
    let s = k / input as f64;
    let az = view.azimuth.rem_euclid(360.0).to_radians();
    let t = (90.0 - view.elevation).to_radians();
    let (th, tw) = match crop {
        None => (0.0, 0.0),
        Some([h0, w0, h, w]) => {
            let centre = (cam_hw as f64 - 1.0) / 2.0;
            (centre - h0 as f64 - (h as f64 - 1.0) / 2.0, centre - w0 as f64 - (w as f64 - 1.0) / 2.0)
        }
    };
    [s as f32, -az as f32, -t as f32, 0.0, th as f32, tw as f32]
}

/// The Phong op's light `[6]`: unit direction towards the light in the camera frame, then
/// colour, from the renderer's light.
pub fn light_values(light: &Light) -> [f32; 6] {
    let d = light.direction();
    [d.x, d.y, d.z, light.colour[0], light.colour[1], light.colour[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `grid_from_input_values` undoes `input_values` on a grid with no symmetry to hide a
    /// swapped or flipped axis.
    #[test]
    fn input_layout_round_trips() {
        let r = 5;
        let occ: Vec<f32> = (0..r * r * r).map(|i| (i * 7 % 11) as f32 / 10.0).collect();
        let grid = VoxelGrid::new([r; 3], occ.clone()).unwrap();
        let back = grid_from_input_values(&input_values(&grid), r).unwrap();
        assert_eq!(back.occupancy(), &occ[..]);
    }
}
