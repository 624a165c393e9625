//! Rigid-body resampling against the f64 reference: forward, backward to the grid and to the
//! pose by finite differences, plus exact geometric checks (identity, quarter turns, shifts,
//! scale) that pin the axis conventions finite differences cannot see.

mod common;
mod reference;
use common::*;
use reference::resample::{self as rref, Dims};
use rendernet::ops::resample::{self, Sampling};
use std::f64::consts::FRAC_PI_2;

// Non-cubic, odd sizes; output larger than input in D and H, equal in W; C = 2.
const DIMS: Dims = Dims { n: 2, c: 2, inp: [5, 6, 7], out: [8, 9, 7] };

fn shape(d: &Dims, s: [usize; 3]) -> [usize; 5] {
    [d.n, d.c, s[0], s[1], s[2]]
}

/// Random poses (f32-rounded): scale 0.7-1.4, angles anywhere, translations within 1.5 voxels.
fn random_poses(rng: &mut Rng, n: usize) -> Vec<f64> {
    let mut p = Vec::new();
    for _ in 0..n {
        p.push(rng.uniform(0.7, 1.4));
        p.push(rng.uniform(-3.2, 3.2));
        p.push(rng.uniform(-3.2, 3.2));
        p.extend(rng.vec(3, -1.5, 1.5));
    }
    f32_round(&p)
}

/// Grid, poses and upstream gradient for one random case.
fn case(seed: u64, d: &Dims) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Rng(seed);
    let x = f32_round(&rng.vec(d.n * d.c * d.inp.iter().product::<usize>(), -1.0, 1.0));
    let poses = random_poses(&mut rng, d.n);
    let r = f32_round(&rng.vec(d.n * d.c * d.out.iter().product::<usize>(), -1.0, 1.0));
    (x, poses, r)
}

/// Both ways of reading the grid; lavapipe (the test adapter) reads rgba32f storage textures.
const SAMPLINGS: [Sampling; 2] = [Sampling::Buffer, Sampling::Texture];

/// Runs the forward on the GPU, reading the grid as `s` says.
fn gpu_forward_with(d: &Dims, x: &[f64], poses: &[f64], s: Sampling) -> Vec<f64> {
    let (tx, tp, ty) = (upload(&shape(d, d.inp), x), upload(&[d.n, 6], poses), zeros(&shape(d, d.out)));
    run(|p| resample::forward_with(gpu(), p, &tx, &tp, &ty, s));
    download(&ty)
}

/// Runs the forward on the GPU as the network does ([`Sampling::Auto`]).
fn gpu_forward(d: &Dims, x: &[f64], poses: &[f64]) -> Vec<f64> {
    gpu_forward_with(d, x, poses, Sampling::Auto)
}

/// The texture path's packing on a CPU adapter writes the grid's texels into a staging
/// buffer and copies it into the texture (src/gpu/passes.rs); in a pass that cannot be split
/// it stores them. Both give the same bits, "quads" (C = 5) and "corners" (C = 1) alike, and
/// only the first splits its pass (on a CPU adapter; elsewhere neither does).
#[test]
fn packing_copied_in_equals_texture_stores() {
    let cpu = copies_on_this_adapter();
    for (k, d) in [Dims { n: 2, c: 5, inp: [5, 6, 7], out: [7, 5, 8] }, Dims { n: 3, c: 1, inp: [7, 5, 6], out: [9, 8, 7] }].iter().enumerate() {
        let (x, poses, _) = case(71 + k as u64, d);
        let (tx, tp) = (upload(&shape(d, d.inp), &x), upload(&[d.n, 6], &poses));
        let ys = [zeros(&shape(d, d.out)), zeros(&shape(d, d.out))];
        let before = gpu().pass_splits();
        run(|p| resample::forward_with(gpu(), p, &tx, &tp, &ys[0], Sampling::Texture));
        let splits = gpu().pass_splits() - before;
        run_unsplit(|p| resample::forward_with(gpu(), p, &tx, &tp, &ys[1], Sampling::Texture));
        assert_eq!(gpu().pass_splits() - before, splits, "{d:?}: a pass the ops cannot split was split");
        assert_eq!(splits > 0, cpu, "{d:?}: {splits} splits");
        assert!(download(&ys[0]) == download(&ys[1]), "{d:?}: copied-in grid differs from texture stores");
    }
}

