//! Where the pose search starts and what it refines: opposite-side twins of the kept
//! views, the light starts, and the light polish's grid and picks.

use super::{Vars, polar_unit};

/// Light directions ranked at every distinct view before the refinement, `(azimuth,
/// elevation)` relative to the camera (degrees): the 20-degree grid of all directions (162).
/// Scored on the CPU from each view's maps, so a fine grid costs no more network work than
/// the 12 directions rendered one by one before.
pub(super) fn light_starts() -> Vec<(f64, f64)> {
    light_grid(20.0)
}

/// Grid step of the light polish after the refinement (degrees; 2592 directions).
pub(super) const POLISH_STEP_DEGREES: f64 = 5.0;

/// Light directions every `step` degrees: azimuth from 0, elevation from `step / 2` to
/// `180 - step / 2` (in the frame of [`light_starts`]; 20 gives 18 x 9 = 162 directions).
pub(super) fn light_grid(step: f64) -> Vec<(f64, f64)> {
    let (na, ne) = ((360.0 / step).round() as usize, (180.0 / step).round() as usize);
    (0..ne).flat_map(|e| (0..na).map(move |a| (step * a as f64, step / 2.0 + step * e as f64))).collect()
}

/// The first `n` of `ranked` (best first) whose lights are at least 30 degrees from every
/// light already taken: the network's light optimum is shallow, so the best few grid
/// lights are often neighbours of one another.
pub(super) fn distinct_lights(ranked: impl Iterator<Item = Vars>, n: usize) -> Vec<Vars> {
    let mut out: Vec<Vars> = Vec::new();
    for v in ranked {
        if out.len() < n && !out.iter().any(|r| within_30_degrees((r.0[3], r.0[4]), (v.0[3], v.0[4]))) {
            out.push(v);
        }
    }
    out
}

/// Lights refined by the polish after the refinement.
pub(super) const POLISHED: usize = 4;

/// Up to `keep` views from `ranked` (best silhouette first): each followed by its twin seen
/// from the opposite side (azimuth + 180 degrees), unless a kept view is already within 30
/// degrees of it. A left-right symmetric object (most chairs) casts nearly the same
/// silhouette from the front and from the back, so the silhouette score cannot tell them
/// apart; the refinement's image loss (shading) can, if both are among its starts.
pub(super) fn with_twins(ranked: impl Iterator<Item = Vars>, keep: usize) -> Vec<Vars> {
    let mut out: Vec<Vars> = Vec::new();
    let near = |a: &Vars, b: &Vars| within_30_degrees((a.0[0], a.0[1]), (b.0[0], b.0[1]));
    for v in ranked {
        for c in [v, twin(v)] {
            if out.len() < keep && !out.iter().any(|k| near(k, &c)) {
                out.push(c);
            }
        }
        if out.len() == keep {
            break;
        }
    }
    out
}

/// `v` seen from the opposite side: azimuth + 180 degrees, elevation, radius and light (relative
/// to the camera) kept. A left-right symmetric shape's silhouettes from the two coincide.
pub(super) fn twin(v: Vars) -> Vars {
    let mut t = v;
    t.0[0] = (v.0[0] + 180.0) % 360.0;
    t
}

/// The 8 views around `v` half a coarse grid step away (`daz` azimuth, `del` elevation,
/// degrees; elevations kept inside (0, 180)), radius and light kept: the paper's subdivision
/// of the start grid around its best views.
pub(super) fn neighbours(v: Vars, daz: f64, del: f64) -> Vec<Vars> {
    let mut out = Vec::with_capacity(8);
    for de in [-1.0, 0.0, 1.0] {
        for da in [-1.0, 0.0, 1.0] {
            if (da, de) != (0.0, 0.0) {
                let mut n = v;
                n.0[0] = (v.0[0] + da * daz).rem_euclid(360.0);
                n.0[1] = (v.0[1] + de * del).clamp(1.0, 179.0);
                out.push(n);
            }
        }
    }
    out
}

/// Each `(score, start)` of `pool` replaced by the best of itself and its 8 neighbours
/// (`ranked`: a best-first list of scored lights per neighbour, 8 per pool entry, as
/// [`neighbours`] gives them), then the pool sorted best first.
pub(super) fn best_of_neighbours(pool: &mut [(f64, Vars)], ranked: &[Vec<(f64, Vars)>]) {
    for (p, r) in pool.iter_mut().zip(ranked.chunks(8)) {
        for &n in r.iter().map(|x| &x[0]) {
            if n.0 < p.0 {
                *p = n;
            }
        }
    }
    pool.sort_by(|a, b| a.0.total_cmp(&b.0));
}

