//! Solid voxelisation of triangle meshes, the way binvox made ShapeNet's grids: scale the mesh
//! so its bounding box's longest side spans the grid, mark every voxel a triangle touches
//! (exact triangle/box overlap), then flood-fill the empty space from the grid border. Whatever
//! the fill cannot reach is solid, so multi-part meshes with open seams or interpenetrating
//! parts still come out solid, as long as the parts together enclose their inside.
//!
//! That gives binary occupancy, whose 0.5 iso-surface is a staircase: rendered smooth it
//! shows voxel steps as rings (Phong) and spurious crease lines (toon, contour). With
//! [`VoxelizeOptions::supersample`] `k > 1` the mesh is voxelised as above at `k N` and
//! box-filtered down to `N` (each voxel = the solid fraction of its `k^3` sub-voxels, exactly
//! what [`VoxelGrid::resample_to`] computes when shrinking), so occupancy is fractional at the
//! surface and the iso-surface follows the mesh to within about `1/k` voxel.

use super::{Mesh, VoxelError, VoxelGrid, check_dims};
use glam::DVec3;

/// Fraction of a voxel the normalised bounding box is shrunk by on each side, so extreme
/// faces that would land exactly on a voxel boundary do not also mark the neighbour outside.
const BOUNDARY_EPS: f64 = 1e-4;

/// Voxeliser settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelizeOptions {
    /// Grid side N; the result is `N^3`.
    pub resolution: usize,
    /// Empty voxels kept between the bounding box's longest side and the grid border
    /// (0 = touch the border, as binvox and the RenderNet data do).
    pub margin: f32,
    /// Fill the inside (true) or keep only the surface shell (false).
    pub fill: bool,
    /// Anti-aliasing: sub-voxels per axis (`k`); `1` gives binvox's binary occupancy, `k > 1`
    /// fractional occupancy at the surface. The default is 1 so grids (and `.binvox` files
    /// written from them) stay what binvox makes; everything that renders a mesh uses
    /// [`VoxelizeOptions::smooth`] ([`SMOOTH_SUPERSAMPLE`]). `k` is lowered as needed to keep
    /// the fine grid within [`MAX_FINE_SIDE`] (0 counts as 1).
    pub supersample: usize,
}

/// Sub-voxels per axis of [`VoxelizeOptions::smooth`]: at 4 the staircase left after the box
/// filter is a quarter voxel, below what the renderer's trilinear iso-surface shows as rings,
/// and a 64^3 grid costs a 256^3 voxelisation (well under a second for the bunny).
pub const SMOOTH_SUPERSAMPLE: usize = 4;

/// Largest fine-grid side the anti-aliased voxeliser uses; it bounds memory (two bytes a fine
/// voxel plus the fill stack, about 0.4 GB at 512^3), so a 128^3 grid gets `k = 4` and a
/// 256^3 grid `k = 2`.
pub const MAX_FINE_SIDE: usize = 512;

impl Default for VoxelizeOptions {
    fn default() -> Self {
        VoxelizeOptions {
            resolution: 64,
            margin: 0.0,
            fill: true,
            supersample: 1,
        }
    }
}

impl VoxelizeOptions {
    /// Solid, no margin, anti-aliased with [`SMOOTH_SUPERSAMPLE`]: the grid to render a mesh from.
    pub fn smooth(resolution: usize) -> Self {
        VoxelizeOptions {
            resolution,
            supersample: SMOOTH_SUPERSAMPLE,
            ..Default::default()
        }
    }

    /// The sub-voxel factor actually used: `supersample` (at least 1), lowered so the fine
    /// grid side stays within [`MAX_FINE_SIDE`] (never below 1).
    pub fn effective_supersample(&self) -> usize {
        let cap = (MAX_FINE_SIDE / self.resolution.max(1)).max(1);
        self.supersample.clamp(1, cap)
    }
}

/// The similarity transform from mesh coordinates to voxel coordinates (voxel `i` spans
/// `[i, i+1)` on each axis): `voxel = (p - center) * scale + N/2`. The reference renderer
/// needs it to draw a mesh aligned with its grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normalization {
    /// Centre of the mesh's bounding box (world units).
    pub center: [f64; 3],
    /// Voxels per world unit.
    pub scale: f64,
    /// Grid side N.
    pub resolution: usize,
}

impl Normalization {
    /// Fits the mesh's bounding box into the grid, centred, longest side = `N - 2 * margin`.
    pub fn fit(mesh: &Mesh, opts: &VoxelizeOptions) -> Result<Self, VoxelError> {
        let what = "voxelize";
        let n = opts.resolution;
        check_dims(what, [n, n, n])?;
        let (lo, hi) = mesh
            .bounds()
            .ok_or_else(|| VoxelError::invalid(what, "mesh has no vertices"))?;
        let longest = (hi - lo).max_element() as f64;
        let avail = n as f64 - 2.0 * opts.margin as f64 - 2.0 * BOUNDARY_EPS;
        if longest.is_nan() || longest <= 0.0 {
            return Err(VoxelError::invalid(what, "mesh bounding box has zero size"));
        }
        if avail.is_nan() || avail <= 0.0 {
            return Err(VoxelError::invalid(
                what,
                format!("margin {} leaves no room in a grid of {n}", opts.margin),
            ));
        }
        let center = ((lo + hi) * 0.5).as_dvec3().to_array();
        Ok(Normalization {
            center,
            scale: avail / longest,
            resolution: n,
        })
    }