#[test]
fn forward_matches_reference() {
    // C = 2 and 5 (the texture path's "quads": one and two texels of 4 channels, the second
    // partly empty) and C = 1 ("corners": a texel holds 4 corners of a cell). Input W a
    // multiple of 4 as well: the staging then reads vec4s (`w4`), and from a tensor of 64 KiB
    // or more on lavapipe, uniform windows (`big`).
    let wide = Dims { n: 2, c: 5, inp: [5, 6, 7], out: [7, 5, 8] };
    let one = Dims { n: 3, c: 1, inp: [7, 5, 6], out: [9, 8, 7] };
    let w4 = Dims { n: 2, c: 2, inp: [5, 3, 8], out: [6, 7, 9] };
    let big = Dims { n: 2, c: 1, inp: [16, 32, 32], out: [9, 10, 12] };
    for (k, d) in [DIMS, wide, one, w4, big].iter().enumerate() {
        let (x, poses, _) = case(11 + 10 * k as u64, d);
        let want = rref::forward(d, &x, &poses);
        for s in SAMPLINGS {
            // |x| <= 1: sample points carry f32 rounding ~1e-6 (coordinates < 10), times a
            // trilinear slope <= 2 per axis, plus f32 sin/cos; 2e-5 leaves ~5x headroom, a
            // wrong tap is ~0.1.
            assert_close(&format!("resample forward {s:?} {:?}", d.out), &gpu_forward_with(d, &x, &poses, s), &want, 2e-5, 1e-4);
        }
    }
}

#[test]
fn backward_input_matches_finite_differences() {
    let (x, poses, r) = case(12, &DIMS);
    let (tp, tr, tdx) = (upload(&[DIMS.n, 6], &poses), upload(&shape(&DIMS, DIMS.out), &r), zeros(&shape(&DIMS, DIMS.inp)));
    run(|p| resample::backward_input(gpu(), p, &tp, &tr, &tdx));
    let want = fd_grad(&x, |x| dot(&r, &rref::forward(&DIMS, x, &poses)));
    // Each dx sums <= (2/s + 1)^3 < 64 terms |r| * weight <= 1 with weights off by ~1e-6:
    // error ~1e-5 at worst; a missed output voxel is ~0.1.
    assert_close("resample backward_input", &download(&tdx), &want, 2e-5, 1e-4);
}

/// Smallest distance of any sample coordinate to an integer: trilinear interpolation has a
/// kink there, and a finite difference straddling one is wrong by O(1).
fn kink_margin(d: &Dims, poses: &[f64]) -> f64 {
    let mut m = f64::INFINITY;
    for n in 0..d.n {
        for o in rref::out_voxels(d) {
            for q in rref::sample_point(d, &poses[n * 6..n * 6 + 6], o) {
                m = m.min((q - q.round()).abs());
            }
        }
    }
    m
}

#[test]
fn backward_pose_matches_finite_differences() {
    let (x, poses, r) = case(13, &DIMS);
    // FD steps of 1e-6 move sample points by < 1e-5; stay 10x away from every kink.
    // (If this fails for a new seed, pick another seed rather than loosening anything.)
    let margin = kink_margin(&DIMS, &poses);
    assert!(margin > 1e-4, "seed puts a sample {margin} from a kink; choose another seed");
    let (tx, tp, tr) = (upload(&shape(&DIMS, DIMS.inp), &x), upload(&[DIMS.n, 6], &poses), upload(&shape(&DIMS, DIMS.out), &r));
    let want = fd_grad(&poses, |p| dot(&r, &rref::forward(&DIMS, &x, p)));
    // Sums of ~1000 voxel terms of size ~1-10 (|dq/dθ| <= |u|/s < 9) with f32 errors ~1e-7
    // relative each, partly cancelling, against gradients of order 1-30: observed errors are
    // ~1e-5, so atol = 1e-5 * max|grad| (~3e-4) leaves ~20x headroom; a dropped or flipped
    // term of any one partial moves it by O(1).
    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for s in SAMPLINGS {
        let tdp = zeros(&[DIMS.n, 6]);
        run(|p| resample::backward_pose_with(gpu(), p, &tx, &tp, &tr, &tdp, s));
        assert_close(&format!("resample backward_pose {s:?}"), &download(&tdp), &want, 1e-5 * scale, 1e-4);
    }
}

