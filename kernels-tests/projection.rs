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

/// The projection then a PReLU in the projection's own dispatches (what a forward-only graph
/// run does with the projection unit's activation) against the f64 projection then PReLU:
/// slopes 0, negative and above 1; the plain forward is unchanged; the reference kernel,
/// which applies no PReLU, refuses with a clear error.
#[test]
fn texture_projection_with_fused_prelu() {
    // What the texture kernels need, not `fuses_prelu` itself (a broken one would skip the test).
    if !(gpu().has_subgroups_of_8() && gpu().reads_rgba32f_storage()) {
        eprintln!("skipped: this adapter does not run the texture kernels");
        return;
    }
    for (n, c, d, h, w, o, seed) in [(2usize, 3usize, 5usize, 4usize, 7usize, 6usize, 21u64), (1, 7, 3, 3, 11, 19, 22)] {
        let (k, s) = (c * d, h * w);
        let mut rng = Rng(seed);
        let x = f32_round(&rng.vec(n * k * s, -1.0, 1.0));
        let wt = f32_round(&rng.vec(o * k, -0.5, 0.5));
        let b = f32_round(&rng.vec(o, -0.5, 0.5));
        let mut alpha = f32_round(&rng.vec(o, -0.5, 1.5));
        alpha[0] = 0.0;
        let (xs, ws) = ([n, c, d, h, w], [o, k, 1, 1]);
        assert!(projection::fuses_prelu(ConvKernel::Texture, gpu(), &xs, &ws).unwrap(), "{xs:?} should fuse");
        let (tx, tw, tb, ta, ty) = (upload(&xs, &x), upload(&ws, &wt), upload(&[o], &b), upload(&[o], &alpha), zeros(&[n, o, h, w]));
        run(|p| projection::forward_prelu(ConvKernel::Texture, gpu(), p, &tx, &tw, &tb, &ta, &ty));
        let plain = proj_ref(&x, &wt, &b, n, k, o, s);
        let want = reference::activations::prelu(&plain, &alpha, o, s);
        assert_close(&format!("{xs:?} projection + prelu"), &download(&ty), &want, 1e-5, 1e-4);
        let y = zeros(&[n, o, h, w]);
        run(|p| projection::forward(ConvKernel::Texture, gpu(), p, &tx, &tw, &tb, &y));
        assert_close(&format!("{xs:?} projection"), &download(&y), &plain, 1e-5, 1e-4);
    }
    let (x, w, b, a, y) = (zeros(&[1, 2, 3, 4, 4]), zeros(&[5, 6, 1, 1]), zeros(&[5]), zeros(&[5]), zeros(&[1, 5, 4, 4]));
    assert!(!projection::fuses_prelu(ConvKernel::Reference, gpu(), x.shape(), w.shape()).unwrap());
    let err = gpu().run(|p| projection::forward_prelu(ConvKernel::Reference, gpu(), p, &x, &w, &b, &a, &y)).unwrap_err();
    assert!(err.to_string().contains("fuses_prelu"), "{err}");
}