    /// Maps a mesh point to voxel coordinates.
    pub fn to_voxel(&self, p: [f32; 3]) -> [f64; 3] {
        let v = (DVec3::from(p.map(f64::from)) - DVec3::from(self.center)) * self.scale
            + DVec3::splat(self.resolution as f64 / 2.0);
        v.to_array()
    }
}

/// Voxelises a mesh into an `N^3` grid (axes as in [`super`]): 0/1 occupancy, or with
/// `supersample > 1` the solid fraction of each voxel's sub-voxels. The frame is the same
/// either way ([`Normalization::fit`] of `opts`, to within `1e-4` voxel).
pub fn voxelize(mesh: &Mesh, opts: &VoxelizeOptions) -> Result<VoxelGrid, VoxelError> {
    mesh.validate("voxelize")?;
    Normalization::fit(mesh, opts)?; // validates the coarse grid and margin
    let n = opts.resolution;
    let k = opts.effective_supersample();
    let fine = VoxelizeOptions {
        resolution: n * k,
        margin: opts.margin * k as f32,
        ..*opts
    };
    let norm = Normalization::fit(mesh, &fine)?;
    let surface = mark_surface(mesh, &norm);
    if !opts.fill {
        return with_mesh_colour(VoxelGrid::new([n, n, n], box_downsample(&surface, None, n, k))?, mesh, opts);
    }
    let solid = fill_from_outside(&surface, [n * k; 3]);
    let mut occ = box_downsample(&solid, Some(&surface), n, k);
    if k > 1 {
        keep_thin_parts(&mut occ, n);
    }
    with_mesh_colour(VoxelGrid::new([n, n, n], occ)?, mesh, opts)
}

/// The grid with the mesh's vertex colours ([`super::mesh_colour`]), when it has some.
fn with_mesh_colour(grid: VoxelGrid, mesh: &Mesh, opts: &VoxelizeOptions) -> Result<VoxelGrid, VoxelError> {
    if mesh.colours.is_empty() {
        return Ok(grid);
    }
    let colour = super::mesh_colour::colour_grid(mesh, &Normalization::fit(mesh, opts)?, grid.occupancy());
    grid.with_colour(colour)
}

/// Occupancy [`keep_thin_parts`] raises thin-part voxels to: their iso-surface then sits
/// about 0.3 voxel from the voxel centre, so a part thinner than a voxel renders about half
/// a voxel thick instead of vanishing.
pub const THIN_PART_OCCUPANCY: f32 = 0.7;

/// Box filtering fades parts thinner than about a voxel (chair legs and slats at 64^3) below
/// the renderer's 0.5 iso-level, so they vanish, where binvox's binary voxelisation would
/// keep them. A partly filled voxel none of whose 6 neighbours reaches 0.5 is part of such a
/// thin part (a surface voxel of a thick part has a neighbour inside it, >= 0.5); unless it
/// is the faint halo of a fuller neighbour (less than half that neighbour's fraction), it is
/// raised to [`THIN_PART_OCCUPANCY`], so slanted legs stay continuous.
fn keep_thin_parts(occ: &mut [f32], n: usize) {
    let src = occ.to_vec();
    let at = |z: usize, y: usize, x: usize| src[(z * n + y) * n + x];
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let f = at(z, y, x);
                if f <= 0.0 || f >= THIN_PART_OCCUPANCY {
                    continue;
                }
                let mut nb = Vec::with_capacity(6);
                if z > 0 { nb.push(at(z - 1, y, x)); }
                if z + 1 < n { nb.push(at(z + 1, y, x)); }
                if y > 0 { nb.push(at(z, y - 1, x)); }
                if y + 1 < n { nb.push(at(z, y + 1, x)); }
                if x > 0 { nb.push(at(z, y, x - 1)); }
                if x + 1 < n { nb.push(at(z, y, x + 1)); }
                let most = nb.iter().fold(0.0f32, |a, &v| a.max(v));
                if most < 0.5 && f >= 0.5 * most {
                    occ[(z * n + y) * n + x] = THIN_PART_OCCUPANCY;
                }
            }
        }
    }
}