#[test]
fn backward_pose_reads_both_texture_layouts() {
    // C = 5: "quads", the second texel holding one channel (a quad skipped or a channel read
    // from the wrong texel shows); C = 1: "corners" (a corner taken from the wrong component
    // shows).
    for (c, seed) in [(5, 16), (1, 17)] {
        let d = Dims { n: 2, c, inp: [5, 4, 6], out: [6, 5, 4] };
        let (x, poses, r) = case(seed, &d);
        assert!(kink_margin(&d, &poses) > 1e-4, "seed puts a sample near a kink; choose another seed");
        let want = fd_grad(&poses, |p| dot(&r, &rref::forward(&d, &x, p)));
        let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (tx, tp, tr, tdp) = (upload(&shape(&d, d.inp), &x), upload(&[2, 6], &poses), upload(&shape(&d, d.out), &r), zeros(&[2, 6]));
        run(|p| resample::backward_pose_with(gpu(), p, &tx, &tp, &tr, &tdp, Sampling::Texture));
        // Tolerance as backward_pose_matches_finite_differences.
        assert_close(&format!("resample backward_pose, {c} channels"), &download(&tdp), &want, 1e-5 * scale, 1e-4);
    }
}

#[test]
fn identity_pose_reproduces_input_exactly() {
    // Even sizes make the centres half-integers: still exact, as c_in = c_out.
    let d = Dims { n: 2, c: 3, inp: [4, 5, 6], out: [4, 5, 6] };
    let mut rng = Rng(14);
    let x = f32_round(&rng.vec(d.n * d.c * 120, -1.0, 1.0));
    let poses = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0].repeat(d.n);
    for s in SAMPLINGS {
        assert_eq!(gpu_forward_with(&d, &x, &poses, s), x, "identity forward {s:?}");
    }
    // The gather's transpose is the identity too: dx = dy exactly.
    let (tp, tdy, tdx) = (upload(&[d.n, 6], &poses), upload(&shape(&d, d.out), &x), zeros(&shape(&d, d.inp)));
    run(|p| resample::backward_input(gpu(), p, &tp, &tdy, &tdx));
    assert_eq!(download(&tdx), x, "identity backward_input");
}

/// Forward with one pose (N = 1, C = 1) and checks y[map(i)] = x[i] for every input voxel.
fn check_mapping(what: &str, inp: [usize; 3], out: [usize; 3], pose: [f64; 6], map: impl Fn([usize; 3]) -> [usize; 3]) {
    let d = Dims { n: 1, c: 1, inp, out };
    // Distinct values (all voxels differ) so any axis mix-up shows.
    let x: Vec<f64> = (0..inp.iter().product::<usize>()).map(|i| 1.0 + i as f64).collect();
    let y = gpu_forward(&d, &x, &f32_round(&pose));
    for a in 0..inp[0] {
        for b in 0..inp[1] {
            for c in 0..inp[2] {
                let o = map([a, b, c]);
                let got = y[(o[0] * out[1] + o[1]) * out[2] + o[2]];
                let want = x[(a * inp[1] + b) * inp[2] + c];
                // f32 sin/cos of π/2 are off by ~4e-8: a ~1e-7 blend with a neighbour.
                assert!((got - want).abs() < 1e-4, "{what}: input {:?} should land at {o:?} = {want}, found {got}", [a, b, c]);
            }
        }
    }
}

#[test]
fn quarter_turns_shifts_and_scale_move_voxels_where_expected() {
    // Azimuth +90°: +W turns into +D, D into -W (p_d = r_w, p_w = -r_d about the centres).
    check_mapping("azimuth 90", [5, 3, 7], [7, 3, 5], [1.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0], |[d, h, w]| [w, h, 4 - d]);
    // Elevation +90°: +H turns into +D, D into -H.
    check_mapping("elevation 90", [5, 7, 3], [7, 5, 3], [1.0, 0.0, FRAC_PI_2, 0.0, 0.0, 0.0], |[d, h, w]| [h, 4 - d, w]);
    // Azimuth first, then elevation: W -> D -> -H... p = R_el R_az q.
    check_mapping("azimuth then elevation", [3, 5, 7], [5, 7, 3], [1.0, FRAC_PI_2, FRAC_PI_2, 0.0, 0.0, 0.0], |[d, h, w]| {
        // R_az: (d, h, w) -> (w', h', -d'); R_el: (a, b, c) -> (b, -a, c), about the centres.
        let (rd, rh, rw) = (d as i64 - 1, h as i64 - 2, w as i64 - 3);
        let (ad, ah, aw) = (rw, rh, -rd);
        let (bd, bh, bw) = (ah, -ad, aw);
        [(bd + 2) as usize, (bh + 3) as usize, (bw + 1) as usize]
    });
    // Translation (t_d, t_h, t_w) in output voxels, same-size grids.
    check_mapping("translation", [3, 4, 5], [5, 6, 5], [1.0, 0.0, 0.0, 1.0, -1.0, 0.0], |[d, h, w]| [d + 2, h, w]);
    // Scale 2 about the centres: input voxel k lands on output voxel 2k.
    check_mapping("scale 2", [3, 2, 4], [5, 3, 7], [2.0, 0.0, 0.0, 0.0, 0.0, 0.0], |[d, h, w]| [2 * d, 2 * h, 2 * w]);
}

