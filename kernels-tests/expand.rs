//! Broadcast over space (`shaders/expand.wgsl`, backward through `reduce.wgsl`) against its
//! f64 reference: forward on odd shapes, and the gradient against central finite
//! differences of `Σ r·expand(x)`.
//!
//! Tolerance: the forward copies (exact: 0); the gradient sums up to 105 f32 products in a
//! fixed tree (1e-5 absolute, 1e-5 relative); finite differences of a linear function are
//! exact up to f64 rounding.

mod common;
mod reference;
use common::*;
use reference::expand::expand as expand_ref;
use rendernet::ops::expand;

#[test]
fn expand_matches_the_reference_and_finite_differences() {
    for (n, c, from, to) in [(2usize, 3usize, vec![1usize, 1, 1], vec![3usize, 5, 7]), (3, 1, vec![], vec![5usize, 3]), (1, 4, vec![1, 1], vec![9usize])] {
        let s: usize = to.iter().product();
        let (xs, ys) = ([&[n, c][..], &from[..]].concat(), [&[n, c][..], &to[..]].concat());
        assert_eq!(expand::output_shape(&xs, &to).unwrap(), ys);
        let mut rng = Rng((n * 10 + c + s) as u64);
        let x = f32_round(&rng.vec(n * c, -1.0, 1.0));
        let (tx, ty) = (upload(&xs, &x), zeros(&ys));
        run(|p| expand::forward(gpu(), p, &tx, &ty));
        assert_close("expand forward", &download(&ty), &expand_ref(&x, n * c, s), 0.0, 0.0);
        let r = f32_round(&rng.vec(n * c * s, -1.0, 1.0));
        let (dy, dx) = (upload(&ys, &r), zeros(&xs));
        run(|p| expand::backward(gpu(), p, &dy, &dx));
        assert_close("d/dx", &download(&dx), &fd_grad(&x, |x| dot(&r, &expand_ref(x, n * c, s))), 1e-5, 1e-5);
    }
    let err = expand::output_shape(&[2, 3, 4], &[5]).unwrap_err().to_string();
    assert!(err.contains("[N, C, 1...]"), "{err}");
    assert!(expand::output_shape(&[2, 3, 1], &[0, 4]).is_err(), "a zero size");
}
