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
    assert!(stats.pool_bytes <= stats.tensor_bytes + 4096, "{stats:?}");
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

/// The network, resampling first: grid + pose -> resample -> conv3d -> PReLU ->
/// projection -> conv2d -> transposed conv2d -> sigmoid -> BCE. Gradients to every
/// parameter, to the input grid and to the pose against finite differences of the f64
/// references composed the same way.
mod full_network {
    use super::*;
    use reference::conv::{Geom, conv, conv_transpose};
    use reference::resample::{Dims, forward as resample_ref};
    use rendernet::ops::{conv::{Conv, Padding}, conv_transpose::ConvTranspose};

    const NB: usize = 2;
    const G: [usize; 3] = [5, 5, 5]; // input grid
    const R: [usize; 3] = [6, 7, 5]; // camera-aligned grid (D, H, W)
    const C3: usize = 3; // 3D channels
    const P: usize = 4; // projection outputs
    const C2: usize = 3; // conv2d outputs
    const CO: usize = 2; // image channels
    const IMG: [usize; 2] = [14, 10]; // transposed conv s2 doubles H, W

    /// Parameters in graph order: conv3d w, b, alpha, proj w, b, conv2d w, b, convT w, b.
    const PARAMS: [(&str, &[usize]); 9] = [
        ("c3.weight", &[C3, 1, 3, 3, 3]),
        ("c3.bias", &[C3]),
        ("act.alpha", &[C3]),
        ("proj.weight", &[P, C3 * 6, 1, 1]),
        ("proj.bias", &[P]),
        ("c2.weight", &[C2, P, 3, 3]),
        ("c2.bias", &[C2]),
        ("up.weight", &[C2, CO, 4, 4]),
        ("up.bias", &[CO]),
    ];

    fn build() -> (Graph, Value, Value, Value, Vec<Value>, Value) {
        let mut g = Graph::new();
        let grid = g.input("grid", &[NB, 1, G[0], G[1], G[2]]).unwrap();
        let pose = g.input("pose", &[NB, 6]).unwrap();
        let target = g.input("target", &[NB, CO, IMG[0], IMG[1]]).unwrap();
        let p: Vec<Value> = PARAMS
            .iter()
            .map(|(n, s)| g.param(n, s, if s.len() > 1 { Init::Xavier } else { Init::Constant(0.1) }).unwrap())
            .collect();
        let r = g.apply("resample", Op::Resample(R), &[grid, pose]).unwrap();
        let c3 = g.apply("c3", Op::Conv(Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same)), &[r, p[0], p[1]]).unwrap();
        let a = g.apply("act", Op::Prelu, &[c3, p[2]]).unwrap();
        let pr = g.apply("proj", Op::Projection, &[a, p[3], p[4]]).unwrap();
        let c2 = g.apply("c2", Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same)), &[pr, p[5], p[6]]).unwrap();
        let up = g.apply("up", Op::ConvTranspose(ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same)), &[c2, p[7], p[8]]).unwrap();
        let s = g.apply("sig", Op::Sigmoid, &[up]).unwrap();
        let loss = g.apply("loss", Op::Loss(Loss::Bce), &[s, target]).unwrap();
        (g, grid, pose, target, p, loss)
    }

    fn same(len: usize, k: usize, s: usize) -> usize {
        reference::conv::same_pads(len, k, s).1
    }

    /// The f64 loss of grid, pose and parameters `p` (in PARAMS order).
    fn loss_ref(grid: &[f64], pose: &[f64], t: &[f64], p: &[Vec<f64>]) -> f64 {
        let r = resample_ref(&Dims { n: NB, c: 1, inp: G, out: R }, grid, pose);
        let g3 = Geom { n: NB, ci: 1, co: C3, input: R, output: R, kernel: [3; 3], stride: [1; 3], before: [1; 3] };
        let c3 = conv(&g3, &r, &p[0], Some(&p[1]));
        let a = act::prelu(&c3, &p[2], C3, R.iter().product());
        let pr = proj_ref(&a, &p[3], &p[4], NB, C3 * R[0], P, R[1] * R[2]);
        let hw = [1, R[1], R[2]];
        let g2 = Geom { n: NB, ci: P, co: C2, input: hw, output: hw, kernel: [1, 3, 3], stride: [1; 3], before: [0, 1, 1] };
        let c2 = conv(&g2, &pr, &p[5], Some(&p[6]));
        let before = [0, same(IMG[0], 4, 2), same(IMG[1], 4, 2)];
        let gt = Geom { n: NB, ci: C2, co: CO, input: hw, output: [1, IMG[0], IMG[1]], kernel: [1, 4, 4], stride: [1, 2, 2], before };
        let up = conv_transpose(&gt, &c2, &p[7], Some(&p[8]));
        lref::bce(&act::sigmoid(&up), t, 1e-7, 1.0 - 1e-7)
    }

    #[test]
    fn gradients_to_params_grid_and_pose_match_finite_differences() {
        let (g, grid_v, pose_v, target_v, params, loss) = build();
        let mut ex = Executor::new(gpu(), g, 11).unwrap();
        let mut rng = Rng(21);
        let grid = f32_round(&rng.vec(NB * G.iter().product::<usize>(), 0.0, 1.0));
        let pose = f32_round(&[0.9, 0.3, -0.2, 0.2, -0.1, 0.15, 1.1, -0.7, 0.4, -0.2, 0.1, 0.05]);
        let t = f32_round(&rng.vec(NB * CO * IMG[0] * IMG[1], 0.0, 1.0));
        ex.feed(gpu(), grid_v, &f32v(&grid)).unwrap();
        ex.feed(gpu(), pose_v, &f32v(&pose)).unwrap();
        ex.feed(gpu(), target_v, &f32v(&t)).unwrap();
        ex.want_grad(grid_v);
        ex.want_grad(pose_v);
        ex.training = false;
        let stats = ex.backward(gpu(), loss).unwrap();
        assert_eq!(stats.submits, 1);
        let p: Vec<Vec<f64>> = params.iter().map(|&v| read64(&ex, v)).collect();
        let l = read64(&ex, loss)[0];
        assert!((l - loss_ref(&grid, &pose, &t, &p)).abs() < 1e-5, "loss {l}");
        // Gradients of a mean over 560 pixels are ~1e-3; f32 chains of a few hundred terms
        // keep errors near 1e-4 relative, so rtol 2e-3 with atol at 1e-3 of the largest
        // gradient leaves 10x headroom while a dropped term or a flipped sign fails.
        let check = |what: &str, got: Vec<f64>, want: Vec<f64>| {
            let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            assert_close(what, &got, &want, 1e-3 * scale, 2e-3);
        };
        check("d/d grid", grad64(&ex, grid_v), fd_grad(&grid, |x| loss_ref(x, &pose, &t, &p)));
        check("d/d pose", grad64(&ex, pose_v), fd_grad(&pose, |x| loss_ref(&grid, x, &t, &p)));
        for (k, &v) in params.iter().enumerate() {
            let want = fd_grad(&p[k], |x| {
                let mut q = p.clone();
                q[k] = x.to_vec();
                loss_ref(&grid, &pose, &t, &q)
            });
            check(PARAMS[k].0, grad64(&ex, v), want);
        }
        assert!(stats.pool_bytes < stats.tensor_bytes, "memory planning reused nothing: {stats:?}");
    }
}

