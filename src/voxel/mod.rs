//! Voxel grids and the shapes that fill them: file formats (binvox, safetensors, MagicaVoxel
//! `.vox`), triangle mesh
//! loading (OBJ, OFF, PLY), a solid voxeliser and a procedural shape generator. [`load`]
//! reads any of them by extension.
//!
//! # Axis convention
//! A [`VoxelGrid`] is indexed `[d, h, w]` (row-major, `w` fastest). Everything in this module maps
//! world axes the same way, so a mesh, its voxelisation and its binvox file agree:
//! `d` ← world **x**, `h` ← world **y** (up, as in ShapeNet), `w` ← world **z**.
//! This is the layout `binvox_rw.read_as_3d_array` (the reader the original RenderNet code used)
//! returns, i.e. `data[x][y][z]`; see [`binvox`] for how that relates to the file's byte order.

pub mod binvox;
mod load;
pub mod mesh;
mod mesh_colour;
pub mod ply;
pub mod safetensors_io;
pub mod shapes;
pub mod vox;
pub mod voxelize;

pub use binvox::Binvox;
pub use load::{BUNNY64, EXTENSIONS, bunny, load};
pub use mesh::Mesh;
pub use shapes::{Family, Shape};
pub use voxelize::{VoxelizeOptions, voxelize};

use std::fmt;

/// Largest grid side accepted anywhere (a 1024^3 f32 grid is already 4 GiB).
pub const MAX_GRID_SIDE: usize = 1024;
/// Largest voxel count accepted anywhere.
pub const MAX_VOXELS: usize = MAX_GRID_SIDE * MAX_GRID_SIDE * MAX_GRID_SIDE;
/// Largest number of triangles (after fan triangulation) a mesh may have.
pub const MAX_TRIANGLES: usize = 50_000_000;
/// Largest number of vertices a mesh may have.
pub const MAX_VERTICES: usize = 50_000_000;

/// Every failure of the voxel module. Each message names the file (or the in-memory object) and
/// the problem, so a user can act on it without a backtrace.
#[derive(Debug)]
pub enum VoxelError {
    /// The file could not be opened, read or written.
    Io {
        /// Path as the caller gave it.
        file: String,
        /// Underlying OS error.
        source: std::io::Error,
    },
    /// The content of a file is malformed.
    Malformed {
        /// Path or name of the input.
        file: String,
        /// 1-based line number for text formats; binary formats put the byte offset in `msg`.
        line: Option<usize>,
        /// What is wrong.
        msg: String,
    },
    /// A size in the input exceeds one of this module's safety limits.
    TooLarge {
        /// Path or name of the input.
        file: String,
        /// What was counted ("voxels", "faces", ...).
        what: String,
        /// The size the input asked for.
        value: u128,
        /// The limit it exceeds.
        limit: u128,
    },
    /// An in-memory argument is invalid (wrong length, out-of-range value, zero size...).
    Invalid {
        /// The object or operation concerned, e.g. `VoxelGrid::new`.
        what: String,
        /// What is wrong.
        msg: String,
    },
}

impl VoxelError {
    /// A malformed-content error at an optional 1-based line.
    pub fn malformed(file: &str, line: Option<usize>, msg: impl Into<String>) -> Self {
        VoxelError::Malformed {
            file: file.to_string(),
            line,
            msg: msg.into(),
        }
    }

    /// An I/O error for `file`.
    pub fn io(file: &str, source: std::io::Error) -> Self {
        VoxelError::Io {
            file: file.to_string(),
            source,
        }
    }

    /// An invalid-argument error for `what`.
    pub fn invalid(what: &str, msg: impl Into<String>) -> Self {
        VoxelError::Invalid {
            what: what.to_string(),
            msg: msg.into(),
        }
    }

    /// Err(TooLarge) when `value > limit`; the one place limits are enforced and worded.
    pub fn check_limit(file: &str, what: &str, value: u128, limit: u128) -> Result<(), Self> {
        if value > limit {
            return Err(VoxelError::TooLarge {
                file: file.to_string(),
                what: what.to_string(),
                value,
                limit,
            });
        }
        Ok(())
    }
}

