//! Stress sweeps: how RenderNet and the conventional reference renderer degrade when the
//! grid is corrupted, coarse or crowded, or the view and light are extreme. Every image is
//! scored ([`Scores`]) against the reference renderer's image of the clean scene, so a
//! method that renders the corruption faithfully loses points just as one that breaks.

use crate::error::Result;
use crate::gpu::Gpu;
use crate::metrics::Scores;
use crate::nn::render::Renderer;
use crate::reference::{Image, Light, Options, RayMarcher, Shader, View};
use crate::voxel::VoxelGrid;
use crate::rng::SplitMix64;

/// One scored image of a sweep.
#[derive(Clone, Debug)]
pub struct Row {
    /// Sweep name (`dropout`, `salt`, `value-noise`, `downsample`, `two-objects`, `view`,
    /// `unseen`).
    pub sweep: &'static str,
    /// What varies along the sweep: a fraction, a factor, a gap in voxels, or a view index.
    pub level: f64,
    /// A word on the level (e.g. "elevation 10").
    pub label: String,
    /// `rendernet` or `reference`.
    pub method: &'static str,
    /// Scores against the reference image of the clean scene.
    pub scores: Scores,
    /// The image scored.
    pub image: Image,
}

/// One corrupted (or re-posed) scene and its clean truth.
struct Case {
    sweep: &'static str,
    level: f64,
    label: String,
    grid: VoxelGrid,
    clean: VoxelGrid,
    view: View,
    light: Light,
}

/// Occupied voxels (> 0.5) switched off with probability `p`.
pub fn dropout(g: &VoxelGrid, p: f64, seed: u64) -> VoxelGrid {
    let mut r = SplitMix64::new(seed, 0xD40F);
    map(g, |v| if v > 0.5 && (r.unit() as f64) < p { 0.0 } else { v })
}

/// Empty voxels (< 0.5) inside the occupied bounding box switched on with probability `p`.
pub fn salt(g: &VoxelGrid, p: f64, seed: u64) -> VoxelGrid {
    let [d, h, w] = g.dims();
    let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                if g.get(z, y, x) > 0.5 {
                    for (a, c) in [z, y, x].into_iter().enumerate() {
                        lo[a] = lo[a].min(c);
                        hi[a] = hi[a].max(c);
                    }
                }
            }
        }
    }
    let mut out = g.clone();
    let mut r = SplitMix64::new(seed, 0x5A17);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let inside = [z, y, x].iter().enumerate().all(|(a, &c)| c >= lo[a] && c <= hi[a]);
                if inside && g.get(z, y, x) < 0.5 && (r.unit() as f64) < p {
                    out.set(z, y, x, 1.0);
                }
            }
        }
    }
    out
}

/// Every value plus uniform noise in `[-a, a]`, clamped to `[0, 1]` (soft grids).
pub fn value_noise(g: &VoxelGrid, a: f64, seed: u64) -> VoxelGrid {
    let mut r = SplitMix64::new(seed, 0x7015);
    map(g, |v| (v + (2.0 * r.unit() - 1.0) * a as f32).clamp(0.0, 1.0))
}

/// Copies of `g` shrunk to 3/8 of its side: with `gap = None` one copy in the middle; with
/// `Some(gap)` two, side by side along W with `gap` voxels between them (negative: they
/// interpenetrate) and staggered along D, so that views from the side see one partly hide
/// the other.
pub fn copies(g: &VoxelGrid, gap: Option<i64>) -> Result<VoxelGrid> {
    let n = g.dims()[0];
    let m = 3 * n / 8;
    let small = g.resample_to(m)?;
    let mut out = VoxelGrid::zeros([n, n, n])?;
    let (c, mi) = ((n / 2) as i64, m as i64);
    let places = match gap {
        None => vec![(c - mi / 2, c - mi / 2)],
        Some(gap) => {
            let x0 = c - (2 * mi + gap) / 2;
            vec![(c - mi / 2 - mi / 4, x0), (c - mi / 2 + mi / 4, x0 + mi + gap)]
        }
    };
    for (dz, dx) in places {
        for z in 0..m {
            for y in 0..m {
                for x in 0..m {
                    let (tz, ty, tx) = (z as i64 + dz, y as i64 + c - mi / 2, x as i64 + dx);
                    if [tz, ty, tx].iter().all(|&t| (0..n as i64).contains(&t)) {
                        let (tz, ty, tx) = (tz as usize, ty as usize, tx as usize);
                        out.set(tz, ty, tx, out.get(tz, ty, tx).max(small.get(z, y, x)));
                    }
                }
            }
        }
    }
    Ok(out)
}

fn map(g: &VoxelGrid, mut f: impl FnMut(f32) -> f32) -> VoxelGrid {
    let occ: Vec<f32> = g.occupancy().iter().map(|&v| f(v)).collect();
    VoxelGrid::new(g.dims(), occ).expect("same dims")
}