#[test]
fn exponential_decay_matches_the_original_schedule() {
    use rendernet::train::lr::exponential_decay;
    assert_eq!(exponential_decay(1e-5, 0.96, 1000, 0, true), 1e-5);
    assert!((exponential_decay(1.0, 0.96, 1000, 2500, true) - 0.96f32.powi(2)).abs() < 1e-7);
    assert!((exponential_decay(1.0, 0.96, 1000, 2500, false) - 0.96f32.powf(2.5)).abs() < 1e-6);
}

#[test]
fn a_step_with_nan_or_inf_gradients_is_refused_and_changes_nothing() {
    let (n, mut ex, _, _) = fed(5);
    ex.training = true;
    ex.train_step(gpu(), n.loss, &Adam::new(1e-2)).unwrap();
    let before: Vec<Vec<f32>> = [n.alpha, n.w, n.b].iter().map(|&v| ex.read(gpu(), v).unwrap()).collect();
    // Finite inputs whose products overflow f32 in the backward pass.
    ex.feed(gpu(), n.x, &vec![3e37; N * C * D * H * W]).unwrap();
    let e = ex.train_step(gpu(), n.loss, &Adam::new(1e-2)).unwrap_err().to_string();
    assert!(e.contains("step 2") && e.contains("NaN or Inf") && e.contains("weights are unchanged"), "{e}");
    assert!(e.contains("'act.alpha'") || e.contains("'proj.weight'") || e.contains("'proj.bias'"), "{e}");
    let after: Vec<Vec<f32>> = [n.alpha, n.w, n.b].iter().map(|&v| ex.read(gpu(), v).unwrap()).collect();
    assert_eq!(before, after);
    assert_eq!(ex.step, 1, "a refused step does not count");
}

#[test]
fn a_training_step_updates_every_parameter_at_once_by_adams_first_step() {
    // The optimizer runs over the flat parameter, gradient and moment buffers: a gradient
    // check, its summary and one Adam update, three dispatches whatever the parameter count.
    // Adam's first step moves each parameter by lr against its gradient's sign (bias-corrected
    // m / sqrt(v) = +-1); act.alpha's 3 values leave a padding gap before the next view, so a
    // misplaced view or update shows.
    let (n, mut ex, _, _) = fed(3);
    let bw = ex.backward(gpu(), n.loss).unwrap();
    let params = [n.alpha, n.w, n.b];
    let before: Vec<Vec<f64>> = params.iter().map(|&v| read64(&ex, v)).collect();
    let grads: Vec<Vec<f64>> = params.iter().map(|&v| grad64(&ex, v)).collect();
    let lr = 1e-3;
    let step = ex.train_step(gpu(), n.loss, &Adam::new(lr as f32)).unwrap();
    assert_eq!(step.dispatches, bw.dispatches + 3, "backward {bw:?}, step {step:?}");
    for (k, &v) in params.iter().enumerate() {
        let sign = |g: f64| if g == 0.0 { 0.0 } else { g.signum() };
        let want: Vec<f64> = before[k].iter().zip(&grads[k]).map(|(p, &g)| p - lr * sign(g)).collect();
        assert_close(&format!("parameter {k} after one step"), &read64(&ex, v), &want, 1e-6, 1e-5);
        // The step's own gradients are the same as the backward run's (same inputs).
        assert_close(&format!("gradient {k}"), &grad64(&ex, v), &grads[k], 1e-6, 1e-5);
    }
}