impl fmt::Display for VoxelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VoxelError::Io { file, source } => write!(f, "{file}: {source}"),
            VoxelError::Malformed {
                file,
                line: Some(l),
                msg,
            } => write!(f, "{file} line {l}: {msg}"),
            VoxelError::Malformed {
                file,
                line: None,
                msg,
            } => write!(f, "{file}: {msg}"),
            VoxelError::TooLarge {
                file,
                what,
                value,
                limit,
            } => {
                write!(f, "{file}: {value} {what} exceeds the limit of {limit}")
            }
            VoxelError::Invalid { what, msg } => write!(f, "{what}: {msg}"),
        }
    }
}

impl std::error::Error for VoxelError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            VoxelError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Reads a whole file, naming it in the error.
pub(crate) fn read_file(path: &std::path::Path) -> Result<(String, Vec<u8>), VoxelError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| VoxelError::io(&name, e))?;
    Ok((name, bytes))
}

/// Writes a whole file, naming it in the error.
pub(crate) fn write_file(path: &std::path::Path, bytes: &[u8]) -> Result<(), VoxelError> {
    std::fs::write(path, bytes).map_err(|e| VoxelError::io(&path.display().to_string(), e))
}

/// Checks grid dimensions against the limits; `file` names the source in the error.
pub fn check_dims(file: &str, dims: [usize; 3]) -> Result<usize, VoxelError> {
    if dims.contains(&0) {
        return Err(VoxelError::malformed(
            file,
            None,
            format!("grid dimensions {dims:?} contain a zero"),
        ));
    }
    for &s in &dims {
        VoxelError::check_limit(
            file,
            "voxels along one axis",
            s as u128,
            MAX_GRID_SIDE as u128,
        )?;
    }
    let n = dims.iter().map(|&s| s as u128).product::<u128>();
    VoxelError::check_limit(file, "voxels", n, MAX_VOXELS as u128)?;
    Ok(n as usize)
}

/// A dense voxel grid: occupancy in `[0, 1]`, row-major `[D, H, W]`, and optional RGB colour
/// stored planar as `[3, D, H, W]` (the layout the network consumes, so no transpose is needed).
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid {
    dims: [usize; 3],
    occupancy: Vec<f32>,
    colour: Option<Vec<f32>>,
}

impl VoxelGrid {
    /// An empty (all zero) grid.
    pub fn zeros(dims: [usize; 3]) -> Result<Self, VoxelError> {
        let n = check_dims("VoxelGrid::zeros", dims)?;
        Ok(VoxelGrid {
            dims,
            occupancy: vec![0.0; n],
            colour: None,
        })
    }

    /// A grid from occupancy values; checks the length and that every value is in `[0, 1]`.
    pub fn new(dims: [usize; 3], occupancy: Vec<f32>) -> Result<Self, VoxelError> {
        let what = "VoxelGrid::new";
        let n = check_dims(what, dims)?;
        if occupancy.len() != n {
            return Err(VoxelError::invalid(
                what,
                format!(
                    "{} occupancy values for dims {dims:?} ({n} voxels)",
                    occupancy.len()
                ),
            ));
        }
        if let Some(i) = occupancy.iter().position(|v| !(0.0..=1.0).contains(v)) {
            return Err(VoxelError::invalid(
                what,
                format!("occupancy[{i}] = {} is outside [0, 1]", occupancy[i]),
            ));
        }
        Ok(VoxelGrid {
            dims,
            occupancy,
            colour: None,
        })
    }

