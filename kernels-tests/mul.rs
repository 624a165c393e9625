//! The channel-broadcast product (`shaders/mul.wgsl`) against its f64 reference: forward on
//! odd shapes with a one-channel mask and with a full one, and both gradients against
//! central finite differences of `Σ r·mul(x, m)`.
//!
//! Tolerance: the forward is one f32 product per element (1e-6); the mask gradient sums up to
//! 3 products in f32 (1e-6 absolute, 1e-5 relative); finite differences of a bilinear
//! function are exact up to f64 rounding.

mod common;
mod reference;
use common::*;
use reference::mul::mul as mul_ref;
use rendernet::ops::mul;

#[test]
fn mul_matches_the_reference_and_finite_differences() {
    for (n, c, cm, sp) in [(2usize, 3usize, 1usize, vec![3usize, 4, 5]), (3, 2, 2, vec![7usize]), (1, 4, 1, vec![5, 3])] {
        let s: usize = sp.iter().product();
        let shape = |ch: usize| [&[n, ch][..], &sp[..]].concat();
        let mut rng = Rng((c * 10 + cm) as u64);
        let (x, m) = (f32_round(&rng.vec(n * c * s, -1.0, 1.0)), f32_round(&rng.vec(n * cm * s, -1.0, 1.0)));
        let (tx, tm, ty) = (upload(&shape(c), &x), upload(&shape(cm), &m), zeros(&shape(c)));
        run(|p| mul::forward(gpu(), p, &tx, &tm, &ty));
        assert_close("mul forward", &download(&ty), &mul_ref(&x, &m, n, c, cm, s), 1e-6, 0.0);
        let r = f32_round(&rng.vec(n * c * s, -1.0, 1.0));
        let (dy, dx, dm) = (upload(&shape(c), &r), zeros(&shape(c)), zeros(&shape(cm)));
        run(|p| mul::backward_x(gpu(), p, &dy, &tm, &dx));
        run(|p| mul::backward_mask(gpu(), p, &tx, &dy, &dm));
        assert_close("d/dx", &download(&dx), &fd_grad(&x, |x| dot(&r, &mul_ref(x, &m, n, c, cm, s))), 1e-6, 1e-5);
        assert_close("d/dm", &download(&dm), &fd_grad(&m, |m| dot(&r, &mul_ref(&x, m, n, c, cm, s))), 1e-6, 1e-5);
    }
    let err = mul::output_shape(&[2, 3, 4], &[2, 2, 4]).unwrap_err().to_string();
    assert!(err.contains("1 or C"), "{err}");
    assert!(mul::output_shape(&[2, 3, 4], &[1, 1, 4]).is_err(), "batch sizes differ");
}
