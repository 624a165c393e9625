//! The graph executor end to end: gradients of a multi-op network against finite
//! differences of the f64 references, for parameters and for an input; one submit per
//! step; save/load round trips; checkpoint resume reproducing an uninterrupted run; and
//! clear errors for corrupt or mismatched files.

#[path = "../kernels-tests/common/mod.rs"]
mod common;
#[path = "../kernels-tests/reference/mod.rs"]
mod reference;

use common::*;
use reference::{activations as act, loss as lref, projection::projection as proj_ref};
use rendernet::graph::{Executor, Graph, Init, Op, Value};
use rendernet::ops::{adam::Adam, loss::Loss};

// x [N, C, D, H, W] -> prelu -> projection (K = C*D) -> (sigmoid + elu, so the projection's
// output feeds two nodes and its gradient is accumulated) -> mse against a target.
const N: usize = 2;
const C: usize = 3;
const D: usize = 4;
const H: usize = 5;
const W: usize = 3;
const O: usize = 5;

struct Net {
    graph: Graph,
    x: Value,
    target: Value,
    alpha: Value,
    w: Value,
    b: Value,
    y: Value,
    loss: Value,
}

fn net() -> Net {
    let mut g = Graph::new();
    let x = g.input("x", &[N, C, D, H, W]).unwrap();
    let target = g.input("target", &[N, O, H, W]).unwrap();
    let alpha = g.param("act.alpha", &[C], Init::Constant(0.25)).unwrap();
    let w = g.param("proj.weight", &[O, C * D, 1, 1], Init::Xavier).unwrap();
    let b = g.param("proj.bias", &[O], Init::Constant(0.001)).unwrap();
    let h = g.apply("act", Op::Prelu, &[x, alpha]).unwrap();
    let p = g.apply("proj", Op::Projection, &[h, w, b]).unwrap();
    let s = g.apply("sig", Op::Sigmoid, &[p]).unwrap();
    let e = g.apply("elu", Op::Elu(1.0), &[p]).unwrap();
    let y = g.apply("sum", Op::Add, &[s, e]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[y, target]).unwrap();
    Net { graph: g, x, target, alpha, w, b, y, loss }
}

fn reference_loss(x: &[f64], t: &[f64], alpha: &[f64], w: &[f64], b: &[f64]) -> f64 {
    let h = act::prelu(x, alpha, C, D * H * W);
    let p = proj_ref(&h, w, b, N, C * D, O, H * W);
    let y: Vec<f64> = act::sigmoid(&p).iter().zip(act::elu(1.0, &p)).map(|(a, b)| a + b).collect();
    lref::mse(&y, t)
}