    /// Attaches planar `[3, D, H, W]` colour; values must be finite.
    pub fn with_colour(mut self, colour: Vec<f32>) -> Result<Self, VoxelError> {
        let what = "VoxelGrid::with_colour";
        if colour.len() != 3 * self.len() {
            return Err(VoxelError::invalid(
                what,
                format!(
                    "{} colour values, expected 3 x {} = {}",
                    colour.len(),
                    self.len(),
                    3 * self.len()
                ),
            ));
        }
        if let Some(i) = colour.iter().position(|v| !v.is_finite()) {
            return Err(VoxelError::invalid(
                what,
                format!("colour[{i}] is not finite"),
            ));
        }
        self.colour = Some(colour);
        Ok(self)
    }

    /// Grid dimensions `[D, H, W]`.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.occupancy.len()
    }

    /// True when the grid has no voxels (never the case for a constructed grid).
    pub fn is_empty(&self) -> bool {
        self.occupancy.is_empty()
    }

    /// Occupancy values, row-major `[D, H, W]`.
    pub fn occupancy(&self) -> &[f32] {
        &self.occupancy
    }

    /// Planar colour `[3, D, H, W]`, if any.
    pub fn colour(&self) -> Option<&[f32]> {
        self.colour.as_deref()
    }

    /// Flat index of voxel `(d, h, w)`.
    pub fn index(&self, d: usize, h: usize, w: usize) -> usize {
        (d * self.dims[1] + h) * self.dims[2] + w
    }

    /// Occupancy of voxel `(d, h, w)`; panics when out of range, like slice indexing.
    pub fn get(&self, d: usize, h: usize, w: usize) -> f32 {
        self.occupancy[self.index(d, h, w)]
    }

    /// Sets the occupancy of voxel `(d, h, w)`, clamped to `[0, 1]` (NaN becomes 0) to keep
    /// the invariant.
    pub fn set(&mut self, d: usize, h: usize, w: usize, v: f32) {
        let i = self.index(d, h, w);
        self.occupancy[i] = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    }

    /// Number of voxels with occupancy >= 0.5 (the threshold binvox and IoU use).
    pub fn occupied_count(&self) -> usize {
        self.occupancy.iter().filter(|&&v| v >= 0.5).count()
    }

    /// Fraction of voxels that are occupied (>= 0.5).
    pub fn fill_fraction(&self) -> f64 {
        self.occupied_count() as f64 / self.len() as f64
    }

    /// Intersection over union of the occupied (>= 0.5) sets; `None` when dims differ.
    /// Two empty grids have IoU 1.
    pub fn iou(&self, other: &VoxelGrid) -> Option<f64> {
        if self.dims != other.dims {
            return None;
        }
        let (mut inter, mut union) = (0usize, 0usize);
        for (&a, &b) in self.occupancy.iter().zip(&other.occupancy) {
            let (a, b) = (a >= 0.5, b >= 0.5);
            inter += (a && b) as usize;
            union += (a || b) as usize;
        }
        Some(if union == 0 {
            1.0
        } else {
            inter as f64 / union as f64
        })
    }

    /// The occupancy blurred once along each axis by the `[1, 2, 1] / 4` kernel (edges
    /// clamped; colour kept): a binary grid's stair-stepped faces become ramps whose 0.5
    /// iso-surface stays where the face was but turns smoothly at its edges and corners, as
    /// a finer grid's would. Thin parts lose density (a one-voxel sheet peaks at 0.5), so
    /// callers compare the result against the original rather than assume it is better.
    pub fn smoothed(&self) -> VoxelGrid {
        let [d, h, w] = self.dims;
        let strides = [h * w, w, 1];
        let mut cur = self.occupancy.clone();
        for axis in 0..3 {
            let (n, st) = (self.dims[axis], strides[axis]);
            let next: Vec<f32> = (0..cur.len())
                .map(|i| {
                    let k = i / st % n;
                    let lo = if k > 0 { cur[i - st] } else { cur[i] };
                    let hi = if k + 1 < n { cur[i + st] } else { cur[i] };
                    0.25 * lo + 0.5 * cur[i] + 0.25 * hi
                })
                .collect();
            cur = next;
        }
        debug_assert_eq!(cur.len(), d * h * w);
        VoxelGrid { occupancy: cur, ..self.clone() }
    }

    /// Resamples to an `n^3` grid (colour too). Shrinking averages the source voxels each target
    /// voxel covers (box filter, so thin parts fade instead of vanishing); enlarging
    /// interpolates trilinearly between voxel centres with edge clamping. Axes are independent.
    pub fn resample_to(&self, n: usize) -> Result<VoxelGrid, VoxelError> {
        check_dims("VoxelGrid::resample_to", [n, n, n])?;
        let weights: Vec<_> = self.dims.iter().map(|&s| axis_weights(s, n)).collect();
        let mut out = VoxelGrid::zeros([n, n, n])?;
        out.occupancy = resample_channel(&self.occupancy, self.dims, &weights, n);
        for v in &mut out.occupancy {
            *v = v.clamp(0.0, 1.0); // guards against rounding just outside [0, 1]
        }
        if let Some(c) = &self.colour {
            let len = self.len();
            let planes: Vec<f32> = (0..3)
                .flat_map(|k| resample_channel(&c[k * len..(k + 1) * len], self.dims, &weights, n))
                .collect();
            out.colour = Some(planes);
        }
        Ok(out)
    }
}

