//! Voxeliser, flood fill, resampling and procedural shapes.

use super::*;

/// Voxel-space bounds of a box under `norm` → how many voxels each axis touches.
fn touched(norm: &Normalization, lo: Vec3, hi: Vec3) -> [std::ops::Range<usize>; 3] {
    let (a, b) = (norm.to_voxel(lo.to_array()), norm.to_voxel(hi.to_array()));
    [0, 1, 2].map(|k| a[k].floor() as usize..b[k].floor() as usize + 1)
}

fn solid_set(dims: usize, boxes: &[[std::ops::Range<usize>; 3]]) -> Vec<f32> {
    let mut v = vec![0.0; dims * dims * dims];
    for [rd, rh, rw] in boxes {
        for d in rd.clone() {
            for h in rh.clone() {
                for w in rw.clone() {
                    v[(d * dims + h) * dims + w] = 1.0;
                }
            }
        }
    }
    v
}

#[test]
fn voxelised_box_matches_analytic_volume() {
    let (lo, hi) = (Vec3::ZERO, Vec3::new(2.0, 1.3, 0.7));
    let mesh = Mesh::cuboid((lo + hi) / 2.0, (hi - lo) / 2.0, Mat3::IDENTITY);
    assert!((mesh.signed_volume() - 1.82).abs() < 1e-5);
    let opts = VoxelizeOptions {
        resolution: 32,
        margin: 4.0,
        fill: true,
        supersample: 1,
    };
    let grid = voxelize(&mesh, &opts).unwrap();
    let norm = Normalization::fit(&mesh, &opts).unwrap();
    // Exactly the voxels the closed box touches: nothing more, nothing missed.
    assert_eq!(
        grid.occupancy(),
        solid_set(32, &[touched(&norm, lo, hi)]).as_slice()
    );

    // Against the analytic volume (voxel units): every voxel the box touches is solid, so the
    // count exceeds V by about half a voxel per unit of surface area on average (a face at a
    // random offset adds 0.5 voxel of thickness in expectation): V + A/2, within 3%.
    let e = ((hi - lo) * norm.scale as f32).as_dvec3();
    let v = e.x * e.y * e.z;
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    let count = grid.occupied_count() as f64;
    assert!(count > v, "conservative voxelisation never loses volume");
    assert!(
        (count / (v + area / 2.0) - 1.0).abs() < 0.03,
        "count {count}, V {v}, V+A/2 {}",
        v + area / 2.0
    );
    let shell = voxelize(
        &mesh,
        &VoxelizeOptions {
            fill: false,
            ..opts
        },
    )
    .unwrap();
    assert!(shell.occupied_count() < grid.occupied_count());
}

#[test]
fn voxelised_sphere_matches_analytic_volume() {
    let mesh = Mesh::uv_sphere(Vec3::new(0.3, -1.0, 2.0), 1.7, 64, 32);
    assert!(mesh.signed_volume() > 0.0);
    let opts = VoxelizeOptions {
        resolution: 48,
        margin: 4.0,
        fill: true,
        supersample: 1,
    };
    let grid = voxelize(&mesh, &opts).unwrap();
    let r = 20.0f64; // (48 - 2 * 4) / 2 voxels
    // Every voxel touching the sphere is solid: that is the sphere grown by a unit cube (a
    // Minkowski sum). Steiner's formula averaged over the lattice offset gives
    // V + 3 pi R^2 (0.75 voxel shell: a cube's mean half-width) + 6 R + 1.
    // The 64 x 32 UV sphere is inscribed (about 0.3% less volume) and one placement is not an
    // average, so allow 2%.
    let v = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let expected = v + 3.0 * std::f64::consts::PI * r * r + 6.0 * r + 1.0;
    let count = grid.occupied_count() as f64;
    assert!(
        (count / expected - 1.0).abs() < 0.02,
        "count {count}, expected {expected}, ball {v}"
    );
    // A ray-parity or winding bug would leave the centre empty.
    assert_eq!(grid.get(24, 24, 24), 1.0);
}

