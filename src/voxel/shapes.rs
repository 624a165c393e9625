//! Procedural shapes: chairs, tables, sofas, CSG primitives and creatures built from analytic solids,
//! deterministic from a `u64` seed. They stand in for ShapeNet, which is not reachable here.
//!
//! A [`Shape`] is an ordered list of solids, each added (union) or carved (difference) in turn.
//! Shapes are normalised into the cube `[-1, 1]^3`, centred, longest side exactly 2, y up and
//! the front facing +z; [`Shape::to_grid`] maps that cube onto the grid
//! (`voxel = (p + 1) * n / 2`, axes as in [`super`]) and [`Shape::to_mesh`] returns triangles in
//! the same frame, so a mesh renderer and the voxel grid line up without further transforms.

mod creature;
mod families;
mod paint;

pub use creature::creature;
pub use families::{chair, primitive, sofa, table};
pub use paint::{Paint, Pattern, TEXTURE_CODE};

use super::{Mesh, VoxelError, VoxelGrid, check_dims};
use glam::{Mat3, Vec3};


/// An analytic solid.
#[derive(Clone, Debug, PartialEq)]
pub enum Solid {
    /// Oriented box: `rot` maps local axes to world; `half` are the half extents.
    Cuboid {
        /// Centre.
        center: Vec3,
        /// Half extents along the local axes.
        half: Vec3,
        /// Local-to-world rotation.
        rot: Mat3,
    },
    /// Cone frustum (a cylinder when the radii match) from `a` (radius `ra`) to `b` (`rb`).
    Frustum {
        /// Centre of the first cap.
        a: Vec3,
        /// Centre of the second cap.
        b: Vec3,
        /// Radius at `a`.
        ra: f32,
        /// Radius at `b`.
        rb: f32,
    },
    /// Ellipsoid: `rot` maps local axes to world; `radii` are the semi-axes along them.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along the local axes.
        radii: Vec3,
        /// Local-to-world rotation.
        rot: Mat3,
    },
    /// Ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}

impl Solid {
    /// Axis-aligned box with corners `lo`, `hi`.
    pub fn aabb_box(lo: Vec3, hi: Vec3) -> Solid {
        Solid::Cuboid {
            center: (lo + hi) * 0.5,
            half: (hi - lo).abs() * 0.5,
            rot: Mat3::IDENTITY,
        }
    }

    /// Whether `p` lies inside (boundary included).
    pub fn contains(&self, p: Vec3) -> bool {
        match *self {
            Solid::Cuboid { center, half, rot } => {
                (rot.transpose() * (p - center)).abs().cmple(half).all()
            }
            Solid::Frustum { a, b, ra, rb } => {
                let axis = b - a;
                let len2 = axis.length_squared();
                let t = if len2 > 0.0 {
                    (p - a).dot(axis) / len2
                } else {
                    -1.0
                };
                (0.0..=1.0).contains(&t) && (p - a - axis * t).length() <= ra + (rb - ra) * t
            }
            Solid::Ellipsoid { center, radii, rot } => {
                ((rot.transpose() * (p - center)) / radii).length_squared() <= 1.0
            }
            Solid::Sphere { center, radius } => p.distance_squared(center) <= radius * radius,
        }
    }

    /// Exact axis-aligned bounds.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match *self {
            Solid::Cuboid { center, half, rot } => {
                let abs = Mat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
                let e = abs * half;
                (center - e, center + e)
            }
            Solid::Frustum { a, b, ra, rb } => {
                // A disc of radius r with unit normal n extends r * sqrt(1 - n_i^2) along axis i.
                let n = (b - a).normalize_or_zero();
                let ext = (Vec3::ONE - n * n).max(Vec3::ZERO).map(f32::sqrt);
                (
                    (a - ext * ra).min(b - ext * rb),
                    (a + ext * ra).max(b + ext * rb),
                )
            }
            Solid::Ellipsoid { center, radii, rot } => {
                // Along world axis i: sqrt(sum_j (rot_ij radii_j)^2).
                let m = rot * Mat3::from_diagonal(radii);
                let e = Vec3::new(m.row(0).length(), m.row(1).length(), m.row(2).length());
                (center - e, center + e)
            }
            Solid::Sphere { center, radius } => {
                (center - Vec3::splat(radius), center + Vec3::splat(radius))
            }
        }
    }

    /// The solid under `p -> p * s + t`.
    fn transformed(&self, s: f32, t: Vec3) -> Solid {
        match *self {
            Solid::Cuboid { center, half, rot } => Solid::Cuboid {
                center: center * s + t,
                half: half * s,
                rot,
            },
            Solid::Frustum { a, b, ra, rb } => Solid::Frustum {
                a: a * s + t,
                b: b * s + t,
                ra: ra * s,
                rb: rb * s,
            },
            Solid::Ellipsoid { center, radii, rot } => Solid::Ellipsoid {
                center: center * s + t,
                radii: radii * s,
                rot,
            },
            Solid::Sphere { center, radius } => Solid::Sphere {
                center: center * s + t,
                radius: radius * s,
            },
        }
    }

    /// Triangle mesh of the solid (cylinders with 16 sides, spheres 24 x 12).
    pub fn to_mesh(&self) -> Mesh {
        match *self {
            Solid::Cuboid { center, half, rot } => Mesh::cuboid(center, half, rot),
            Solid::Frustum { a, b, ra, rb } => Mesh::frustum(a, b, ra, rb, 16),
            Solid::Ellipsoid { center, radii, rot } => {
                let mut m = Mesh::uv_sphere(Vec3::ZERO, 1.0, 24, 12);
                for p in &mut m.positions {
                    *p = (center + rot * (Vec3::from(*p) * radii)).to_array();
                }
                m
            }
            Solid::Sphere { center, radius } => Mesh::uv_sphere(center, radius, 24, 12),
        }
    }
}