/// For each of `dst` target cells along one axis, the source cells and weights (summing to 1).
fn axis_weights(src: usize, dst: usize) -> Vec<Vec<(usize, f32)>> {
    let ratio = src as f64 / dst as f64;
    (0..dst)
        .map(|i| {
            if ratio >= 1.0 {
                // Box filter: exact overlap of [i, i+1) * ratio with each source cell.
                let (lo, hi) = (i as f64 * ratio, (i + 1) as f64 * ratio);
                let mut ws = Vec::new();
                let mut j = lo.floor() as usize;
                while (j as f64) < hi && j < src {
                    let overlap = hi.min(j as f64 + 1.0) - lo.max(j as f64);
                    if overlap > 1e-12 {
                        ws.push((j, (overlap / ratio) as f32));
                    }
                    j += 1;
                }
                ws
            } else {
                // Trilinear: target centre mapped into source index space, clamped at the edges.
                let x = ((i as f64 + 0.5) * ratio - 0.5).clamp(0.0, (src - 1) as f64);
                let j0 = x.floor() as usize;
                let t = x - j0 as f64;
                if j0 + 1 < src && t > 0.0 {
                    vec![(j0, (1.0 - t) as f32), (j0 + 1, t as f32)]
                } else {
                    vec![(j0, 1.0)]
                }
            }
        })
        .collect()
}

/// Applies separable per-axis weights to one `[D, H, W]` channel, producing `n^3` values.
fn resample_channel(
    src: &[f32],
    dims: [usize; 3],
    weights: &[Vec<Vec<(usize, f32)>>],
    n: usize,
) -> Vec<f32> {
    let [d, h, w] = dims;
    // W axis: [d, h, w] -> [d, h, n]
    let mut a = vec![0.0f32; d * h * n];
    for row in 0..d * h {
        for (x, ws) in weights[2].iter().enumerate() {
            a[row * n + x] = ws.iter().map(|&(j, wt)| wt * src[row * w + j]).sum();
        }
    }
    // H axis: [d, h, n] -> [d, n, n]
    let mut b = vec![0.0f32; d * n * n];
    for z in 0..d {
        for (y, ws) in weights[1].iter().enumerate() {
            for x in 0..n {
                b[(z * n + y) * n + x] =
                    ws.iter().map(|&(j, wt)| wt * a[(z * h + j) * n + x]).sum();
            }
        }
    }
    // D axis: [d, n, n] -> [n, n, n]
    let mut c = vec![0.0f32; n * n * n];
    for (z, ws) in weights[0].iter().enumerate() {
        for yx in 0..n * n {
            c[z * n * n + yx] = ws.iter().map(|&(j, wt)| wt * b[j * n * n + yx]).sum();
        }
    }
    c
}