#[test]
fn flood_fill_solidifies_overlapping_parts() {
    // An L of two closed boxes whose faces cut through each other: the mesh is not a manifold
    // and even-odd filling would hollow the overlap; filling from outside does not care.
    let (a_lo, a_hi) = (Vec3::ZERO, Vec3::new(2.0, 0.55, 0.55));
    let (b_lo, b_hi) = (Vec3::ZERO, Vec3::new(0.55, 2.0, 0.55));
    let mut mesh = Mesh::cuboid((a_lo + a_hi) / 2.0, (a_hi - a_lo) / 2.0, Mat3::IDENTITY);
    mesh.append(&Mesh::cuboid(
        (b_lo + b_hi) / 2.0,
        (b_hi - b_lo) / 2.0,
        Mat3::IDENTITY,
    ));
    let opts = VoxelizeOptions {
        resolution: 32,
        margin: 4.0,
        fill: true,
        supersample: 1,
    };
    let grid = voxelize(&mesh, &opts).unwrap();
    let norm = Normalization::fit(&mesh, &opts).unwrap();
    let want = solid_set(
        32,
        &[touched(&norm, a_lo, a_hi), touched(&norm, b_lo, b_hi)],
    );
    assert_eq!(grid.occupancy(), want.as_slice());

    // A hollow shell with a hole in it stays hollow; a closed one fills.
    let n = 8;
    let shell: Vec<bool> = (0..n * n * n)
        .map(|i| {
            let c = [i / 64, (i / 8) % 8, i % 8];
            c.iter().all(|&x| (1..7).contains(&x)) && c.iter().any(|&x| x == 1 || x == 6)
        })
        .collect();
    assert_eq!(
        fill_from_outside(&shell, [n, n, n])
            .iter()
            .filter(|&&s| s)
            .count(),
        216
    );
    let mut holed = shell.clone();
    holed[(n + 3) * n + 3] = false; // voxel (1, 3, 3) on the shell's d = 1 face
    assert_eq!(
        fill_from_outside(&holed, [n, n, n])
            .iter()
            .filter(|&&s| s)
            .count(),
        216 - 64 - 1
    );
}

#[test]
fn voxelize_rejects_bad_meshes() {
    let empty = Mesh::default();
    assert!(voxelize(&empty, &VoxelizeOptions::default()).is_err());
    let bad = Mesh {
        positions: vec![[0.0; 3]],
        triangles: vec![[0, 1, 2]],
        colours: Vec::new(),
    };
    assert!(
        voxelize(&bad, &VoxelizeOptions::default())
            .unwrap_err()
            .to_string()
            .contains("voxelize")
    );
    let cube = Mesh::cuboid(Vec3::ZERO, Vec3::ONE, Mat3::IDENTITY);
    assert!(
        voxelize(
            &cube,
            &VoxelizeOptions {
                resolution: 4096,
                ..Default::default()
            }
        )
        .is_err()
    );
    assert!(
        voxelize(
            &cube,
            &VoxelizeOptions {
                resolution: 8,
                margin: 4.0,
                fill: true,
                supersample: 1,
            }
        )
        .is_err()
    );
}

#[test]
fn resampling_preserves_mass_and_range() {
    let g = pattern_grid([64, 64, 64]);
    let small = g.resample_to(32).unwrap();
    let mean =
        |g: &VoxelGrid| g.occupancy().iter().map(|&v| v as f64).sum::<f64>() / g.len() as f64;
    assert!(
        (mean(&small) - mean(&g)).abs() < 1e-5,
        "box filter keeps the mean for integer ratios"
    );
    let big = shapes::chair(3)
        .to_grid(16)
        .unwrap()
        .resample_to(40)
        .unwrap();
    assert_eq!(big.dims(), [40, 40, 40]);
    assert!(big.occupancy().iter().all(|v| (0.0..=1.0).contains(v)));
    let coloured = VoxelGrid::new([4, 4, 4], vec![1.0; 64])
        .unwrap()
        .with_colour(vec![0.25; 192])
        .unwrap();
    let up = coloured.resample_to(6).unwrap();
    assert!(
        up.colour()
            .unwrap()
            .iter()
            .all(|&c| (c - 0.25).abs() < 1e-6)
    );
    assert!(up.occupancy().iter().all(|&v| (v - 1.0).abs() < 1e-6));
    assert!(g.resample_to(0).is_err());
}

