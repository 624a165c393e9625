//! MSE and BCE against f64 references (forward, and finite-difference backward scaled by an
//! upstream gradient read from a [1] tensor), BCE's clamp, per-image MSE and PSNR.

mod common;
mod reference;
use common::*;
use reference::loss::{bce, mse, per_image_mse};
use rendernet::ops::loss::{BCE_EPS, Loss, per_image_mse as gpu_per_image_mse, psnr_from_mse};

// Odd, non-power-of-two, more than one 64-wide workgroup and more than one reduction stride.
const SHAPE: [usize; 4] = [2, 3, 5, 7];
/// The upstream gradient: not 1, so a backward that ignores it fails.
const G: f64 = 0.75;

/// The GPU's clamp bounds as f64 (`1 - 1e-7` is 0.99999988 in f32).
fn bounds() -> (f64, f64) {
    (BCE_EPS as f64, (1.0f32 - BCE_EPS) as f64)
}

/// Runs `loss` forward and backward; returns (loss value, dpred).
fn run_loss(loss: Loss, shape: &[usize], p: &[f64], t: &[f64]) -> (f64, Vec<f64>) {
    let (tp, tt, tl, tdp) = (upload(shape, p), upload(shape, t), zeros(&[1]), zeros(shape));
    let tg = upload(&[1], &[G]);
    run(|pass| {
        loss.forward(gpu(), pass, &tp, &tt, &tl)?;
        loss.backward(gpu(), pass, &tp, &tt, &tg, &tdp)
    });
    (download(&tl)[0], download(&tdp))
}

#[test]
fn mse_forward_and_backward() {
    // SHAPE: one value per invocation; 360 values, a multiple of 4: four per invocation.
    for shape in [SHAPE.to_vec(), vec![2, 3, 5, 12]] {
        let n: usize = shape.iter().product();
        let mut rng = Rng(21);
        let (p, t) = (f32_round(&rng.vec(n, -0.5, 1.5)), f32_round(&rng.vec(n, 0.0, 1.0)));
        let (l, dp) = run_loss(Loss::Mse, &shape, &p, &t);
        // A mean of <= 360 O(1) squares: f32 error ~1e-7 relative.
        assert_close(&format!("mse forward {shape:?}"), &[l], &[mse(&p, &t)], 1e-7, 1e-5);
        let want = fd_grad(&p, |p| G * mse(p, &t));
        // Gradients are O(1/n) = O(3e-3); 1e-9 absolute is far below a dropped factor.
        assert_close(&format!("mse backward {shape:?}"), &dp, &want, 1e-9, 1e-4);
    }
}

#[test]
fn bce_forward_and_backward() {
    // A different odd shape, rank 3: losses do not care about layout.
    let shape = [3, 11, 13];
    let n: usize = shape.iter().product();
    let mut rng = Rng(22);
    // Inside the clamp with margin (FD must not straddle it); soft targets in [0, 1].
    let (p, t) = (f32_round(&rng.vec(n, 0.02, 0.98)), f32_round(&rng.vec(n, 0.0, 1.0)));
    let (l, dp) = run_loss(Loss::Bce, &shape, &p, &t);
    let (lo, hi) = bounds();
    // ln in f32 has ~1e-7 relative error; terms are O(1..4).
    assert_close("bce forward", &[l], &[bce(&p, &t, lo, hi)], 1e-6, 1e-5);
    let want = fd_grad(&p, |p| G * bce(p, &t, lo, hi));
    // |dp| <= 1/(0.02 * 0.98) / n ~ 0.12; 1/(q(1-q)) in f32 ~1e-7 relative.
    assert_close("bce backward", &dp, &want, 1e-9, 1e-4);
}

#[test]
fn bce_clamps_and_zeroes_the_gradient_outside() {
    let (lo, hi) = bounds();
    // Saturated probabilities as a sigmoid in f32 produces them (0, 1, below and above the
    // clamp), out-of-range values, and two ordinary ones that keep their gradient.
    let p = f32_round(&[0.0, 1.0, 1e-9, 0.99999999, -0.1, 1.2, 0.3, 0.6]);
    let t = [1.0, 0.0, 0.7, 0.2, 0.5, 0.5, 1.0, 0.0];
    let (l, dp) = run_loss(Loss::Bce, &[8], &p, &t);
    // -ln(1e-7) = 16.1: the clamp keeps the loss finite at p = 0 with target 1.
    assert_close("clamped bce forward", &[l], &[bce(&p, &t, lo, hi)], 1e-5, 1e-5);
    assert!(dp[..6].iter().all(|&g| g == 0.0), "clamped gradients should be exactly 0: {dp:?}");
    let want = [G * (0.3 - 1.0) / (0.3 * 0.7) / 8.0, G * 0.6 / (0.6 * 0.4) / 8.0];
    assert_close("unclamped gradients", &dp[6..], &want, 1e-8, 1e-5);
}

#[test]
fn per_image_mse_and_psnr() {
    // An odd size, then one of whole vec4s (the `_vec4` terms).
    for shape in [[3, 2, 5, 7], [3, 2, 5, 8]] {
        let n: usize = shape.iter().product();
        let mut rng = Rng(23);
        let (a, b) = (f32_round(&rng.vec(n, 0.0, 1.0)), f32_round(&rng.vec(n, 0.0, 1.0)));
        let (ta, tb, tm) = (upload(&shape, &a), upload(&shape, &b), zeros(&[3]));
        run(|p| gpu_per_image_mse(gpu(), p, &ta, &tb, &tm));
        assert_close(&format!("per-image mse {shape:?}"), &download(&tm), &per_image_mse(&a, &b, 3), 1e-7, 1e-5);
    }

    assert!((psnr_from_mse(0.01, 1.0) - 20.0).abs() < 1e-5);
    assert!((psnr_from_mse(1e-4, 1.0) - 40.0).abs() < 1e-4);
    // 8-bit peak: 255^2 / 65.025 = 1000, 30 dB.
    assert!((psnr_from_mse(65.025, 255.0) - 30.0).abs() < 1e-4);
    assert_eq!(psnr_from_mse(0.0, 1.0), f32::INFINITY);
    assert!(psnr_from_mse(-1.0, 1.0).is_nan());
}

#[test]
fn bad_shapes_are_errors_not_panics() {
    let (p, t, one, two) = (zeros(&[2, 3]), zeros(&[3, 2]), zeros(&[1]), zeros(&[2]));
    let err = gpu().run(|pass| Loss::Mse.forward(gpu(), pass, &p, &t, &one)).unwrap_err().to_string();
    assert!(err.contains("mse_forward") && err.contains("target"), "{err}");
    let err = gpu().run(|pass| Loss::Bce.forward(gpu(), pass, &p, &p, &two)).unwrap_err().to_string();
    assert!(err.contains("bce_forward") && err.contains("loss"), "{err}");
    let err = gpu().run(|pass| Loss::Bce.backward(gpu(), pass, &p, &p, &two, &p)).unwrap_err().to_string();
    assert!(err.contains("bce_backward") && err.contains("loss gradient"), "{err}");
    let err = gpu().run(|pass| Loss::Mse.backward(gpu(), pass, &p, &p, &one, &t)).unwrap_err().to_string();
    assert!(err.contains("mse_backward") && err.contains("prediction gradient"), "{err}");
    let err = gpu().run(|pass| gpu_per_image_mse(gpu(), pass, &p, &p, &one)).unwrap_err().to_string();
    assert!(err.contains("per_image_mse") && err.contains("mse"), "{err}");
}
