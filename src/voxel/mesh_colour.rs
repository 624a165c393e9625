//! Vertex colours of a mesh carried into its voxel grid: each voxel a triangle touches takes
//! the mean of the triangle colours at the voxel centre's nearest point, then the colour
//! spreads through the solid from the surface inwards, so every occupied voxel has one (the
//! renderer weights colour by occupancy, so empty voxels need none).

use super::voxelize::{Normalization, for_each_cell_near};
use super::Mesh;
use glam::DVec3;
use std::collections::VecDeque;

/// Barycentric weights of the point of triangle `t` nearest to `p`, approximately: the
/// weights of `p`'s projection on the triangle's plane, negative ones clamped to 0 and the
/// rest renormalised (exact inside the triangle, close enough at its edges for colour).
fn weights(t: &[DVec3; 3], p: DVec3) -> [f64; 3] {
    let (e0, e1, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d00, d01, d11, d20, d21) = (e0.dot(e0), e0.dot(e1), e1.dot(e1), d.dot(e0), d.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() < 1e-18 {
        return [1.0 / 3.0; 3]; // degenerate: the mean colour
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    let b = [1.0 - v - w, v, w].map(|x| x.max(0.0));
    let s: f64 = b.iter().sum();
    b.map(|x| x / s)
}

/// Planar `[3, N, N, N]` colour for a grid of occupancy `occ` voxelised from `mesh` in frame
/// `norm` (N = `norm.resolution`). `mesh.colours` must hold one colour per vertex.
pub(crate) fn colour_grid(mesh: &Mesh, norm: &Normalization, occ: &[f32]) -> Vec<f32> {
    let n = norm.resolution;
    let cells = n * n * n;
    let (mut sum, mut count) = (vec![DVec3::ZERO; cells], vec![0u32; cells]);
    for t in &mesh.triangles {
        let v = t.map(|i| DVec3::from(norm.to_voxel(mesh.positions[i as usize])));
        let c = t.map(|i| DVec3::from(mesh.colours[i as usize].map(f64::from)));
        for_each_cell_near(&v, n, |i, centre, overlaps| {
            if overlaps() {
                let b = weights(&v, centre);
                sum[i] += c[0] * b[0] + c[1] * b[1] + c[2] * b[2];
                count[i] += 1;
            }
        });
    }
    // Breadth-first from the surface: an occupied voxel without colour takes the colour of
    // the neighbour that reached it first (the nearest surface, in 6-connected steps).
    let mut colour: Vec<Option<DVec3>> = (0..cells).map(|i| (count[i] > 0).then(|| sum[i] / count[i] as f64)).collect();
    let mut queue: VecDeque<usize> = (0..cells).filter(|&i| colour[i].is_some()).collect();
    while let Some(i) = queue.pop_front() {
        let (d, h, w) = (i / (n * n), (i / n) % n, i % n);
        let neighbours = [(d > 0, i.wrapping_sub(n * n)), (d + 1 < n, i + n * n), (h > 0, i.wrapping_sub(n)), (h + 1 < n, i + n), (w > 0, i.wrapping_sub(1)), (w + 1 < n, i + 1)];
        for (ok, j) in neighbours {
            if ok && colour[j].is_none() && occ[j] > 0.0 {
                colour[j] = colour[i];
                queue.push_back(j);
            }
        }
    }
    let mut out = vec![0.0f32; 3 * cells];
    for (i, c) in colour.iter().enumerate() {
        if let (Some(c), true) = (c, occ[i] > 0.0) {
            for k in 0..3 {
                out[k * cells + i] = c[k] as f32;
            }
        }
    }
    out
}