/// `smoothed` blurs each axis by [1, 2, 1] / 4 with clamped edges: a single voxel spreads
/// to the product kernel (centre 1/8, face neighbours 1/16, edges 1/32, corners 1/64), its
/// mass is kept away from the border, a flat face keeps its 0.5 crossing, a full grid stays
/// full, and the colour is untouched. Non-cubic dims catch a swapped axis stride.
#[test]
fn smoothing_spreads_by_the_separable_kernel() {
    let dims = [5, 6, 7];
    let mut g = VoxelGrid::zeros(dims).unwrap();
    g.set(2, 3, 4, 1.0);
    let s = g.smoothed();
    assert_eq!(s.dims(), dims);
    let want = |d: usize, h: usize, w: usize| -> f32 {
        let k = |a: usize, c: usize| match a.abs_diff(c) {
            0 => 0.5,
            1 => 0.25,
            _ => 0.0,
        };
        k(d, 2) * k(h, 3) * k(w, 4)
    };
    for d in 0..5 {
        for h in 0..6 {
            for w in 0..7 {
                assert!((s.get(d, h, w) - want(d, h, w)).abs() < 1e-7, "({d}, {h}, {w}): {} against {}", s.get(d, h, w), want(d, h, w));
            }
        }
    }
    assert!((s.occupancy().iter().sum::<f32>() - 1.0).abs() < 1e-6);
    // A half-filled grid along w: the face between w = 2 and 3 keeps its crossing; the
    // clamped edges keep the full and the empty ends at 1 and 0.
    let mut half = VoxelGrid::zeros(dims).unwrap();
    for d in 0..5 {
        for h in 0..6 {
            for w in 0..3 {
                half.set(d, h, w, 1.0);
            }
        }
    }
    let s = half.smoothed();
    let row: Vec<f32> = (0..7).map(|w| s.get(1, 5, w)).collect();
    assert_eq!(row, vec![1.0, 1.0, 0.75, 0.25, 0.0, 0.0, 0.0]);
    let full = VoxelGrid::new(dims, vec![1.0; 210]).unwrap().with_colour(vec![0.3; 630]).unwrap();
    let s = full.smoothed();
    assert!(s.occupancy().iter().all(|&v| (v - 1.0).abs() < 1e-6));
    assert_eq!(s.colour(), full.colour());
}

#[test]
fn procedural_shapes_are_deterministic_and_varied() {
    assert_eq!(shapes::chair(7), shapes::chair(7));
    let grids: Vec<VoxelGrid> = (0..12)
        .map(|s| shapes::chair(s).to_grid(32).unwrap())
        .collect();
    for (s, g) in grids.iter().enumerate() {
        assert_eq!(
            g,
            &shapes::chair(s as u64).to_grid(32).unwrap(),
            "seed {s} is deterministic"
        );
        let f = g.fill_fraction();
        assert!(
            (0.01..0.4).contains(&f),
            "chair {s}: occupancy fraction {f}"
        );
    }
    for i in 0..grids.len() {
        for j in i + 1..grids.len() {
            assert!(
                grids[i].iou(&grids[j]).unwrap() < 0.95,
                "chairs {i} and {j} are near-identical"
            );
        }
    }
    for family in Family::VARIED {
        for seed in 0..8 {
            let shape = family.generate(seed);
            let g = shape.to_grid(32).unwrap();
            let f = g.fill_fraction();
            assert!(
                (0.005..0.7).contains(&f),
                "{family:?} {seed}: occupancy fraction {f}"
            );
            // The mesh is the same solid in the same frame: its voxelisation (every voxel the
            // surface touches) contains every sampled voxel centre and is not much larger.
            if let Some(mesh) = shape.to_mesh() {
                let v = voxelize(
                    &mesh,
                    &VoxelizeOptions {
                        resolution: 32,
                        ..Default::default()
                    },
                )
                .unwrap();
                let both = v
                    .occupancy()
                    .iter()
                    .zip(g.occupancy())
                    .filter(|&(&a, &b)| a >= 0.5 && b >= 0.5)
                    .count();
                let (nv, ng) = (v.occupied_count(), g.occupied_count());
                assert!(
                    both as f64 >= 0.99 * ng as f64,
                    "{family:?} {seed}: mesh voxels miss the grid ({both} of {ng})"
                );
                assert!(
                    nv < 4 * ng,
                    "{family:?} {seed}: mesh gives {nv} voxels, grid {ng}"
                );
            }
        }
    }
    let smooth = shapes::sofa(1).to_grid_supersampled(16, 3).unwrap();
    assert!(smooth.occupancy().iter().any(|&v| v > 0.0 && v < 1.0));
}