fn f32v(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

fn fed(seed: u64) -> (Net, Executor, Vec<f64>, Vec<f64>) {
    let n = net();
    let mut ex = Executor::new(gpu(), n.graph.clone(), 7).unwrap();
    let mut rng = Rng(seed);
    // Away from PReLU's kink at 0 so finite differences are clean.
    let x: Vec<f64> = f32_round(&rng.vec(N * C * D * H * W, -2.0, 2.0)).into_iter().map(|v| if v.abs() < 0.01 { 0.5 } else { v }).collect();
    let t = f32_round(&rng.vec(N * O * H * W, 0.0, 1.0));
    ex.feed(gpu(), n.x, &f32v(&x)).unwrap();
    ex.feed(gpu(), n.target, &f32v(&t)).unwrap();
    ex.want_grad(n.x);
    ex.keep(n.y);
    ex.training = false;
    (n, ex, x, t)
}

fn read64(ex: &Executor, v: Value) -> Vec<f64> {
    ex.read(gpu(), v).unwrap().iter().map(|&x| x as f64).collect()
}

fn grad64(ex: &Executor, v: Value) -> Vec<f64> {
    ex.grad(gpu(), v).unwrap().iter().map(|&x| x as f64).collect()
}

#[test]
fn gradients_match_finite_differences_end_to_end() {
    let (n, mut ex, x, t) = fed(1);
    let stats = ex.backward(gpu(), n.loss).unwrap();
    assert_eq!(stats.submits, 1);
    assert!(stats.dispatches >= 10, "{stats:?}");
    assert!(stats.peak_bytes <= stats.tensor_bytes + 4096, "{stats:?}");
    let (alpha, w, b) = (read64(&ex, n.alpha), read64(&ex, n.w), read64(&ex, n.b));
    let loss = read64(&ex, n.loss);
    assert!((loss[0] - reference_loss(&x, &t, &alpha, &w, &b)).abs() < 1e-5, "loss {loss:?}");
    // Sums of <= 12 terms then a mean over 150 values: f32 error ~1e-7 of gradients ~1e-2.
    let (atol, rtol) = (1e-6, 1e-3);
    assert_close("d loss / d x", &grad64(&ex, n.x), &fd_grad(&x, |x| reference_loss(x, &t, &alpha, &w, &b)), atol, rtol);
    assert_close("d loss / d alpha", &grad64(&ex, n.alpha), &fd_grad(&alpha, |a| reference_loss(&x, &t, a, &w, &b)), atol, rtol);
    assert_close("d loss / d w", &grad64(&ex, n.w), &fd_grad(&w, |w| reference_loss(&x, &t, &alpha, w, &b)), atol, rtol);
    assert_close("d loss / d b", &grad64(&ex, n.b), &fd_grad(&b, |b| reference_loss(&x, &t, &alpha, &w, b)), atol, rtol);
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("rendernet-graph-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

#[test]
fn saved_and_loaded_params_give_identical_outputs() {
    let (n, mut ex, _, _) = fed(2);
    ex.training = true;
    for _ in 0..3 {
        ex.train_step(gpu(), n.loss, &Adam::new(1e-2)).unwrap();
    }
    ex.forward(gpu()).unwrap();
    let y = ex.read(gpu(), n.y).unwrap();
    let path = tmp("params.safetensors");
    ex.save_params(gpu(), &path).unwrap();
    let (_, mut other, _, _) = fed(2);
    other.load_params(gpu(), &path).unwrap();
    other.forward(gpu()).unwrap();
    assert_eq!(other.read(gpu(), n.y).unwrap(), y);
}

#[test]
fn resuming_a_checkpoint_reproduces_the_uninterrupted_run() {
    let adam = Adam::new(5e-3);
    let (n, mut straight, _, _) = fed(3);
    straight.training = true;
    for _ in 0..4 {
        straight.train_step(gpu(), n.loss, &adam).unwrap();
    }
    let (_, mut first, _, _) = fed(3);
    first.training = true;
    for _ in 0..2 {
        first.train_step(gpu(), n.loss, &adam).unwrap();
    }
    let path = tmp("ckpt.safetensors");
    first.save_checkpoint(gpu(), &path).unwrap();
    let (_, mut resumed, _, _) = fed(3);
    resumed.training = true;
    resumed.load_checkpoint(gpu(), &path).unwrap();
    assert_eq!(resumed.step, 2);
    for _ in 0..2 {
        resumed.train_step(gpu(), n.loss, &adam).unwrap();
    }
    for v in [n.alpha, n.w, n.b] {
        assert_eq!(resumed.read(gpu(), v).unwrap(), straight.read(gpu(), v).unwrap(), "param {v:?}");
    }
}

#[test]
fn corrupt_or_mismatched_files_are_clear_errors() {
    let (n, mut ex, _, _) = fed(4);
    let bad = tmp("corrupt.safetensors");
    std::fs::write(&bad, b"definitely not safetensors").unwrap();
    let e = ex.load_params(gpu(), &bad).unwrap_err().to_string();
    assert!(e.contains("corrupt.safetensors") && e.contains("not a valid safetensors"), "{e}");
    // A file from another graph: every problem is listed at once.
    let mut g = Graph::new();
    g.param("proj.weight", &[O + 1, C * D, 1, 1], Init::Xavier).unwrap();
    g.param("other", &[3], Init::Constant(0.0)).unwrap();
    let ex2 = Executor::new(gpu(), g, 1).unwrap();
    let other = tmp("other.safetensors");
    ex2.save_params(gpu(), &other).unwrap();
    let e = ex.load_params(gpu(), &other).unwrap_err().to_string();
    for needle in ["missing 'act.alpha'", "'proj.weight' has shape [6, 12, 1, 1]", "missing 'proj.bias'", "unexpected 'other'"] {
        assert!(e.contains(needle), "'{needle}' not in: {e}");
    }
    assert!(ex.feed(gpu(), n.x, &[f32::NAN]).is_err());
    let e = ex.feed(gpu(), n.x, &vec![f32::NAN; N * C * D * H * W]).unwrap_err().to_string();
    assert!(e.contains("'x'") && e.contains("NaN"), "{e}");
}

#[test]
fn shape_errors_name_the_node_and_shapes() {
    let mut g = Graph::new();
    let x = g.input("x", &[1, 2, 3, 4, 5]).unwrap();
    let w = g.param("w", &[4, 7, 1, 1], Init::Xavier).unwrap();
    let b = g.param("b", &[4], Init::Constant(0.0)).unwrap();
    let e = g.apply("proj", Op::Projection, &[x, w, b]).unwrap_err().to_string();
    assert!(e.contains("node 'proj'") && e.contains("[4, 7, 1, 1]") && e.contains("[1, 2, 3, 4, 5]"), "{e}");
}
