//! Sigmoid and ELU against f64 references, forward and finite-difference backward; and the
//! deterministic reduction they and other backward passes rely on.

mod common;
use common::*;
use rendernet::ops::{elu, reduce, sigmoid};

fn sigmoid_ref(x: &[f64]) -> Vec<f64> {
    x.iter().map(|&v| 1.0 / (1.0 + (-v).exp())).collect()
}

fn elu_ref(alpha: f64, x: &[f64]) -> Vec<f64> {
    x.iter().map(|&v| if v > 0.0 { v } else { alpha * (v.exp() - 1.0) }).collect()
}

// Odd, non-power-of-two shape with batch > 1.
const SHAPE: [usize; 4] = [2, 3, 5, 7];

#[test]
fn sigmoid_forward_and_backward() {
    let n: usize = SHAPE.iter().product();
    let mut rng = Rng(1);
    let x = f32_round(&rng.vec(n, -4.0, 4.0));
    let r = f32_round(&rng.vec(n, -1.0, 1.0));
    let (tx, ty, tr, tdx) = (upload(&SHAPE, &x), zeros(&SHAPE), upload(&SHAPE, &r), zeros(&SHAPE));
    run(|p| {
        sigmoid::forward(gpu(), p, &tx, &ty)?;
        sigmoid::backward(gpu(), p, &ty, &tr, &tdx)
    });
    assert_close("sigmoid forward", &download(&ty), &sigmoid_ref(&x), 1e-6, 1e-5);
    let want = fd_grad(&x, |x| dot(&r, &sigmoid_ref(x)));
    assert_close("sigmoid backward", &download(&tdx), &want, 1e-6, 1e-4);
}

#[test]
fn elu_forward_and_backward() {
    let n: usize = SHAPE.iter().product();
    let alpha = 1.3;
    let mut rng = Rng(2);
    // Keep away from the kink at 0 so finite differences do not straddle it.
    let x: Vec<f64> = f32_round(&rng.vec(n, -3.0, 3.0)).into_iter().map(|v| if v.abs() < 1e-3 { 0.5 } else { v }).collect();
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
    // [A, B, C] = [3, 5, 131]: C not a multiple of the 64-wide workgroup.
    let (a, b, c) = (3, 5, 131);
    let mut rng = Rng(3);
    let x = f32_round(&rng.vec(a * b * c, -1.0, 1.0));
    let want: Vec<f64> = (0..b)
        .map(|j| (0..a).flat_map(|i| (0..c).map(move |k| (i, k))).map(|(i, k)| x[(i * b + j) * c + k]).sum::<f64>() * 0.5)
        .collect();
    let (tx, tout) = (upload(&[a, b, c], &x), zeros(&[b]));
    run(|p| reduce::sum_outer_inner(gpu(), p, &tx, [a, b, c], 0.5, &tout));
    // 393 terms of size <= 1: f32 sum error << 1e-5.
    assert_close("sum_outer_inner", &download(&tout), &want, 1e-5, 1e-5);
}

#[test]
fn mismatched_shapes_are_errors_not_panics() {
    let (tx, ty) = (zeros(&[2, 3]), zeros(&[3, 3]));
    let err = gpu().run(|p| sigmoid::forward(gpu(), p, &tx, &ty)).unwrap_err();
    assert!(err.to_string().contains("sigmoid_forward"), "{err}");
    let err = gpu().run(|p| reduce::sum_outer_inner(gpu(), p, &tx, [2, 2, 2], 1.0, &ty)).unwrap_err();
    assert!(err.to_string().contains("does not match"), "{err}");
}