#[test]
fn antialiased_sphere_is_fractional_with_analytic_volume() {
    let mesh = Mesh::uv_sphere(Vec3::new(0.3, -1.0, 2.0), 1.7, 64, 32);
    let opts = VoxelizeOptions {
        resolution: 24,
        margin: 2.0,
        fill: true,
        supersample: 4,
    };
    let grid = voxelize(&mesh, &opts).unwrap();
    let r = 10.0f64; // (24 - 2 * 2) / 2 voxels
    let v = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    // Sum of occupancy = volume in voxels. Surface sub-voxels count half, so the conservative
    // marking adds no shell in expectation (binary at this size would be ~25% over, V + 3 pi R^2
    // + ...); what is left is the inscribed UV sphere (-0.3%) and one lattice placement: 1.5%.
    let sum: f64 = grid.occupancy().iter().map(|&x| x as f64).sum();
    assert!((sum / v - 1.0).abs() < 0.015, "sum {sum}, ball {v}");
    // Fractional at the surface: a voxel the sphere cuts through near its middle is neither
    // empty nor full, and there are many such voxels (about the sphere's area, 4 pi R^2).
    let fractional = grid.occupancy().iter().filter(|&&x| x > 0.05 && x < 0.95).count();
    assert!(fractional as f64 > 2.0 * std::f64::consts::PI * r * r, "{fractional} fractional voxels");
    // The voxel straddling the +d pole (centre 12 + 10 = 22 in grid units) is about half full;
    // the centre is full and the corners empty.
    let pole = grid.get(21, 12, 12) + grid.get(22, 12, 12);
    assert!((pole - 1.0).abs() < 0.3, "pole voxels {} {}", grid.get(21, 12, 12), grid.get(22, 12, 12));
    assert_eq!(grid.get(12, 12, 12), 1.0);
    assert_eq!(grid.get(0, 0, 0), 0.0);
    // Thresholded at 0.5 it is the same solid as the binary voxelisation up to a thin shell.
    let binary = voxelize(&mesh, &VoxelizeOptions { supersample: 1, ..opts }).unwrap();
    assert!(grid.iou(&binary).unwrap() > 0.8);
    // The default stays binary (binvox files), `smooth` is anti-aliased, and `k` is capped.
    let plain = voxelize(&mesh, &VoxelizeOptions { resolution: 16, ..Default::default() }).unwrap();
    assert!(plain.occupancy().iter().all(|&x| x == 0.0 || x == 1.0));
    assert_eq!(VoxelizeOptions::smooth(64).effective_supersample(), 4);
    assert_eq!(VoxelizeOptions::smooth(256).effective_supersample(), 2);
    assert_eq!(VoxelizeOptions::smooth(1024).effective_supersample(), 1);
}

/// A red box and a blue box side by side, voxelised: every occupied voxel takes the colour of
/// its own box, inside as well as on the surface, and a mesh without colours gives a grid
/// without colour.
#[test]
fn voxelising_carries_vertex_colours_through_the_solid() {
    let paint = |mut m: Mesh, rgb: [f32; 3]| {
        m.colours = vec![rgb; m.positions.len()];
        m
    };
    let mut mesh = paint(Mesh::cuboid(Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.45, 0.3, 0.3), Mat3::IDENTITY), [1.0, 0.0, 0.0]);
    mesh.append(&paint(Mesh::cuboid(Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.45, 0.3, 0.3), Mat3::IDENTITY), [0.0, 0.0, 1.0]));
    let n = 24;
    let grid = voxelize(&mesh, &VoxelizeOptions { resolution: n, ..Default::default() }).unwrap();
    let c = grid.colour().expect("colour carried");
    let (mut red, mut blue) = (0, 0);
    for d in 0..n {
        for h in 0..n {
            for w in 0..n {
                let i = grid.index(d, h, w);
                if grid.occupancy()[i] < 0.5 {
                    continue;
                }
                let rgb = [c[i], c[grid.len() + i], c[2 * grid.len() + i]];
                // x maps to D: the red box is the low half.
                let want = if d < n / 2 { [1.0, 0.0, 0.0] } else { [0.0, 0.0, 1.0] };
                assert_eq!(rgb, want, "voxel ({d}, {h}, {w})");
                if d < n / 2 { red += 1 } else { blue += 1 }
            }
        }
    }
    assert!(red > 100 && blue > 100, "{red} red and {blue} blue voxels");
    let grey = voxelize(&Mesh::cuboid(Vec3::ZERO, Vec3::splat(0.4), Mat3::IDENTITY), &VoxelizeOptions::default()).unwrap();
    assert!(grey.colour().is_none());
}

