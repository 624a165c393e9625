//! Channel concatenation (`shaders/concat.wgsl`) and reshape, against f64 references: forward
//! on odd shapes (spatial and vector parts), backward against finite differences of
//! `Σ r·concat(a, b)`, and both inside a graph that turns a conv-shaped value into a
//! fully-connected layer's input (reshape, projection as the FC layer, concat with a second
//! input that wants no gradient), whose gradients are checked end to end. Concatenation along
//! axis 0 and narrowing the same way, and inside a graph that runs three sibling convs as one
//! (the Phong heads), against the three convs run apart.
//!
//! Tolerance: concat and reshape copy values, so they must match exactly up to f32 rounding
//! (1e-6); the graph test sums <= 12 products in f32 (1e-5 relative).

mod common;
mod reference;
use common::*;
use reference::{concat::concat as concat_ref, concat::narrow as narrow_ref, loss as lref, projection::projection as proj_ref};
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

#[test]
fn concatenates_along_axis_0_and_narrows_like_the_reference() {
    // Parts [3, 5, 2], [1, 5, 2], [4, 5, 2]: N = 1 of the channel kernels, odd row sizes.
    let rows = [3usize, 1, 4];
    let rest = [5usize, 2];
    let r: usize = rest.iter().product();
    let shape = |o: usize| [&[o][..], &rest[..]].concat();
    let mut rng = Rng(11);
    let parts: Vec<Vec<f64>> = rows.iter().map(|&o| f32_round(&rng.vec(o * r, -1.0, 1.0))).collect();
    let total: usize = rows.iter().sum();
    let cat = |ps: &[Vec<f64>]| ps.concat();
    let tp: Vec<_> = rows.iter().zip(&parts).map(|(&o, v)| upload(&shape(o), v)).collect();
    let ty = zeros(&shape(total));
    run(|p| concat::forward_axis0(gpu(), p, &tp.iter().collect::<Vec<_>>(), &ty));
    assert_close("concat axis 0", &download(&ty), &cat(&parts), 1e-6, 0.0);
    let w = f32_round(&rng.vec(total * r, -1.0, 1.0));
    let dy = upload(&shape(total), &w);
    let dp: Vec<_> = rows.iter().map(|&o| zeros(&shape(o))).collect();
    let shapes: Vec<Vec<usize>> = rows.iter().map(|&o| shape(o)).collect();
    let refs: Vec<&[usize]> = shapes.iter().map(Vec::as_slice).collect();
    // The middle part asks for no gradient and must stay zero.
    run(|p| concat::backward_axis0(gpu(), p, &dy, &refs, &[Some(&dp[0]), None, Some(&dp[2])]));
    for k in [0, 2] {
        let f = |v: &[f64]| {
            let mut ps = parts.clone();
            ps[k] = v.to_vec();
            dot(&w, &cat(&ps))
        };
        assert_close(&format!("d/dpart{k}"), &download(&dp[k]), &fd_grad(&parts[k], f), 1e-6, 1e-6);
    }
    assert!(download(&dp[1]).iter().all(|&v| v == 0.0));
    assert!(concat::output_shape_axis0(&[&[3, 5, 2], &[1, 5, 3]]).unwrap_err().to_string().contains("outside axis 0"));

    // Narrowing [2, 7, 3, 5] to channels 2..6, and its backward (zero outside the range).
    let (n, c, s, start, len) = (2usize, 7usize, 15usize, 2usize, 4usize);
    let x = f32_round(&rng.vec(n * c * s, -1.0, 1.0));
    let (tx, ty) = (upload(&[n, c, 3, 5], &x), zeros(&[n, len, 3, 5]));
    run(|p| concat::narrow(gpu(), p, &tx, start, &ty));
    assert_close("narrow", &download(&ty), &narrow_ref(&x, n, c, s, start, len), 1e-6, 0.0);
    let w = f32_round(&rng.vec(n * len * s, -1.0, 1.0));
    let (dy, dx) = (upload(&[n, len, 3, 5], &w), upload(&[n, c, 3, 5], &vec![7.0; n * c * s]));
    run(|p| concat::narrow_backward(gpu(), p, &dy, start, &dx));
    let fd = fd_grad(&x, |x| dot(&w, &narrow_ref(x, n, c, s, start, len)));
    assert_close("narrow backward", &download(&dx), &fd, 1e-6, 1e-6);
    // Added into a gradient already there (another range's): `acc` + the same gradient, the
    // channels outside the range untouched.
    let acc = f32_round(&rng.vec(n * c * s, -1.0, 1.0));
    let tacc = upload(&[n, c, 3, 5], &acc);
    run(|p| concat::narrow_backward_add(gpu(), p, &dy, start, &tacc));
    let want: Vec<f64> = acc.iter().zip(&fd).map(|(a, g)| a + g).collect();
    assert_close("narrow backward added", &download(&tacc), &want, 1e-6, 1e-6);
    let err = gpu().run(|p| concat::narrow_backward_add(gpu(), p, &dy, 4, &tacc)).unwrap_err();
    assert!(err.to_string().contains("start + len <= C"), "{err}");
    assert!(concat::narrow_shape(&[2, 7, 3], 5, 3).unwrap_err().to_string().contains("start + len <= C"));
}

