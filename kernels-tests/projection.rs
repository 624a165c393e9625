//! The projection unit's 1x1 conv over depth-folded channels: forward against the f64
//! reference, and input, weight and bias gradients against finite differences.

mod common;
mod reference;
use common::*;
use reference::projection::projection as proj_ref;
use rendernet::ops::conv::ConvKernel;
use rendernet::ops::projection;

/// Every family: `Reference` is `projection.wgsl` (the oracle), `Buffers` and `Texture` the
/// tiled conv kernels run as a matmul.
const KERNELS: [ConvKernel; 3] = [ConvKernel::Reference, ConvKernel::Buffers, ConvKernel::Texture];

#[test]
fn projection_forward_and_backward() {
    // x [N, C, D, H, W] = [2, 3, 5, 4, 7] folds to K = 15; O = 6; S = 28.
    for k in KERNELS {
        check(k, 2, 3, 5, 4, 7, 6, 11);
    }
}

#[test]
fn wide_projection_forward_and_backward() {
    // O = 19 not a multiple of the tiled kernels' 16-channel tile, K = 21 not a multiple of
    // 4 and W = 11 not a multiple of 8.
    for k in KERNELS {
        check(k, 2, 7, 3, 3, 11, 19, 12);
    }
}

#[allow(clippy::too_many_arguments)]
fn check(kernel: ConvKernel, n: usize, c: usize, d: usize, h: usize, w: usize, o: usize, seed: u64) {
    let (k, s) = (c * d, h * w);
    let mut rng = Rng(seed);
    let x = f32_round(&rng.vec(n * k * s, -1.0, 1.0));
    let wt = f32_round(&rng.vec(o * k, -0.5, 0.5));
    let b = f32_round(&rng.vec(o, -0.5, 0.5));
    let r = f32_round(&rng.vec(n * o * s, -1.0, 1.0));
    let xs = [n, c, d, h, w];
    let (tx, tw, tb, ty) = (upload(&xs, &x), upload(&[o, k, 1, 1], &wt), upload(&[o], &b), zeros(&[n, o, h, w]));
    let tr = upload(&[n, o, h, w], &r);
    let (tdx, tdw, tdb) = (zeros(&xs), zeros(&[o, k, 1, 1]), zeros(&[o]));
    run(|p| {
        projection::forward(kernel, gpu(), p, &tx, &tw, &tb, &ty)?;
        projection::backward_input(kernel, gpu(), p, &tr, &tw, &tdx)?;
        projection::backward_weight(kernel, gpu(), p, &tx, &tr, &tdw)?;
        projection::backward_bias(gpu(), p, &tr, &tdb)
    });
    // Sums of K <= 21 (forward), O <= 19 (dx), N*S <= 66 (dw, db) terms of size <= 1.
    let name = |what: &str| format!("projection {what} ({kernel:?})");
    assert_close(&name("forward"), &download(&ty), &proj_ref(&x, &wt, &b, n, k, o, s), 1e-5, 1e-4);
    let l = |x: &[f64], w: &[f64], b: &[f64]| dot(&r, &proj_ref(x, w, b, n, k, o, s));
    assert_close(&name("backward input"), &download(&tdx), &fd_grad(&x, |x| l(x, &wt, &b)), 1e-5, 1e-4);
    assert_close(&name("backward weight"), &download(&tdw), &fd_grad(&wt, |w| l(&x, w, &b)), 1e-5, 1e-4);
    assert_close(&name("backward bias"), &download(&tdb), &fd_grad(&b, |b| l(&x, &wt, b)), 1e-5, 1e-4);
}

#[test]
fn projection_rejects_mismatched_weights() {
    let (tx, tw, tb, ty) = (zeros(&[1, 2, 3, 4, 4]), zeros(&[5, 7, 1, 1]), zeros(&[5]), zeros(&[1, 5, 4, 4]));
    let err = gpu().run(|p| projection::forward(ConvKernel::Auto, gpu(), p, &tx, &tw, &tb, &ty)).unwrap_err();
    assert!(err.to_string().contains("K = C*D = 6"), "{err}");
}