#[test]
fn pose_from_view_follows_paper_conventions() {
    let p = resample::pose_from_view(90.0, 90.0, 3.3);
    assert_eq!(p, [1.0, std::f32::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0]);
    let p = resample::pose_from_view(0.0, 10.0, 6.6);
    assert!((p[0] - 0.5).abs() < 1e-7 && (p[2] + 80f32.to_radians()).abs() < 1e-6, "{p:?}");
}

#[test]
fn bad_shapes_are_errors_not_panics() {
    let (x, y, pose) = (zeros(&[2, 1, 3, 3, 3]), zeros(&[2, 1, 4, 4, 4]), zeros(&[2, 6]));
    let expect_err = |what: &str, r: rendernet::Result<()>, needle: &str| {
        let e = r.expect_err(what).to_string();
        assert!(e.contains(needle), "{what}: {e}");
    };
    let g = gpu();
    expect_err("pose [2, 5]", g.run(|p| resample::forward(g, p, &x, &zeros(&[2, 5]), &y)), "resample_forward");
    expect_err("pose batch", g.run(|p| resample::forward(g, p, &x, &zeros(&[1, 6]), &y)), "pose");
    expect_err("rank 4 x", g.run(|p| resample::forward(g, p, &zeros(&[2, 3, 3, 3]), &pose, &y)), "x");
    expect_err("y channels", g.run(|p| resample::forward(g, p, &x, &pose, &zeros(&[2, 2, 4, 4, 4]))), "y");
    expect_err("dx batch", g.run(|p| resample::backward_input(g, p, &pose, &y, &zeros(&[1, 1, 3, 3, 3]))), "dx");
    expect_err("dy channels", g.run(|p| resample::backward_pose(g, p, &x, &pose, &zeros(&[2, 3, 4, 4, 4]), &pose)), "dy");
    expect_err("dpose", g.run(|p| resample::backward_pose(g, p, &x, &pose, &y, &zeros(&[2, 5]))), "dpose");
}

#[test]
fn a_grid_too_wide_for_a_texture_is_sampled_from_its_buffer() {
    let limit = gpu().limits.max_texture_dimension_3d as usize;
    // W + 2 border texels over the limit; tiny otherwise.
    let d = Dims { n: 1, c: 1, inp: [1, 1, limit - 1], out: [1, 1, 4] };
    let x: Vec<f64> = (0..limit - 1).map(|i| i as f64).collect();
    let (tx, tp, ty) = (upload(&shape(&d, d.inp), &x), upload(&[1, 6], &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), zeros(&shape(&d, d.out)));
    let g = gpu();
    let e = g.run(|p| resample::forward_with(g, p, &tx, &tp, &ty, Sampling::Texture)).expect_err("texture too wide").to_string();
    assert!(e.contains("max_texture_dimension_3d") && e.contains("resample_forward"), "{e}");
    // Auto falls back to the buffer: samples at the row's centre -1.5..+1.5, where x (its own
    // index) interpolates to the sample's coordinate, exactly in f32.
    run(|p| resample::forward(g, p, &tx, &tp, &ty));
    let c = (limit - 2) as f64 / 2.0;
    let want: Vec<f64> = (0..4).map(|k| c - 1.5 + k as f64).collect();
    assert_eq!(download(&ty), want);
}

#[test]
fn a_zero_scale_samples_nothing_rather_than_nan() {
    // Scale 0 divides by zero (sample points infinite or NaN); an executor's pose input is
    // zero until set. Both paths must read zeros, not NaN, so nothing poisons a training step.
    let mut poses = vec![0.0; 12];
    poses[6] = 1.0; // item 1: identity-like scale 1, for contrast
    // C = 1 and 2: the texture path's two layouts.
    for c in [1, 2] {
        let d = Dims { n: 2, c, inp: [3, 4, 5], out: [4, 3, 8] };
        let x = vec![1.0; d.n * d.c * 60];
        for s in SAMPLINGS {
            let y = gpu_forward_with(&d, &x, &poses, s);
            let (first, second) = y.split_at(y.len() / 2);
            assert!(first.iter().all(|&v| v == 0.0), "{s:?}, C = {c}: zero scale gave {first:?}");
            assert!(second.iter().any(|&v| v > 0.5), "{s:?}, C = {c}: scale 1 gave nothing");
        }
    }
}
