//! Coloured procedural shapes: every added solid gets a colour and a pattern (plain, stripes
//! or a checkerboard of two colours), drawn from the shape's seed and defined in the
//! `[-1, 1]^3` frame, so the same shape paints the same at every grid resolution (the input
//! grid and the finer grid the targets are rendered from agree).

use super::{Op, Shape};
use crate::rng::SplitMix64;
use crate::voxel::{VoxelError, VoxelGrid};
use glam::Vec3;

/// Stream of the paint, apart from the geometry's.
const PAINT_STREAM: u64 = 0x5041_494e; // "PAIN"

/// How one solid is painted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pattern {
    /// One colour.
    Plain,
    /// Bands across `axis` (0 x, 1 y, 2 z), `period` object units per pair of bands.
    Stripes { axis: usize, period: f32 },
    /// Cubes of side `period / 2` in alternating colours.
    Checker { period: f32 },
}

/// The paint of one solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Paint {
    /// Main colour, RGB in [0, 1].
    pub a: Vec3,
    /// Second colour of the pattern.
    pub b: Vec3,
    /// Where each colour goes.
    pub pattern: Pattern,
}

impl Paint {
    /// The colour at `p` (object frame).
    pub fn at(&self, p: Vec3) -> Vec3 {
        let band = |x: f32, period: f32| (x / (0.5 * period)).floor().rem_euclid(2.0) as u32;
        let second = match self.pattern {
            Pattern::Plain => 0,
            Pattern::Stripes { axis, period } => band(p[axis], period),
            Pattern::Checker { period } => (band(p.x, period) + band(p.y, period) + band(p.z, period)) % 2,
        };
        if second == 1 { self.b } else { self.a }
    }
}

/// A saturated, not too dark colour (HSV with S in [0.35, 0.9], V in [0.55, 1]).
fn colour(rng: &mut SplitMix64) -> Vec3 {
    let (h, s, v) = (rng.range(0.0, 6.0), rng.range(0.35, 0.9), rng.range(0.55, 1.0));
    let f = |n: f32| {
        let k = (n + h) % 6.0;
        v - v * s * k.min(4.0 - k).clamp(0.0, 1.0)
    };
    Vec3::new(f(5.0), f(3.0), f(1.0))
}

impl Shape {
    /// The paint of each part, in order (carved parts get one too, unused), from `seed`.
    /// Half the parts are plain, a quarter striped, a quarter checkered; periods of 0.2-0.4
    /// object units keep a band at least ~3 voxels wide on a 32^3 grid.
    pub fn paints(&self, seed: u64) -> Vec<Paint> {
        let mut rng = SplitMix64::new(seed, PAINT_STREAM);
        self.parts
            .iter()
            .map(|_| {
                let (a, b) = (colour(&mut rng), colour(&mut rng));
                let (kind, period, axis) = (rng.unit(), rng.range(0.2, 0.4), (rng.unit() * 3.0) as usize % 3);
                let pattern = if kind < 0.5 {
                    Pattern::Plain
                } else if kind < 0.75 {
                    Pattern::Stripes { axis, period }
                } else {
                    Pattern::Checker { period }
                };
                Paint { a, b, pattern }
            })
            .collect()
    }

    /// [`Shape::to_grid`] with colour: each voxel takes the paint of the last added solid
    /// that covers its centre ([`Shape::paints`] of `seed`).
    pub fn to_coloured_grid(&self, n: usize, seed: u64) -> Result<VoxelGrid, VoxelError> {
        let grid = self.to_grid(n)?;
        let paints = self.paints(seed);
        let cells = n * n * n;
        let mut col = vec![0.0f32; 3 * cells];
        let half = n as f32 / 2.0;
        for d in 0..n {
            for h in 0..n {
                for w in 0..n {
                    let i = grid.index(d, h, w);
                    if grid.occupancy()[i] == 0.0 {
                        continue;
                    }
                    let p = (Vec3::new(d as f32, h as f32, w as f32) + 0.5) / half - 1.0;
                    let last = self.parts.iter().zip(&paints).rev().find(|((op, s), _)| *op == Op::Union && s.contains(p));
                    let c = last.map_or(Vec3::ONE, |(_, paint)| paint.at(p));
                    for k in 0..3 {
                        col[k * cells + i] = c[k];
                    }
                }
            }
        }
        grid.with_colour(col)
    }
}