/// Whether directions `a` and `b` (azimuth, elevation in degrees) are within 30 degrees of
/// each other.
fn within_30_degrees(a: (f64, f64), b: (f64, f64)) -> bool {
    let (u, v) = (polar_unit(a.0, a.1), polar_unit(b.0, b.1));
    u.iter().zip(&v).map(|(x, y)| x * y).sum::<f64>() > 30f64.to_radians().cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(az: f64, el: f64) -> Vars {
        Vars([az, el, 1.0, 30.0, 60.0])
    }

    /// The best start is followed by its opposite-side twin; near-duplicates (of a start or
    /// of a twin) are skipped, so the kept starts cover distinct views.
    #[test]
    fn kept_starts_pair_each_view_with_its_opposite_side() {
        let ranked = [v(30.0, 70.0), v(40.0, 70.0), v(210.0, 72.0), v(120.0, 90.0), v(300.0, 45.0)];
        let kept: Vec<[f64; 2]> = with_twins(ranked.into_iter(), 4).iter().map(|k| [k.0[0], k.0[1]]).collect();
        assert_eq!(kept, [[30.0, 70.0], [210.0, 70.0], [120.0, 90.0], [300.0, 90.0]]);
        assert_eq!(with_twins(ranked.into_iter(), 1).len(), 1);
    }

    /// The subdivision's views: 8, each half a step from the centre along one or both axes,
    /// azimuth wrapped, elevation kept off the poles, radius and light unchanged.
    #[test]
    fn neighbours_surround_a_view_half_a_step_away() {
        let c = Vars([350.0, 170.0, 1.5, 30.0, 60.0]);
        let n = neighbours(c, 15.0, 18.0);
        assert_eq!(n.len(), 8);
        let mut got: Vec<[f64; 2]> = n.iter().map(|k| [k.0[0], k.0[1]]).collect();
        got.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(got, [[5.0, 152.0], [5.0, 170.0], [5.0, 179.0], [335.0, 152.0], [335.0, 170.0], [335.0, 179.0], [350.0, 152.0], [350.0, 179.0]]);
        assert!(n.iter().all(|k| k.0[2..] == c.0[2..]));
    }

    /// Subdivision: a view whose neighbour scores better is replaced by that neighbour (its
    /// best light), one whose neighbours all score worse stays, and the pool is re-ranked.
    #[test]
    fn subdivision_keeps_the_best_of_each_view_and_its_neighbours() {
        let mut pool = vec![(1.0, v(0.0, 90.0)), (2.0, v(120.0, 90.0))];
        let scored = |s: f64, az: f64| vec![(s, v(az, 90.0)), (s + 5.0, v(az, 90.0))];
        let mut ranked: Vec<Vec<(f64, Vars)>> = (0..8).map(|k| scored(3.0 + k as f64, 15.0)).collect();
        ranked.extend((0..8).map(|k| scored(if k == 5 { 0.5 } else { 4.0 }, 135.0 + k as f64)));
        best_of_neighbours(&mut pool, &ranked);
        let got: Vec<(f64, f64)> = pool.iter().map(|p| (p.0, p.1.0[0])).collect();
        assert_eq!(got, [(0.5, 140.0), (1.0, 0.0)]);
    }

    /// The polish's lights: best first, neighbours within 30 degrees of a taken one skipped
    /// (20 degrees apart at the equator is a neighbour; 40 is not), at most `n`.
    #[test]
    fn polish_takes_the_best_lights_at_least_30_degrees_apart() {
        let l = |az: f64, el: f64| Vars([0.0, 90.0, 1.0, az, el]);
        let ranked = [l(0.0, 90.0), l(20.0, 90.0), l(40.0, 90.0), l(0.0, 110.0), l(180.0, 30.0), l(90.0, 90.0)];
        let got: Vec<[f64; 2]> = distinct_lights(ranked.into_iter(), 3).iter().map(|k| [k.0[3], k.0[4]]).collect();
        assert_eq!(got, [[0.0, 90.0], [40.0, 90.0], [180.0, 30.0]]);
        assert_eq!(distinct_lights(ranked.into_iter(), 1).len(), 1);
    }

    /// The polish's grid leaves no direction more than 15 degrees from one of its lights
    /// (20-degree steps: at most ~14 degrees at the equator's cell centres).
    #[test]
    fn light_grid_covers_every_direction() {
        let grid: Vec<[f64; 3]> = light_grid(20.0).iter().map(|&(az, el)| polar_unit(az, el)).collect();
        assert_eq!(grid.len(), 162);
        for i in 0..400 {
            // Fibonacci sphere: near-uniform test directions.
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / 400.0;
            let (r, phi) = ((1.0 - y * y).sqrt(), i as f64 * 2.399_963);
            let d = [r * phi.cos(), y, r * phi.sin()];
            let best = grid.iter().map(|g| g.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>()).fold(-1.0, f64::max);
            assert!(best.clamp(-1.0, 1.0).acos().to_degrees() < 15.0, "direction {d:?} is {:.1} degrees from the grid", best.acos().to_degrees());
        }
    }
}