/// The sweeps of issue 12 on one scene.
fn cases(grid: &VoxelGrid, view: &View, light: &Light, seed: u64) -> Result<Vec<Case>> {
    let case = |sweep, level: f64, label: String, g: VoxelGrid| Case { sweep, level, label, grid: g, clean: grid.clone(), view: *view, light: *light };
    let mut v = Vec::new();
    for p in [0.0, 0.1, 0.2, 0.3, 0.4, 0.5] {
        v.push(case("dropout", p, format!("{:.0}% dropped", 100.0 * p), dropout(grid, p, seed)));
    }
    for p in [0.0, 0.01, 0.02, 0.05, 0.1] {
        v.push(case("salt", p, format!("{:.0}% salt", 100.0 * p), salt(grid, p, seed)));
    }
    for a in [0.0, 0.1, 0.2, 0.3, 0.4] {
        v.push(case("value-noise", a, format!("noise ±{a}"), value_noise(grid, a, seed)));
    }
    let n = grid.dims()[0];
    for f in [1usize, 2, 3, 4] {
        v.push(case("downsample", f as f64, format!("{}^3", n / f), grid.resample_to(n / f)?));
    }
    // Level: the gap in voxels; the single copy (the yardstick) is level 99.
    for gap in [Some(8i64), Some(0), Some(-6), None] {
        let g = copies(grid, gap)?;
        let (level, label) = gap.map_or((99.0, "one copy".to_string()), |g| (g as f64, format!("gap {g}")));
        v.push(Case { sweep: "two-objects", level, label, clean: g.clone(), grid: g, view: *view, light: *light });
    }
    let views = [
        ("elevation 10", View { elevation: 10.0, ..*view }, *light),
        ("elevation 170", View { elevation: 170.0, ..*view }, *light),
        ("radius 3", View { radius: 3.0, ..*view }, *light),
        ("radius 6.3", View { radius: 6.3, ..*view }, *light),
        ("grazing light", *view, Light { azimuth: 88.0, elevation: 90.0, ..*light }),
    ];
    for (i, (label, vw, l)) in views.into_iter().enumerate() {
        v.push(Case { sweep: "view", level: i as f64, label: label.into(), grid: grid.clone(), clean: grid.clone(), view: vw, light: l });
    }
    Ok(v)
}

/// Runs every sweep on `grid` seen from `view` under `light`: RenderNet (`net`) and the
/// reference renderer on each corrupted grid, both scored against the reference image of
/// the clean grid. `unseen` adds the sweep `unseen`: each named shape (e.g. real meshes no
/// training set holds) clean, at the same view and light. `progress(done, total)` after
/// each case.
#[allow(clippy::too_many_arguments)]
pub fn run(
    gpu: &Gpu,
    net: &mut Renderer,
    grid: &VoxelGrid,
    view: &View,
    light: &Light,
    seed: u64,
    unseen: &[(String, VoxelGrid)],
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Row>> {
    let mut cases = cases(grid, view, light, seed)?;
    for (i, (name, g)) in unseen.iter().enumerate() {
        cases.push(Case { sweep: "unseen", level: i as f64, label: name.clone(), grid: g.clone(), clean: g.clone(), view: *view, light: *light });
    }
    let reference = RayMarcher::new(gpu).with_options(Options { supersample: 2, ..Options::default() });
    let size = net.size() as u32;
    let mut rows = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let truth = reference.render(gpu, &c.clean, &c.view, &c.light, Shader::Phong, size)?;
        let ours = net.render(gpu, &c.grid, &c.view, &c.light)?;
        let theirs = reference.render(gpu, &c.grid, &c.view, &c.light, Shader::Phong, size)?;
        for (method, image) in [("rendernet", ours), ("reference", theirs)] {
            rows.push(Row { sweep: c.sweep, level: c.level, label: c.label.clone(), method, scores: Scores::of(&image, &truth), image });
        }
        progress(k + 1, cases.len());
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16^3 grid with a solid 8^3 block in the middle.
    fn block() -> VoxelGrid {
        let mut g = VoxelGrid::zeros([16, 16, 16]).unwrap();
        for z in 4..12 {
            for y in 4..12 {
                for x in 4..12 {
                    g.set(z, y, x, 1.0);
                }
            }
        }
        g
    }

    fn mass(g: &VoxelGrid) -> f64 {
        g.occupancy().iter().map(|&v| v as f64).sum()
    }

    #[test]
    fn dropout_removes_about_p_of_the_occupied_voxels_and_adds_none() {
        let g = block();
        assert_eq!(dropout(&g, 0.0, 1).occupancy(), g.occupancy());
        let d = dropout(&g, 0.5, 1);
        let kept = mass(&d) / mass(&g);
        assert!((0.45..0.55).contains(&kept), "kept {kept}");
        assert!(d.occupancy().iter().zip(g.occupancy()).all(|(a, b)| a <= b));
    }

    #[test]
    fn salt_fills_only_empty_voxels_inside_the_box() {
        let mut g = block();
        g.set(4, 4, 4, 0.0); // one hole inside the box, the only place salt can go
        let s = salt(&g, 1.0, 2);
        assert_eq!(s.get(4, 4, 4), 1.0);
        assert_eq!(mass(&s), mass(&block()), "salt went outside the occupied box");
        assert_eq!(salt(&g, 0.0, 2).occupancy(), g.occupancy());
    }

    #[test]
    fn value_noise_stays_in_range_and_changes_values() {
        let g = block();
        let n = value_noise(&g, 0.3, 3);
        assert!(n.occupancy().iter().all(|v| (0.0..=1.0).contains(v)));
        let changed = n.occupancy().iter().zip(g.occupancy()).filter(|(a, b)| a != b).count();
        assert!(changed > g.len() / 3, "only {changed} values changed");
    }

    #[test]
    fn two_copies_hold_twice_the_mass_of_one() {
        let g = block();
        let one = mass(&copies(&g, None).unwrap());
        let two = mass(&copies(&g, Some(2)).unwrap());
        // 3/8 scale: a 3^3 block from 16 -> 6 keeps (6/16)^3 of the mass.
        assert!((one - mass(&g) * 0.052734375).abs() < 1.0, "one copy: {one}");
        assert!((two - 2.0 * one).abs() < 1e-3, "two copies {two} vs one {one}");
    }
}
