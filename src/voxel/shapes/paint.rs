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

/// Length of a texture code (see [`Paint::from_code`]).
pub const TEXTURE_CODE: usize = 9;

impl Paint {
    /// A paint as [`Shape::paints`] draws one: two saturated colours, half the time plain,
    /// a quarter striped, a quarter checkered, periods of 0.2-0.4 object units (a band at
    /// least ~3 voxels wide on a 32^3 grid).
    pub fn random(rng: &mut SplitMix64) -> Paint {
        let (a, b) = (colour(rng), colour(rng));
        let (kind, period, axis) = (rng.unit(), rng.range(0.2, 0.4), (rng.unit() * 3.0) as usize % 3);
        // The same thresholds as `from_code`, built directly so datasets keep their bytes.
        let pattern = if kind < 0.5 {
            Pattern::Plain
        } else if kind < 0.75 {
            Pattern::Stripes { axis, period }
        } else {
            Pattern::Checker { period }
        };
        Paint { a, b, pattern }
    }

    /// The paint a texture code describes, each number in [0, 1] (clamped): colour `a`
    /// (RGB), colour `b` (RGB), the pattern (below 0.5 plain, below 0.75 stripes, else a
    /// checkerboard), the period (0.2 + 0.2 u object units) and the stripes' axis (x, y, z by
    /// thirds). The texture decoder (`nn::texture`) learns to draw it.
    pub fn from_code(c: &[f32; TEXTURE_CODE]) -> Paint {
        let c = c.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) });
        let period = 0.2 + 0.2 * c[7];
        let pattern = if c[6] < 0.5 {
            Pattern::Plain
        } else if c[6] < 0.75 {
            Pattern::Stripes { axis: ((c[8] * 3.0) as usize).min(2), period }
        } else {
            Pattern::Checker { period }
        };
        Paint { a: Vec3::new(c[0], c[1], c[2]), b: Vec3::new(c[3], c[4], c[5]), pattern }
    }

    /// A code that [`Paint::from_code`] maps back to this paint (within f32 rounding).
    pub fn code(&self) -> [f32; TEXTURE_CODE] {
        let (kind, period, axis) = match self.pattern {
            Pattern::Plain => (0.25, 0.3, 0),
            Pattern::Stripes { axis, period } => (0.625, period, axis),
            Pattern::Checker { period } => (0.875, period, 0),
        };
        let (a, b) = (self.a, self.b);
        [a.x, a.y, a.z, b.x, b.y, b.z, kind, ((period - 0.2) / 0.2).clamp(0.0, 1.0), (axis as f32 + 0.5) / 3.0]
    }

    /// The paint over the whole `[-1, 1]^3` cube sampled at the centres of an `n`^3 grid's
    /// voxels: `[3, n, n, n]` (channel, d, h, w), the layout of [`VoxelGrid::colour`].
    pub fn field(&self, n: usize) -> Vec<f32> {
        let cells = n * n * n;
        let half = n as f32 / 2.0;
        let mut col = vec![0.0f32; 3 * cells];
        for i in 0..cells {
            let (d, h, w) = (i / (n * n), (i / n) % n, i % n);
            let c = self.at((Vec3::new(d as f32, h as f32, w as f32) + 0.5) / half - 1.0);
            for k in 0..3 {
                col[k * cells + i] = c[k];
            }
        }
        col
    }
}

impl Shape {
    /// The paint of each part, in order (carved parts get one too, unused), from `seed`
    /// ([`Paint::random`]).
    pub fn paints(&self, seed: u64) -> Vec<Paint> {
        let mut rng = SplitMix64::new(seed, PAINT_STREAM);
        self.parts.iter().map(|_| Paint::random(&mut rng)).collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_codes_round_trip_and_draw_their_paint() {
        let mut rng = SplitMix64::new(3, 0);
        for _ in 0..200 {
            let p = Paint::random(&mut rng);
            let q = Paint::from_code(&p.code());
            assert!((p.a - q.a).abs().max_element() < 1e-6 && (p.b - q.b).abs().max_element() < 1e-6, "{p:?} {q:?}");
            match (p.pattern, q.pattern) {
                (Pattern::Plain, Pattern::Plain) => {}
                (Pattern::Stripes { axis: a, period: x }, Pattern::Stripes { axis: b, period: y }) => assert!(a == b && (x - y).abs() < 1e-5),
                (Pattern::Checker { period: x }, Pattern::Checker { period: y }) => assert!((x - y).abs() < 1e-5),
                _ => panic!("{p:?} came back as {q:?}"),
            }
        }
        // Stripes across x (voxel axis d) of period 0.5 on an 8^3 grid: voxel centres at
        // -0.875, -0.625, ...; bands of 0.25 alternate every voxel.
        let (a, b) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
        let f = Paint { a, b, pattern: Pattern::Stripes { axis: 0, period: 0.5 } }.field(8);
        let red_at = |d: usize| f[d * 64 + 3 * 8 + 5];
        assert_eq!((0..8).map(red_at).collect::<Vec<_>>(), [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0]);
        assert!(Paint { a, b, pattern: Pattern::Plain }.field(4).chunks(64).zip([1.0, 0.0, 0.0]).all(|(c, v)| c.iter().all(|&x| x == v)));
        // Codes out of range are clamped, NaN taken as 0.
        let odd = Paint::from_code(&[2.0, -1.0, f32::NAN, 0.5, 0.5, 0.5, 0.9, 3.0, 1.0]);
        assert_eq!(odd.a, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(odd.pattern, Pattern::Checker { period: 0.4 });
    }
}