/// How a solid combines with everything before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// Add the solid.
    Union,
    /// Carve the solid away.
    Difference,
}

/// Shape families the generator knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Seat, back (panel or slats), four legs (straight, tapered or splayed), optional arms and
    /// stretchers.
    Chair,
    /// Rectangular or round top on four legs or a pedestal, optional shelf or apron.
    Table,
    /// Base, cushions, back, arms, optional feet.
    Sofa,
    /// Unions and differences of boxes, spheres and cylinders.
    Primitive,
    /// Curved, animal-like bodies: an ellipsoid body with legs, neck, head and tail, or a
    /// cluster of ellipsoids (a rock, a head, a crouching animal).
    Creature,
}

impl Family {
    /// The four families of `dataset --shapes mixed`, in its order (furniture and CSG
    /// primitives: every surface flat, cylindrical, conical or spherical).
    pub const ALL: [Family; 4] = [
        Family::Chair,
        Family::Table,
        Family::Sofa,
        Family::Primitive,
    ];

    /// Every family, in the order of `dataset --shapes varied`: [`Family::ALL`], then
    /// [`Family::Creature`].
    pub const VARIED: [Family; 5] = [
        Family::Chair,
        Family::Table,
        Family::Sofa,
        Family::Primitive,
        Family::Creature,
    ];

    /// The shape of this family for `seed`.
    pub fn generate(self, seed: u64) -> Shape {
        match self {
            Family::Chair => chair(seed),
            Family::Table => table(seed),
            Family::Sofa => sofa(seed),
            Family::Primitive => primitive(seed),
            Family::Creature => creature(seed),
        }
    }
}

/// Axis-aligned bounds of the added (union) solids of `parts`.
fn added_bounds(parts: &[(Op, Solid)]) -> (Vec3, Vec3) {
    parts
        .iter()
        .filter(|(op, _)| *op == Op::Union)
        .map(|(_, s)| s.bounds())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
}

/// A procedural shape: solids applied in order, normalised into `[-1, 1]^3`.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    /// The family it was generated from.
    pub family: Family,
    /// Solids and how each combines with the ones before it.
    pub parts: Vec<(Op, Solid)>,
}

impl Shape {
    /// Builds a shape from parts in any units and normalises it (see the module docs); the
    /// bounds are those of the added solids, as carving can only shrink the shape.
    pub fn new(family: Family, parts: Vec<(Op, Solid)>) -> Shape {
        let (lo, hi) = added_bounds(&parts);
        let longest = (hi - lo).max_element();
        if !(longest.is_finite() && longest > 0.0) {
            return Shape { family, parts };
        }
        let s = 2.0 / longest;
        let t = -(lo + hi) * 0.5 * s;
        Shape {
            family,
            parts: parts
                .iter()
                .map(|(op, solid)| (*op, solid.transformed(s, t)))
                .collect(),
        }
    }

    /// Bounds of the added solids (carving only shrinks the shape): centred, longest side 2,
    /// once normalised.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        added_bounds(&self.parts)
    }

    /// Whether a point of the `[-1, 1]^3` frame is inside the shape.
    pub fn contains(&self, p: Vec3) -> bool {
        self.parts.iter().fold(false, |inside, (op, s)| match op {
            Op::Union => inside || s.contains(p),
            Op::Difference => inside && !s.contains(p),
        })
    }

    /// Rasterises into an `n^3` grid of 0/1 occupancy by testing each voxel centre. Each solid
    /// only visits the voxels inside its bounds, so thin parts stay cheap.
    pub fn to_grid(&self, n: usize) -> Result<VoxelGrid, VoxelError> {
        let mut grid = VoxelGrid::zeros([n, n, n])?;
        let half = n as f32 / 2.0;
        let range = |lo: f32, hi: f32| {
            let a = ((lo + 1.0) * half - 0.5).ceil().max(0.0) as usize;
            let b = (((hi + 1.0) * half - 0.5).floor() + 1.0).clamp(0.0, n as f32) as usize;
            a..b
        };
        for (op, solid) in &self.parts {
            let (lo, hi) = solid.bounds();
            let value = if *op == Op::Union { 1.0 } else { 0.0 };
            for d in range(lo.x, hi.x) {
                for h in range(lo.y, hi.y) {
                    for w in range(lo.z, hi.z) {
                        let p = (Vec3::new(d as f32, h as f32, w as f32) + 0.5) / half - 1.0;
                        if solid.contains(p) {
                            grid.set(d, h, w, value);
                        }
                    }
                }
            }
        }
        Ok(grid)
    }

    /// Like [`Shape::to_grid`] with `s^3` samples per voxel, giving fractional occupancy on the
    /// boundary (smoother edges for training targets).
    pub fn to_grid_supersampled(&self, n: usize, s: usize) -> Result<VoxelGrid, VoxelError> {
        check_dims("Shape::to_grid_supersampled", [n * s.max(1); 3])?;
        self.to_grid(n * s.max(1))?.resample_to(n)
    }

    /// A triangle mesh in the `[-1, 1]^3` frame: the union of each solid's closed surface
    /// (parts overlap, like ShapeNet models). `None` when the shape carves solids away, since
    /// that would need mesh booleans; render its grid instead.
    pub fn to_mesh(&self) -> Option<Mesh> {
        let mut mesh = Mesh::default();
        for (op, solid) in &self.parts {
            if *op == Op::Difference {
                return None;
            }
            mesh.append(&solid.to_mesh());
        }
        Some(mesh)
    }
}
