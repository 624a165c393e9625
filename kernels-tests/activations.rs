//! The elementwise ops (sigmoid, ELU, PReLU, dropout, residual add) against f64 references,
//! forward and finite-difference backward; and the deterministic reduction that backward
//! passes rely on.

mod common;
mod reference;
use common::*;
use reference::activations::{dropout as dropout_ref, elu as elu_ref, prelu as prelu_ref, sigmoid as sigmoid_ref};
use rendernet::ops::{add, dropout::Dropout, elu, prelu, reduce, sigmoid};

/// Random values kept at least `gap` away from 0, where PReLU and ELU have kinks that a
/// finite difference must not straddle.
fn away_from_zero(rng: &mut Rng, n: usize, gap: f64) -> Vec<f64> {
    f32_round(&rng.vec(n, -3.0, 3.0)).into_iter().map(|v| if v.abs() < gap { v.signum() * gap + v } else { v }).collect()
}

// Odd, non-power-of-two shape with batch > 1.
const SHAPE: [usize; 4] = [2, 3, 5, 7];

/// Shapes for the elementwise ops: SHAPE (210 values, one per invocation) and 360 values
/// (a multiple of 4: four per invocation, 90 invocations over two workgroups).
const SHAPES: [[usize; 4]; 2] = [SHAPE, [2, 3, 5, 12]];

#[test]
fn sigmoid_forward_and_backward() {
    for shape in SHAPES {
        sigmoid_case(shape);
    }
}

fn sigmoid_case(shape: [usize; 4]) {
    let n: usize = shape.iter().product();
    let mut rng = Rng(1);
    let x = f32_round(&rng.vec(n, -4.0, 4.0));
    let r = f32_round(&rng.vec(n, -1.0, 1.0));
    let (tx, ty, tr, tdx) = (upload(&shape, &x), zeros(&shape), upload(&shape, &r), zeros(&shape));
    run(|p| {
        sigmoid::forward(gpu(), p, &tx, &ty)?;
        sigmoid::backward(gpu(), p, &ty, &tr, &tdx)
    });
    assert_close("sigmoid forward", &download(&ty), &sigmoid_ref(&x), 1e-6, 1e-5);
    let want = fd_grad(&x, |x| dot(&r, &sigmoid_ref(x)));
    assert_close("sigmoid backward", &download(&tdx), &want, 1e-6, 1e-4);
}

/// The sigmoid of a channel range read in place (a Narrow then a Sigmoid run as one):
/// x [2, 7, 3, 5], channels 2..6. Forward against the f64 sigmoid of the range; the gradient
/// of x against finite differences of it, written whole (zero outside the range) over a
/// tensor holding garbage, and added into a gradient already there (the other channels kept).
#[test]
fn sigmoid_of_a_channel_range() {
    let (n, c, s, start, len) = (2usize, 7usize, 15usize, 2usize, 4usize);
    let (xs, rs) = ([n, c, 3, 5], [n, len, 3, 5]);
    let mut rng = Rng(5);
    let x = f32_round(&rng.vec(n * c * s, -4.0, 4.0));
    let r = f32_round(&rng.vec(n * len * s, -1.0, 1.0));
    let range = |x: &[f64]| -> Vec<f64> {
        let mut out = Vec::new();
        for b in 0..n {
            out.extend_from_slice(&x[(b * c + start) * s..(b * c + start + len) * s]);
        }
        sigmoid_ref(&out)
    };
    let (tx, ty, tr, tdx) = (upload(&xs, &x), zeros(&rs), upload(&rs, &r), upload(&xs, &vec![7.0; n * c * s]));
    run(|p| {
        sigmoid::forward_range(gpu(), p, &tx, start, &ty)?;
        sigmoid::backward_range(gpu(), p, &ty, &tr, start, &tdx, false)
    });
    assert_close("sigmoid of a range", &download(&ty), &range(&x), 1e-6, 1e-5);
    let fd = fd_grad(&x, |x| dot(&r, &range(x)));
    assert_close("its gradient", &download(&tdx), &fd, 1e-6, 1e-4);
    let acc = f32_round(&rng.vec(n * c * s, -1.0, 1.0));
    let tacc = upload(&xs, &acc);
    run(|p| sigmoid::backward_range(gpu(), p, &ty, &tr, start, &tacc, true));
    let want: Vec<f64> = acc.iter().zip(&fd).map(|(a, g)| a + g).collect();
    assert_close("its gradient added", &download(&tacc), &want, 1e-6, 1e-4);
    // A range past the channels, and a gradient of the wrong shape, are errors naming them.
    let err = gpu().run(|p| sigmoid::forward_range(gpu(), p, &tx, 4, &ty)).unwrap_err();
    assert!(err.to_string().contains("start + len <= C"), "{err}");
    let err = gpu().run(|p| sigmoid::backward_range(gpu(), p, &ty, &tx, start, &tdx, false)).unwrap_err();
    assert!(err.to_string().contains("dy"), "{err}");
}