/// An ellipsoid's bounds are tight (points of its surface reach every face of the box, to 1%)
/// and hold every point it contains; its mesh lies on its surface.
#[test]
fn rotated_ellipsoid_bounds_are_exact() {
    let rot = glam::Mat3::from_euler(glam::EulerRot::YXZ, 0.7, -0.4, 0.3);
    let (center, radii) = (Vec3::new(0.2, -0.1, 0.4), Vec3::new(0.9, 0.3, 0.5));
    let e = shapes::Solid::Ellipsoid { center, radii, rot };
    let (lo, hi) = e.bounds();
    let (mut reach_lo, mut reach_hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for i in 0..200 {
        for j in 0..100 {
            let (th, ph) = (i as f32 / 200.0 * std::f32::consts::TAU, j as f32 / 99.0 * std::f32::consts::PI);
            let p = center + rot * (Vec3::new(ph.sin() * th.cos(), ph.cos(), ph.sin() * th.sin()) * radii);
            reach_lo = reach_lo.min(p);
            reach_hi = reach_hi.max(p);
            assert!(e.contains(center + (p - center) * 0.99), "a point just inside the surface is outside");
            assert!(!e.contains(center + (p - center) * 1.01), "a point just outside the surface is inside");
        }
    }
    let size = hi - lo;
    assert!(((reach_lo - lo) / size).abs().max_element() < 0.01 && ((reach_hi - hi) / size).abs().max_element() < 0.01, "bounds {lo} {hi}, surface reaches {reach_lo} {reach_hi}");
    for p in e.to_mesh().positions {
        let local = rot.transpose() * (Vec3::from(p) - center) / radii;
        assert!((local.length() - 1.0).abs() < 1e-4, "mesh vertex {p:?} is off the surface");
    }
}

/// Every family's shape is normalised (its added solids' bounds centred, longest side 2, to
/// f32 rounding:
/// [`shapes::Shape::new`] scales every solid kind alike) and the creatures are one piece (the
/// largest 6-connected component of the 48^3 grid holds nearly every voxel; thin tails may
/// lose a voxel or two to sampling).
#[test]
fn shapes_are_normalised_and_creatures_are_one_piece() {
    for family in Family::VARIED {
        for seed in 0..12 {
            let shape = family.generate(seed);
            let (lo, hi) = shape.bounds();
            assert!(((hi - lo).max_element() - 2.0).abs() < 1e-3 && (lo + hi).abs().max_element() < 1e-3, "{family:?} {seed}: bounds {lo} {hi}");
        }
    }
    let n = 48;
    for seed in 0..40 {
        let g = shapes::creature(seed).to_grid(n).unwrap();
        let occ: Vec<bool> = g.occupancy().iter().map(|&v| v >= 0.5).collect();
        let total = occ.iter().filter(|&&o| o).count();
        let mut seen = vec![false; occ.len()];
        let mut largest = 0;
        for start in 0..occ.len() {
            if !occ[start] || seen[start] {
                continue;
            }
            let (mut stack, mut size) = (vec![start], 0);
            seen[start] = true;
            while let Some(i) = stack.pop() {
                size += 1;
                let (d, h, w) = (i / (n * n), i / n % n, i % n);
                for (dd, dh, dw) in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)] {
                    let (d2, h2, w2) = (d as i64 + dd, h as i64 + dh, w as i64 + dw);
                    if [d2, h2, w2].iter().any(|&x| x < 0 || x >= n as i64) {
                        continue;
                    }
                    let j = ((d2 as usize * n) + h2 as usize) * n + w2 as usize;
                    if occ[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
            largest = largest.max(size);
        }
        assert!(largest as f64 >= 0.98 * total as f64, "creature {seed}: largest piece {largest} of {total} voxels");
    }
}
