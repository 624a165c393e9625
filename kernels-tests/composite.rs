//! Front-to-back compositing (`shaders/composite.wgsl`) against its f64 reference: forward on
//! odd, non-square shapes (1, 3 and 4 channels, depth 1 to 9), and the gradient of every input
//! value (occupancy and premultiplied channels) against central finite differences of
//! `Σ r·composite(x)`. Plus two cases whose answer is known without the reference: a solid
//! voxel hides everything behind it, and an empty column composites to zero.
//!
//! Tolerance: the forward sums at most 9 products of at most 10 f32 factors (1e-6 absolute,
//! 1e-5 relative); the backward adds one more product and sum per voxel (same bounds, as
//! gradients here are O(1)). Finite differences of a polynomial of degree <= D in each
//! variable, with h = 1e-6, are exact to ~1e-9.

mod common;
mod reference;
use common::*;
use reference::composite::composite as composite_ref;
use rendernet::ops::composite;

#[test]
fn composite_matches_the_reference_and_finite_differences() {
    for (n, c, d, h, w) in [(2usize, 4usize, 5usize, 3usize, 2usize), (1, 3, 9, 2, 5), (3, 1, 1, 1, 3), (1, 4, 7, 1, 1)] {
        let hw = h * w;
        let mut rng = Rng((n * 100 + c * 10 + d) as u64);
        // Occupancy in [0, 1] with some exact 0s and 1s (solid voxels, empty space).
        let mut x = f32_round(&rng.vec(n * c * d * hw, -1.0, 1.0));
        for b in 0..n {
            for z in 0..d {
                for s in 0..hw {
                    let i = ((b * c) * d + z) * hw + s;
                    x[i] = match (b + z + s) % 5 {
                        0 => 0.0,
                        1 => 1.0,
                        _ => x[i].abs(),
                    };
                }
            }
        }
        let (xs, ys) = ([n, c, d, h, w], [n, c, h, w]);
        let (tx, ty) = (upload(&xs, &x), zeros(&ys));
        run(|p| composite::forward(gpu(), p, &tx, &ty));
        assert_close("composite forward", &download(&ty), &composite_ref(&x, n, c, d, hw), 1e-6, 1e-5);
        let r = f32_round(&rng.vec(n * c * hw, -1.0, 1.0));
        let (tdy, tdx) = (upload(&ys, &r), zeros(&xs));
        run(|p| composite::backward(gpu(), p, &tx, &tdy, &tdx));
        let want = fd_grad(&x, |x| dot(&r, &composite_ref(x, n, c, d, hw)));
        assert_close("composite d/dx", &download(&tdx), &want, 1e-6, 1e-5);
    }
}

#[test]
fn a_solid_voxel_hides_what_lies_behind_it() {
    // One column, depth 4, 2 channels; camera end is depth 3. Voxel 2 is solid (o = 1, value
    // 0.5): voxel 3 in front (o = 0.25, value 0.1) shows through its 0.25, voxels 1 and 0
    // behind are hidden whatever they hold.
    let o = [0.7, 0.9, 1.0, 0.25];
    let v = [5.0, 7.0, 0.5, 0.1];
    let x: Vec<f64> = o.iter().chain(&v).copied().collect();
    let tx = upload(&[1, 2, 4, 1, 1], &x);
    let ty = zeros(&[1, 2, 1, 1]);
    run(|p| composite::forward(gpu(), p, &tx, &ty));
    let y = download(&ty);
    assert!((y[0] - 1.0).abs() < 1e-6, "coverage {}", y[0]);
    assert!((y[1] - (0.1 + 0.75 * 0.5)).abs() < 1e-6, "colour {}", y[1]);
    let empty = upload(&[1, 2, 4, 1, 1], &[0.0; 8]);
    run(|p| composite::forward(gpu(), p, &empty, &ty));
    assert_eq!(download(&ty), [0.0, 0.0]);
    assert!(composite::output_shape(&[1, 2, 3, 4]).is_err(), "a 4D input was accepted");
}