#[test]
fn elu_forward_and_backward() {
    let n: usize = SHAPE.iter().product();
    let alpha = 1.3;
    let mut rng = Rng(2);
    // Keep away from the kink at 0 so finite differences do not straddle it.
    let x = f32_round(&away_from_zero(&mut rng, n, 1e-3));
    let r = f32_round(&rng.vec(n, -1.0, 1.0));
    let (tx, ty, tr, tdx) = (upload(&SHAPE, &x), zeros(&SHAPE), upload(&SHAPE, &r), zeros(&SHAPE));
    run(|p| {
        elu::forward(gpu(), p, alpha as f32, &tx, &ty)?;
        elu::backward(gpu(), p, alpha as f32, &tx, &tr, &tdx)
    });
    assert_close("elu forward", &download(&ty), &elu_ref(alpha, &x), 1e-6, 1e-5);
    let want = fd_grad(&x, |x| dot(&r, &elu_ref(alpha, x)));
    assert_close("elu backward", &download(&tdx), &want, 1e-6, 1e-4);
}

#[test]
fn sum_outer_inner_matches_reference() {
    // C = 131: not a multiple of the 64-wide workgroup (the scalar entry point). C = 324: a
    // multiple of 4 and >= 256 (the vec4 one), 81 quads, so lanes 17..63 make a second round
    // past the end; B = 5 rows interleave with A = 3 so a wrong row stride shows.
    for (a, b, c) in [(3, 5, 131), (3, 5, 324)] {
        let mut rng = Rng(3);
        let x = f32_round(&rng.vec(a * b * c, -1.0, 1.0));
        let want: Vec<f64> = (0..b)
            .map(|j| (0..a).flat_map(|i| (0..c).map(move |k| (i, k))).map(|(i, k)| x[(i * b + j) * c + k]).sum::<f64>() * 0.5)
            .collect();
        let (tx, tout) = (upload(&[a, b, c], &x), zeros(&[b]));
        run(|p| reduce::sum_outer_inner(gpu(), p, &tx, [a, b, c], 0.5, &tout));
        // <= 972 terms of size <= 1: f32 sum error << 1e-5.
        assert_close(&format!("sum_outer_inner {a}x{b}x{c}"), &download(&tout), &want, 1e-5, 1e-5);
    }
}

#[test]
fn mismatched_shapes_are_errors_not_panics() {
    let (tx, ty) = (zeros(&[2, 3]), zeros(&[3, 3]));
    let err = gpu().run(|p| sigmoid::forward(gpu(), p, &tx, &ty)).unwrap_err();
    assert!(err.to_string().contains("sigmoid_forward"), "{err}");
    let err = gpu().run(|p| reduce::sum_outer_inner(gpu(), p, &tx, [2, 2, 2], 1.0, &ty)).unwrap_err();
    assert!(err.to_string().contains("does not match"), "{err}");
}

/// Every kernel: spatial sizes that are a multiple of 4 (the row kernels, vec4s; the window
/// kernels where the tensor spans a 64 KiB window) and one that is not (one element per
/// invocation).
#[test]
fn prelu_forward_and_backward() {
    // [N, C, D, H, W]: channels not a multiple of 4, odd spatial dims. S = 36 (a row in one
    // workgroup, most of its invocations idle), 27, then 2388: 597 vec4s a row, two
    // workgroups of 64 x 8 vec4s with the second one partly past the row's end.
    // Then tensors of more than one 64 KiB uniform window (the window kernels): 4365 vec4s
    // with S / 4 = 1455 odd (one vec4 an invocation; the second window ends at the tensor's
    // end, overlapping the first), and 5400 vec4s with S / 4 = 540 (four an invocation).
    for shape in [[2, 5, 3, 4, 3], [2, 5, 3, 3, 3], [2, 3, 4, 3, 199], [1, 3, 5, 12, 97], [2, 5, 4, 6, 90]] {
        prelu_case(shape, None);
    }
}