/// The box filter from a `(k n)^3` cell grid to `n^3`: each voxel is the mean of its `k^3`
/// cells (what [`VoxelGrid::resample_to`] computes when shrinking), counted in integers so it
/// is exact. With `k > 1`, cells in `half` (the surface) count 1/2: a surface through a cell
/// leaves half of it inside on average, so the conservative marking, which would otherwise
/// grow the solid by ~3/8 of a cell everywhere, leaves the volume unbiased. `k = 1` stays 0/1.
fn box_downsample(cells: &[bool], half: Option<&[bool]>, n: usize, k: usize) -> Vec<f32> {
    if k == 1 {
        return cells.iter().map(|&c| c as u8 as f32).collect();
    }
    let f = n * k;
    let mut counts = vec![0u32; n * n * n]; // in half cells
    for (i, &c) in cells.iter().enumerate() {
        if c {
            let (z, y, x) = (i / (f * f), (i / f) % f, i % f);
            let w = if half.is_some_and(|h| h[i]) { 1 } else { 2 };
            counts[((z / k) * n + y / k) * n + x / k] += w;
        }
    }
    let inv = 0.5 / (k * k * k) as f32;
    counts.into_iter().map(|c| c as f32 * inv).collect()
}

/// Walks the cells of an `n^3` grid inside the bounds of triangle `v` (voxel coordinates),
/// calling `visit(index, centre, overlaps)`; `overlaps()` runs the exact triangle/cell test,
/// so a caller that already knows a cell's answer can skip it. Triangles wholly outside the
/// grid visit nothing. Shared by the voxeliser and the colour splat (`mesh_colour`).
pub(crate) fn for_each_cell_near(v: &[DVec3; 3], n: usize, mut visit: impl FnMut(usize, DVec3, &dyn Fn() -> bool)) {
    let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
    if hi.cmplt(DVec3::ZERO).any() || lo.cmpgt(DVec3::splat(n as f64)).any() {
        return;
    }
    let clamp = |x: f64| (x.floor().max(0.0) as usize).min(n - 1);
    for d in clamp(lo.x)..=clamp(hi.x) {
        for h in clamp(lo.y)..=clamp(hi.y) {
            for w in clamp(lo.z)..=clamp(hi.z) {
                let centre = DVec3::new(d as f64, h as f64, w as f64) + 0.5;
                visit((d * n + h) * n + w, centre, &|| triangle_overlaps_box(v, centre, 0.5));
            }
        }
    }
}

/// Marks every voxel that a triangle touches, testing only voxels in the triangle's bounds.
fn mark_surface(mesh: &Mesh, norm: &Normalization) -> Vec<bool> {
    let n = norm.resolution;
    let mut cells = vec![false; n * n * n];
    for t in &mesh.triangles {
        let v = t.map(|i| DVec3::from(norm.to_voxel(mesh.positions[i as usize])));
        for_each_cell_near(&v, n, |i, _, overlaps| {
            if !cells[i] && overlaps() {
                cells[i] = true;
            }
        });
    }
    cells
}

/// Exact triangle / axis-aligned cube overlap by the separating axis theorem
/// (Akenine-Möller 2001): the three box normals, the triangle normal and the nine
/// edge-by-axis cross products. Touching counts as overlapping.
pub fn triangle_overlaps_box(tri: &[DVec3; 3], center: DVec3, half: f64) -> bool {
    let v = tri.map(|p| p - center);
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: DVec3| {
        let p = v.map(|q| q.dot(axis));
        let r = half * axis.abs().element_sum();
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    let units = [DVec3::X, DVec3::Y, DVec3::Z];
    if units.iter().any(|&a| separated(a)) || separated(edges[0].cross(edges[1])) {
        return false;
    }
    !units
        .iter()
        .any(|&a| edges.iter().any(|&e| separated(a.cross(e))))
}

/// Flood-fills empty cells 6-connected from the grid border; returns `true` for every cell the
/// fill did not reach (the marked cells and everything they enclose).
pub fn fill_from_outside(marked: &[bool], dims: [usize; 3]) -> Vec<bool> {
    let [d, h, w] = dims;
    let idx = |z: usize, y: usize, x: usize| (z * h + y) * w + x;
    let mut outside = vec![false; marked.len()];
    // u32 indices halve the stack of a large (anti-aliasing) fill; MAX_VOXELS < 2^32.
    let mut stack: Vec<u32> = Vec::new();
    let visit = |i: usize, outside: &mut Vec<bool>, stack: &mut Vec<u32>| {
        if !marked[i] && !outside[i] {
            outside[i] = true;
            stack.push(i as u32);
        }
    };
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                if z == 0 || y == 0 || x == 0 || z == d - 1 || y == h - 1 || x == w - 1 {
                    visit(idx(z, y, x), &mut outside, &mut stack);
                }
            }
        }
    }
    while let Some(i) = stack.pop() {
        let i = i as usize;
        let (z, y, x) = (i / (h * w), (i / w) % h, i % w);
        if z > 0 {
            visit(i - h * w, &mut outside, &mut stack);
        }
        if z + 1 < d {
            visit(i + h * w, &mut outside, &mut stack);
        }
        if y > 0 {
            visit(i - w, &mut outside, &mut stack);
        }
        if y + 1 < h {
            visit(i + w, &mut outside, &mut stack);
        }
        if x > 0 {
            visit(i - 1, &mut outside, &mut stack);
        }
        if x + 1 < w {
            visit(i + 1, &mut outside, &mut stack);
        }
    }
    outside.iter().map(|&o| !o).collect()
}