/// x [1, 5, 9, 7] -> three sibling 3x3 convs (3, 2 and 1 channels) as one: their weights and
/// biases concatenated along axis 0, one conv, each output narrowed out -> MSE against
/// targets. Against the same three convs run apart: the losses and every gradient (the six
/// parameters and x) agree.
#[test]
fn sibling_convs_run_as_one_match_the_convs_run_apart() {
    use rendernet::ops::conv::{Conv, Padding};
    let (c, h, w) = (5usize, 9usize, 7usize);
    let outs = [3usize, 2, 1];
    let conv = || Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same));
    let build = |joint: bool| {
        let mut g = Graph::new();
        let x = g.input("x", &[1, c, h, w]).unwrap();
        let mut ps = Vec::new();
        for (k, &o) in outs.iter().enumerate() {
            ps.push(g.param(&format!("c{k}.weight"), &[o, c, 3, 3], Init::Xavier).unwrap());
            ps.push(g.param(&format!("c{k}.bias"), &[o], Init::Constant(0.1)).unwrap());
        }
        let ys: Vec<_> = if joint {
            let wt = g.apply("w", Op::ConcatAxis0(outs.to_vec()), &[ps[0], ps[2], ps[4]]).unwrap();
            let bt = g.apply("b", Op::ConcatAxis0(outs.to_vec()), &[ps[1], ps[3], ps[5]]).unwrap();
            let y = g.apply("joint", conv(), &[x, wt, bt]).unwrap();
            let starts = [0, 3, 5];
            (0..3).map(|k| g.apply(&format!("y{k}"), Op::Narrow(starts[k], outs[k]), &[y]).unwrap()).collect()
        } else {
            (0..3).map(|k| g.apply(&format!("y{k}"), conv(), &[x, ps[2 * k], ps[2 * k + 1]]).unwrap()).collect()
        };
        let mut loss = None;
        for (k, &y) in ys.iter().enumerate() {
            let t = g.input(&format!("t{k}"), &[1, outs[k], h, w]).unwrap();
            let l = g.apply(&format!("loss{k}"), Op::Loss(Loss::Mse), &[y, t]).unwrap();
            loss = Some(match loss {
                None => l,
                Some(prev) => g.apply(&format!("sum{k}"), Op::Add, &[prev, l]).unwrap(),
            });
        }
        (g, x, ps, loss.unwrap())
    };
    let mut rng = Rng(21);
    let xs: Vec<f32> = rng.vec(c * h * w, -1.0, 1.0).iter().map(|&v| v as f32).collect();
    let ts: Vec<Vec<f32>> = outs.iter().map(|&o| rng.vec(o * h * w, 0.0, 1.0).iter().map(|&v| v as f32).collect()).collect();
    let mut results = Vec::new();
    for joint in [false, true] {
        let (g, x, ps, loss) = build(joint);
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &xs).unwrap();
        for (k, t) in ts.iter().enumerate() {
            ex.feed(gpu(), g.value(&format!("t{k}")).unwrap(), t).unwrap();
        }
        ex.want_grad(x);
        ex.backward(gpu(), loss).unwrap();
        let f64s = |v: Vec<f32>| v.into_iter().map(f64::from).collect::<Vec<_>>();
        let mut r = vec![f64s(ex.read(gpu(), loss).unwrap()), f64s(ex.grad(gpu(), x).unwrap())];
        r.extend(ps.iter().map(|&p| f64s(ex.grad(gpu(), p).unwrap())));
        results.push(r);
    }
    // The same sums in other kernels' orders: f32 rounding, ~1e-6 of values ~1e-1.
    let names = ["loss", "d/dx", "d/dw0", "d/db0", "d/dw1", "d/db1", "d/dw2", "d/db2"];
    for (k, name) in names.iter().enumerate() {
        assert_close(name, &results[1][k], &results[0][k], 1e-6, 1e-4);
    }
}