/// The window kernels over more than four windows: two dispatches, the second holding the
/// tensor's overlapping last window. 17490 vec4s with S / 4 odd (one vec4 an invocation),
/// then 16640 vec4s with S / 4 = 3328 (eight an invocation). dx is checked by finite
/// differences at every 31st value and around every window boundary (a full check would
/// take n^2 reference evaluations).
#[test]
fn prelu_windows_over_several_dispatches() {
    for shape in [[2, 3, 4, 55, 53], [1, 5, 8, 16, 104]] {
        let n: usize = shape.iter().product();
        let edges = (1..=n / 16384).flat_map(|k| (16384 * k).saturating_sub(6)..(16384 * k + 6).min(n));
        let mut at: Vec<usize> = (0..n).step_by(31).chain(edges).chain(n - 6..n).collect();
        at.sort_unstable();
        at.dedup();
        prelu_case(shape, Some(&at));
        // The windows ran: two forward dispatches of four windows each (on a CPU adapter;
        // elsewhere the one dispatch of the rows kernel).
        let (tx, ta, ty) = (zeros(&shape), zeros(&[shape[1]]), zeros(&shape));
        let before = gpu().dispatch_count();
        run(|p| prelu::forward(gpu(), p, &tx, &ta, &ty));
        let want = if gpu().info.device_type == wgpu::DeviceType::Cpu { 2 } else { 1 };
        assert_eq!(gpu().dispatch_count() - before, want, "forward dispatches, shape {shape:?}");
    }
}

/// Forward, dx and dalpha of PReLU on `shape` against the reference, dx by finite
/// differences at the indices `at` (every index if `None`).
fn prelu_case(shape: [usize; 5], at: Option<&[usize]>) {
    let (c, s) = (shape[1], shape[2..].iter().product::<usize>());
    let n: usize = shape.iter().product();
    let mut rng = Rng(4);
    let x = f32_round(&away_from_zero(&mut rng, n, 1e-3));
    let alpha = f32_round(&rng.vec(c, -0.5, 0.5));
    let r = f32_round(&rng.vec(n, -1.0, 1.0));
    let (tx, ta, ty, tr) = (upload(&shape, &x), upload(&[c], &alpha), zeros(&shape), upload(&shape, &r));
    let (tdx, tda) = (zeros(&shape), zeros(&[c]));
    run(|p| {
        prelu::forward(gpu(), p, &tx, &ta, &ty)?;
        prelu::backward(gpu(), p, &tx, &ta, &tr, &tdx, &tda)
    });
    let what = |t: &str| format!("prelu {t}, shape {shape:?}");
    assert_close(&what("forward"), &download(&ty), &prelu_ref(&x, &alpha, c, s), 1e-6, 1e-5);
    let loss = |x: &[f64]| dot(&r, &prelu_ref(x, &alpha, c, s));
    let (got_dx, want_dx) = match at {
        None => (download(&tdx), fd_grad(&x, loss)),
        Some(at) => {
            let all = download(&tdx);
            (at.iter().map(|&i| all[i]).collect(), fd_grad_at(&x, at.iter().copied(), loss))
        }
    };
    assert_close(&what("backward input"), &got_dx, &want_dx, 1e-6, 1e-4);
    // dalpha sums up to ~14000 terms of size <= 3 per channel (f32 error ~1e-4 absolute,
    // several times under the 1e-4 relative bound on sums of that size).
    let want_da = fd_grad(&alpha, |a| dot(&r, &prelu_ref(&x, a, c, s)));
    assert_close(&what("backward alpha"), &download(&tda), &want_da, 1e-5, 1e-4);
}

#[test]
fn prelu_rejects_wrong_alpha() {
    let (tx, ta, ty) = (zeros(&[2, 3, 4]), zeros(&[4]), zeros(&[2, 3, 4]));
    let err = gpu().run(|p| prelu::forward(gpu(), p, &tx, &ta, &ty)).unwrap_err();
    assert!(err.to_string().contains("alpha"), "{err}");
}

