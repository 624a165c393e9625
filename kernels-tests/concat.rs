//! Channel concatenation (`shaders/concat.wgsl`) and reshape, against f64 references: forward
//! on odd shapes (spatial and vector parts), backward against finite differences of
//! `Σ r·concat(a, b)`, and both inside a graph that turns a conv-shaped value into a
//! fully-connected layer's input (reshape, projection as the FC layer, concat with a second
//! input that wants no gradient), whose gradients are checked end to end.
//!
//! Tolerance: concat and reshape copy values, so they must match exactly up to f32 rounding
//! (1e-6); the graph test sums <= 12 products in f32 (1e-5 relative).

mod common;
mod reference;
use common::*;
use reference::{concat::concat as concat_ref, loss as lref, projection::projection as proj_ref};
use rendernet::graph::{Executor, Graph, Init, Op};
use rendernet::ops::{concat, loss::Loss};

#[test]
fn concatenates_and_splits_like_the_reference() {
    // [N, C, H, W] parts with odd sizes, then [N, C] vectors (no spatial axes).
    for (n, c1, c2, sp) in [(2usize, 3usize, 4usize, vec![5usize, 3usize]), (3, 5, 2, vec![])] {
        let s: usize = sp.iter().product();
        let shape = |c: usize| [&[n, c][..], &sp[..]].concat();
        let mut rng = Rng(c1 as u64);
        let (a, b) = (f32_round(&rng.vec(n * c1 * s, -1.0, 1.0)), f32_round(&rng.vec(n * c2 * s, -1.0, 1.0)));
        let (ta, tb, ty) = (upload(&shape(c1), &a), upload(&shape(c2), &b), zeros(&shape(c1 + c2)));
        run(|p| concat::forward(gpu(), p, &[&ta, &tb], &ty));
        assert_close("concat forward", &download(&ty), &concat_ref(&a, &b, n, c1, c2, s), 1e-6, 0.0);
        let r = f32_round(&rng.vec(n * (c1 + c2) * s, -1.0, 1.0));
        let (dy, da, db) = (upload(&shape(c1 + c2), &r), zeros(&shape(c1)), zeros(&shape(c2)));
        let (sa, sb) = (shape(c1), shape(c2));
        run(|p| concat::backward(gpu(), p, &dy, &[&sa, &sb], &[Some(&da), Some(&db)]));
        assert_close("d/da", &download(&da), &fd_grad(&a, |a| dot(&r, &concat_ref(a, &b, n, c1, c2, s))), 1e-6, 1e-6);
        assert_close("d/db", &download(&db), &fd_grad(&b, |b| dot(&r, &concat_ref(&a, b, n, c1, c2, s))), 1e-6, 1e-6);
    }
    let bad = [&[2usize, 3, 4][..], &[2, 3, 5][..]];
    assert!(concat::output_shape(&bad).unwrap_err().to_string().contains("outside axis 1"));
}

/// x [2, 3, 2, 2] -> reshape [2, 12, 1, 1] -> FC (projection, w [5, 12, 1, 1]) -> concat
/// with v [2, 4, 1, 1] (no gradient wanted) -> MSE against a target [2, 9, 1, 1].
#[test]
fn reshape_fc_and_concat_in_a_graph_match_finite_differences() {
    let (n, k, o, cv) = (2, 12, 5, 4);
    let mut g = Graph::new();
    let x = g.input("x", &[n, 3, 2, 2]).unwrap();
    let v = g.input("v", &[n, cv, 1, 1]).unwrap();
    let target = g.input("target", &[n, o + cv, 1, 1]).unwrap();
    let w = g.param("fc.weight", &[o, k, 1, 1], Init::Xavier).unwrap();
    let b = g.param("fc.bias", &[o], Init::Constant(0.1)).unwrap();
    let flat = g.apply("flat", Op::Reshape(vec![n, k, 1, 1]), &[x]).unwrap();
    let h = g.apply("fc", Op::Projection, &[flat, w, b]).unwrap();
    let cat = g.apply("cat", Op::Concat, &[h, v]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[cat, target]).unwrap();
    assert!(g.apply("bad", Op::Reshape(vec![n, 5]), &[x]).unwrap_err().to_string().contains("sizes differ"));
    let mut rng = Rng(5);
    let (xs, vs, ts) = (f32_round(&rng.vec(n * k, -1.0, 1.0)), f32_round(&rng.vec(n * cv, -1.0, 1.0)), f32_round(&rng.vec(n * (o + cv), 0.0, 1.0)));
    let mut ex = Executor::new(gpu(), g.clone(), 1).unwrap();
    let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    ex.feed(gpu(), x, &f32s(&xs)).unwrap();
    ex.feed(gpu(), v, &f32s(&vs)).unwrap();
    ex.feed(gpu(), target, &f32s(&ts)).unwrap();
    ex.want_grad(x);
    ex.training = false;
    ex.backward(gpu(), loss).unwrap();
    let (ws, bs): (Vec<f64>, Vec<f64>) = (
        ex.read(gpu(), w).unwrap().iter().map(|&x| x as f64).collect(),
        ex.read(gpu(), b).unwrap().iter().map(|&x| x as f64).collect(),
    );
    let reference = |xs: &[f64], ws: &[f64], bs: &[f64]| lref::mse(&concat_ref(&proj_ref(xs, ws, bs, n, k, o, 1), &vs, n, o, cv, 1), &ts);
    let loss_gpu = ex.read(gpu(), loss).unwrap()[0] as f64;
    assert!((loss_gpu - reference(&xs, &ws, &bs)).abs() < 1e-6, "loss {loss_gpu}");
    let grad = |v| ex.grad(gpu(), v).unwrap().iter().map(|&x| x as f64).collect::<Vec<_>>();
    assert_close("d/dx through reshape", &grad(x), &fd_grad(&xs, |xs| reference(xs, &ws, &bs)), 1e-6, 1e-5);
    assert_close("d/dw", &grad(w), &fd_grad(&ws, |ws| reference(&xs, ws, &bs)), 1e-6, 1e-5);
    assert_close("d/db", &grad(b), &fd_grad(&bs, |bs| reference(&xs, &ws, bs)), 1e-6, 1e-5);
    assert!(ex.grad(gpu(), v).is_err(), "v asked for no gradient");
}