#[test]
fn dropout_mask_is_seeded_and_shared_by_backward() {
    let shape = [3, 7, 11];
    let n: usize = shape.iter().product();
    let keep = 0.7;
    let mut rng = Rng(5);
    let x = f32_round(&rng.vec(n, 0.5, 2.0)); // nonzero, so the mask is visible in y
    let r = f32_round(&rng.vec(n, -1.0, 1.0));
    let d = Dropout { keep_prob: keep as f32 };
    let (tx, ty, ty2, tr, tdx) = (upload(&shape, &x), zeros(&shape), zeros(&shape), upload(&shape, &r), zeros(&shape));
    run(|p| {
        d.forward(gpu(), p, 42, &tx, &ty)?;
        d.forward(gpu(), p, 43, &tx, &ty2)?;
        d.backward(gpu(), p, 42, &tr, &tdx)
    });
    let y = download(&ty);
    // 1/0.7 is not exact in f32: relative 1e-6.
    assert_close("dropout forward", &y, &dropout_ref(&x, keep, 42), 1e-6, 1e-6);
    let kept = y.iter().filter(|&&v| v != 0.0).count() as f64 / n as f64;
    assert!((kept - keep).abs() < 0.07, "kept fraction {kept} for keep_prob {keep}");
    assert_ne!(download(&ty2), y, "another seed must give another mask");
    let want = fd_grad(&x, |x| dot(&r, &dropout_ref(x, keep, 42)));
    assert_close("dropout backward", &download(&tdx), &want, 1e-6, 1e-5);
    // keep_prob 1 (evaluation) is exactly the identity.
    let all = Dropout { keep_prob: 1.0 };
    run(|p| all.forward(gpu(), p, 42, &tx, &ty));
    assert_close("dropout keep_prob 1", &download(&ty), &x, 0.0, 0.0);
    let bad = Dropout { keep_prob: 0.0 };
    assert!(gpu().run(|p| bad.forward(gpu(), p, 1, &tx, &ty)).is_err());
}

#[test]
fn add_forward_backward_and_accumulate() {
    for shape in SHAPES {
        add_case(shape);
    }
}

fn add_case(shape: [usize; 4]) {
    let n: usize = shape.iter().product();
    let mut rng = Rng(6);
    let (a, b) = (f32_round(&rng.vec(n, -1.0, 1.0)), f32_round(&rng.vec(n, -1.0, 1.0)));
    let (ta, tb, ty, tcopy) = (upload(&shape, &a), upload(&shape, &b), zeros(&shape), zeros(&shape));
    run(|p| {
        add::forward(gpu(), p, &ta, &tb, &ty)?;
        // Accumulating twice checks that it adds rather than overwrites.
        add::accumulate(gpu(), p, &ta, &tb)?;
        add::accumulate(gpu(), p, &ta, &tb)?;
        add::copy(gpu(), p, &ta, &tcopy)
    });
    assert_close("add copy", &download(&tcopy), &a, 0.0, 0.0);
    let sum: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
    assert_close("add forward", &download(&ty), &sum, 1e-6, 1e-6);
    let acc: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 2.0 * x + y).collect();
    assert_close("add accumulate", &download(&tb), &acc, 1e-6, 1e-6);
    // Backward: the executor routes dy to each input with `copy` (that input's first
    // gradient) or `accumulate` (a later one, when a value feeds several nodes). On the GPU,
    // both must give the finite-difference gradient of dot(r, a + b).
    let (r, prior) = (f32_round(&rng.vec(n, -1.0, 1.0)), f32_round(&rng.vec(n, -1.0, 1.0)));
    let (tr, tga, tgb) = (upload(&shape, &r), zeros(&shape), upload(&shape, &prior));
    run(|p| {
        add::copy(gpu(), p, &tr, &tga)?;
        add::accumulate(gpu(), p, &tr, &tgb)
    });
    let add_ref = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p + q).collect::<Vec<_>>();
    let da = fd_grad(&a, |x| dot(&r, &add_ref(x, &b)));
    let db = fd_grad(&b, |y| dot(&r, &add_ref(&a, y)));
    assert_close("add backward to a (copy)", &download(&tga), &da, 1e-6, 1e-5);
    let want_b: Vec<f64> = prior.iter().zip(&db).map(|(p, d)| p + d).collect();
    assert_close("add backward to b (accumulated onto an earlier gradient)", &download(&tgb), &want_b, 1e-6, 1e-5);
}
