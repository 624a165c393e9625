//! What a graph run keeps instead of redoing, against runs that keep nothing: weights packed
//! once while the parameters are unchanged (`gpu/constant.rs`) and a run's stale ones packed
//! in one dispatch ahead of it (`ops/conv_pack_jobs.rs`), a conv's PReLU written by the conv,
//! a conv's input packed once for its forward and weight gradient (`gpu/kept.rs`), a head's
//! input staged once, the resampling's grid packed once. Values and gradients equal to the
//! bit, and the dispatches counted.

#[path = "../kernels-tests/common/mod.rs"]
mod common;

use common::*;
use rendernet::graph::{Executor, Graph, Init, Op, Value};
use rendernet::ops::{adam::Adam, loss::Loss};

fn f32v(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

// Weights packed once (gpu/constant.rs): x [1, 1, 9, 10, 11] -> conv3d 1->8 5^3 stride 2
// (the first layer's direct kernels) -> conv3d 8->6 3^3 -> mse against a target. With
// `weight_input`, the second conv's weights are a graph input instead of a parameter.
struct ConvNet {
    graph: Graph,
    x: Value,
    w1: Value,
    w2: Value,
    y: Value,
    loss: Value,
}

fn conv_net(weight_input: bool) -> ConvNet {
    use rendernet::ops::conv::{Conv, Padding};
    let mut g = Graph::new();
    let x = g.input("x", &[1, 1, 9, 10, 11]).unwrap();
    let target = g.input("target", &[1, 6, 5, 5, 6]).unwrap();
    let w1 = g.param("c1.weight", &[8, 1, 5, 5, 5], Init::Xavier).unwrap();
    let b1 = g.param("c1.bias", &[8], Init::Constant(0.01)).unwrap();
    let w2 = if weight_input { g.input("c2.weight", &[6, 8, 3, 3, 3]) } else { g.param("c2.weight", &[6, 8, 3, 3, 3], Init::Xavier) }.unwrap();
    let b2 = g.param("c2.bias", &[6], Init::Constant(0.01)).unwrap();
    let h = g.apply("c1", Op::Conv(Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same)), &[x, w1, b1]).unwrap();
    let y = g.apply("c2", Op::Conv(Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same)), &[h, w2, b2]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[y, target]).unwrap();
    ConvNet { graph: g, x, w1, w2, y, loss }
}

/// An executor of `n` with a random input, keeping y and asking for x's gradient.
fn conv_executor(n: &ConvNet, seed: u64) -> Executor {
    let mut ex = Executor::new(gpu(), n.graph.clone(), seed).unwrap();
    ex.feed(gpu(), n.x, &f32v(&Rng(seed).vec(9 * 10 * 11, -1.0, 1.0))).unwrap();
    ex.keep(n.y);
    ex.want_grad(n.x);
    ex
}

/// A fresh executor of `n` holding `ex`'s parameters and input: what `ex` must compute.
fn fresh_copy(n: &ConvNet, ex: &Executor) -> Executor {
    let fresh = conv_executor(n, 99);
    for v in n.graph.params().into_iter().chain([n.x]) {
        fresh.feed(gpu(), v, &ex.read(gpu(), v).unwrap()).unwrap();
    }
    fresh
}

#[test]
fn frozen_weights_are_packed_once_and_again_after_every_change() {
    let n = conv_net(false);
    let mut ex = conv_executor(&n, 5);
    let first = ex.forward(gpu()).unwrap();
    let y = ex.read(gpu(), n.y).unwrap();
    // The second run skips the two convs' weight packings (one dispatch ahead of the first
    // run, ops/conv_pack_jobs.rs, where the convs' texture kernels run; one each on buffers);
    // from the third on, nothing is created.
    let again = ex.forward(gpu()).unwrap();
    let packings = if first_conv_on_textures() { 1 } else { 2 };
    assert_eq!(again.dispatches + packings, first.dispatches, "first {first:?}, again {again:?}");
    assert_eq!(ex.read(gpu(), n.y).unwrap(), y);
    let third = ex.forward(gpu()).unwrap();
    assert_eq!((third.dispatches, third.created), (again.dispatches, 0), "{third:?}");
    assert_eq!(ex.read(gpu(), n.y).unwrap(), y);
    // New values in one parameter: both packed again, and the output is the new weights'.
    let w2: Vec<f32> = ex.read(gpu(), n.w2).unwrap().iter().map(|v| -0.5 * v).collect();
    ex.feed(gpu(), n.w2, &w2).unwrap();
    assert_eq!(ex.forward(gpu()).unwrap().dispatches, first.dispatches);
    let y2 = ex.read(gpu(), n.y).unwrap();
    assert_ne!(y2, y);
    let mut fresh = fresh_copy(&n, &ex);
    fresh.forward(gpu()).unwrap();
    assert_eq!(y2, fresh.read(gpu(), n.y).unwrap(), "after feeding a parameter");
    // A training step changes every parameter: the next forward is the trained network's.
    ex.forward(gpu()).unwrap();
    ex.train_step(gpu(), n.loss, &Adam::new(0.05)).unwrap();
    assert_ne!(ex.read(gpu(), n.w1).unwrap(), fresh.read(gpu(), n.w1).unwrap(), "the step moved c1");
    ex.forward(gpu()).unwrap();
    let mut fresh = fresh_copy(&n, &ex);
    fresh.forward(gpu()).unwrap();
    assert_eq!(ex.read(gpu(), n.y).unwrap(), fresh.read(gpu(), n.y).unwrap(), "after a training step");
}

#[test]
fn a_run_needing_more_weight_packings_than_the_last_packs_them_all() {
    // A frozen backward that wants no gradient runs no backward op, so it packs only the
    // convs' forward weights; asking for x's gradient adds c2's packing for its input
    // gradient, and the one dispatch that packs a run's stale weights ahead of it
    // (ops/conv_pack_jobs.rs) is remade for the larger set.
    let n = conv_net(false);
    let mut ex = Executor::new(gpu(), n.graph.clone(), 12).unwrap();
    ex.feed(gpu(), n.x, &f32v(&Rng(12).vec(9 * 10 * 11, -1.0, 1.0))).unwrap();
    ex.keep(n.y);
    ex.freeze_params();
    ex.backward(gpu(), n.loss).unwrap();
    ex.want_grad(n.x);
    let w2: Vec<f32> = ex.read(gpu(), n.w2).unwrap().iter().map(|v| -0.5 * v).collect();
    ex.feed(gpu(), n.w2, &w2).unwrap();
    ex.backward(gpu(), n.loss).unwrap();
    let mut plain = fresh_copy(&n, &ex);
    plain.reuse_gpu_objects(false);
    plain.freeze_params();
    plain.backward(gpu(), n.loss).unwrap();
    assert_eq!(ex.grad(gpu(), n.x).unwrap(), plain.grad(gpu(), n.x).unwrap(), "against a run that keeps nothing");
}

#[test]
fn a_frozen_backward_reuses_its_packings_and_weights_that_are_inputs_never_do() {
    // Inverse rendering's runs: backward through frozen parameters to an input, repeated.
    let n = conv_net(false);
    let mut ex = conv_executor(&n, 6);
    ex.freeze_params();
    let first = ex.backward(gpu(), n.loss).unwrap();
    let dx = ex.grad(gpu(), n.x).unwrap();
    let again = ex.backward(gpu(), n.loss).unwrap();
    // Forward and backward-input packings kept: one dispatch ahead of the first run packed
    // them all where the convs run on textures, one each (at least 3) elsewhere.
    if first_conv_on_textures() {
        assert_eq!(again.dispatches + 1, first.dispatches, "first {first:?}, again {again:?}");
    } else {
        assert!(again.dispatches + 2 < first.dispatches, "first {first:?}, again {again:?}");
    }
    assert_eq!(ex.grad(gpu(), n.x).unwrap(), dx);
    let mut plain = fresh_copy(&n, &ex);
    plain.reuse_gpu_objects(false);
    plain.freeze_params();
    plain.backward(gpu(), n.loss).unwrap();
    assert_eq!(plain.grad(gpu(), n.x).unwrap(), dx, "against a run that keeps nothing");
    // Weights fed as an input may change without a parameter write: packed every run.
    let n = conv_net(true);
    let mut ex = conv_executor(&n, 7);
    ex.feed(gpu(), n.w2, &f32v(&Rng(8).vec(6 * 8 * 27, -0.3, 0.3))).unwrap();
    let first = ex.forward(gpu()).unwrap();
    ex.feed(gpu(), n.w2, &f32v(&Rng(9).vec(6 * 8 * 27, -0.3, 0.3))).unwrap();
    let again = ex.forward(gpu()).unwrap();
    assert_eq!(again.dispatches + 1, first.dispatches, "only the parameter c1 kept its packing");
    // Against a run that keeps nothing: a fresh executor that kept packings would share a
    // wrong rule for inputs.
    let mut plain = conv_executor(&n, 7);
    plain.reuse_gpu_objects(false);
    plain.feed(gpu(), n.w2, &ex.read(gpu(), n.w2).unwrap()).unwrap();
    for v in n.graph.params() {
        plain.feed(gpu(), v, &ex.read(gpu(), v).unwrap()).unwrap();
    }
    plain.forward(gpu()).unwrap();
    assert_eq!(ex.read(gpu(), n.y).unwrap(), plain.read(gpu(), n.y).unwrap(), "new input weights");
}

// A forward-only run writes a PReLU that follows a conv in the conv's own dispatch
// (`Executor::prelu_fusions`): x [1, 1, 9, 10, 11] -> conv3d 1->8 5^3 s2 (direct kernels) ->
// prelu -> conv3d 8->16 3^3 (16-channel tile) -> prelu -> y, the second conv's output also
// feeding `side` (so that PReLU is not fused: its input is read twice); y + side -> a
// transposed conv -> prelu -> z -> the projection -> prelu -> q.
/// The first two layers of the graphs below: x [1, 1, 9, 10, 11] -> conv3d 1->8 5^3 stride 2
/// (the first layer's direct kernels) -> prelu -> conv3d 8->16 3^3 (the 16-channel tiles):
/// x, the first conv's output and the second's, [1, 16, 5, 5, 6].
fn two_convs(g: &mut Graph) -> (Value, Value, Value) {
    use rendernet::ops::conv::{Conv, Padding};
    let x = g.input("x", &[1, 1, 9, 10, 11]).unwrap();
    let w1 = g.param("c1.weight", &[8, 1, 5, 5, 5], Init::Xavier).unwrap();
    let b1 = g.param("c1.bias", &[8], Init::Constant(0.01)).unwrap();
    let a1 = g.param("a1.alpha", &[8], Init::Constant(0.3)).unwrap();
    let w2 = g.param("c2.weight", &[16, 8, 3, 3, 3], Init::Xavier).unwrap();
    let b2 = g.param("c2.bias", &[16], Init::Constant(-0.01)).unwrap();
    let c1 = g.apply("c1", Op::Conv(Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same)), &[x, w1, b1]).unwrap();
    let h = g.apply("a1", Op::Prelu, &[c1, a1]).unwrap();
    let c2 = g.apply("c2", Op::Conv(Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same)), &[h, w2, b2]).unwrap();
    (x, c1, c2)
}

/// Whether `two_convs`' first conv runs the texture kernels (lavapipe), which fuse a PReLU
/// and pack their operands into textures; storage-buffer kernels (elsewhere) do neither.
fn first_conv_on_textures() -> bool {
    use rendernet::ops::conv::{Conv, ConvKernel, Padding};
    Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same).fuses_prelu(ConvKernel::Auto, gpu(), &[1, 1, 9, 10, 11], &[8, 1, 5, 5, 5]).unwrap()
}

#[test]
fn a_forward_only_run_fuses_conv_and_prelu_with_identical_values() {
    use rendernet::ops::conv::Padding;
    use rendernet::ops::conv_transpose::ConvTranspose;
    let mut g = Graph::new();
    let (x, c1, c2) = two_convs(&mut g);
    let a2 = g.param("a2.alpha", &[16], Init::Constant(-0.2)).unwrap();
    let y = g.apply("a2", Op::Prelu, &[c2, a2]).unwrap();
    let side = g.apply("side", Op::Sigmoid, &[c2]).unwrap();
    let total = g.apply("total", Op::Add, &[y, side]).unwrap();
    let target = g.input("target", &[1, 16, 5, 5, 6]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[total, target]).unwrap();
    // And a transposed conv 16->4 4^3 stride 2 then a PReLU, fused too: z [1, 4, 10, 10, 12].
    let w3 = g.param("t3.weight", &[16, 4, 4, 4, 4], Init::Xavier).unwrap();
    let b3 = g.param("t3.bias", &[4], Init::Constant(0.02)).unwrap();
    let a3 = g.param("a3.alpha", &[4], Init::Constant(0.5)).unwrap();
    let t3 = g.apply("t3", Op::ConvTranspose(ConvTranspose::conv3d([4, 4, 4], [2, 2, 2], Padding::Same)), &[total, w3, b3]).unwrap();
    let z = g.apply("a3", Op::Prelu, &[t3, a3]).unwrap();
    // And the projection unit (depth folded into channels, K = 40 -> 6) then a PReLU: q.
    let w4 = g.param("p4.weight", &[6, 40, 1, 1], Init::Xavier).unwrap();
    let b4 = g.param("p4.bias", &[6], Init::Constant(0.03)).unwrap();
    let a4 = g.param("a4.alpha", &[6], Init::Constant(-0.4)).unwrap();
    let p4 = g.apply("p4", Op::Projection, &[z, w4, b4]).unwrap();
    let q = g.apply("a4", Op::Prelu, &[p4, a4]).unwrap();
    let fuses = first_conv_on_textures();
    let run = |keep_c1: bool, backward: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &f32v(&Rng(8).vec(9 * 10 * 11, -1.0, 1.0))).unwrap();
        ex.keep(total);
        ex.keep(q);
        if keep_c1 {
            ex.keep(c1);
            ex.keep(t3);
            ex.keep(p4);
        }
        let stats = if backward { ex.backward(gpu(), loss).unwrap() } else { ex.forward(gpu()).unwrap() };
        ([ex.read(gpu(), total).unwrap(), ex.read(gpu(), q).unwrap()], stats.dispatches)
    };
    let (fused, d_fused) = run(false, false);
    // The same forward without fusion: c1's output kept for the caller, or a backward run
    // (which saves it for a1's backward); values equal to the bit.
    let (kept, d_kept) = run(true, false);
    let (with_backward, _) = run(false, true);
    assert_eq!(fused, kept, "fused against c1's output kept");
    assert_eq!(fused, with_backward, "fused against a backward run's forward");
    // Three PReLUs fused on lavapipe (c1 -> a1, t3 -> a3 and p4 -> a4; a2's input c2 is read
    // by `side` too): their dispatches are gone; elsewhere nothing fuses and nothing changes.
    let prelu_dispatches = {
        let (t, a, o) = (upload(&[1, 8, 5, 5, 6], &vec![0.5; 1200]), upload(&[8], &[0.1; 8]), zeros(&[1, 8, 5, 5, 6]));
        let d0 = gpu().dispatch_count();
        common::run(|p| rendernet::ops::prelu::forward(gpu(), p, &t, &a, &o));
        gpu().dispatch_count() - d0
    };
    assert_eq!(d_kept - d_fused, if fuses { 3 * prelu_dispatches } else { 0 }, "dispatches fused {d_fused}, kept {d_kept}");
}

// A training run keeps the input packing each conv's forward makes for the same conv's weight
// gradient (gpu/kept.rs): x [1, 1, 9, 10, 11] -> conv3d 1->8 5^3 s2 (the direct kernels' staged
// input) -> prelu -> conv3d 8->16 3^3 (the texture packing) -> conv3d 16->16 3^3 (whose dy
// packing has the very layout of its x packing: only the tensor tells them apart) -> a
// transposed conv 16->4 4^3 s2 (its input packed as the backward-input kernels pack dy) ->
// the projection -> mse. Against
// a run that keeps nothing (`reuse_gpu_objects(false)`): gradients and a training step's
// parameters equal to the bit, one dispatch fewer per op whose weights get a gradient (and
// per packing one backward makes twice), and none fewer where none does (frozen parameters,
// inverse rendering's runs).
#[test]
fn a_training_run_packs_each_conv_input_once_for_forward_and_weight_gradient() {
    use rendernet::ops::conv::{Conv, Padding};
    use rendernet::ops::conv_transpose::ConvTranspose;
    let mut g = Graph::new();
    let (x, _, c2) = two_convs(&mut g);
    let w5 = g.param("c5.weight", &[16, 16, 3, 3, 3], Init::Xavier).unwrap();
    let b5 = g.param("c5.bias", &[16], Init::Constant(0.01)).unwrap();
    let w3 = g.param("t3.weight", &[16, 4, 4, 4, 4], Init::Xavier).unwrap();
    let b3 = g.param("t3.bias", &[4], Init::Constant(0.02)).unwrap();
    let w4 = g.param("p4.weight", &[6, 40, 1, 1], Init::Xavier).unwrap();
    let b4 = g.param("p4.bias", &[6], Init::Constant(0.03)).unwrap();
    let c5 = g.apply("c5", Op::Conv(Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same)), &[c2, w5, b5]).unwrap();
    let t3 = g.apply("t3", Op::ConvTranspose(ConvTranspose::conv3d([4, 4, 4], [2, 2, 2], Padding::Same)), &[c5, w3, b3]).unwrap();
    let p4 = g.apply("p4", Op::Projection, &[t3, w4, b4]).unwrap();
    let target = g.input("target", &[1, 6, 10, 12]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[p4, target]).unwrap();
    let params = g.params();
    let run = |keep: bool, frozen: bool, train: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &f32v(&Rng(8).vec(9 * 10 * 11, -1.0, 1.0))).unwrap();
        ex.feed(gpu(), target, &f32v(&Rng(9).vec(6 * 10 * 12, -1.0, 1.0))).unwrap();
        ex.reuse_gpu_objects(keep);
        ex.want_grad(x);
        if frozen {
            ex.freeze_params();
        }
        let stats = if train { ex.train_step(gpu(), loss, &Adam::new(0.01)).unwrap() } else { ex.backward(gpu(), loss).unwrap() };
        let mut got = vec![ex.grad(gpu(), x).unwrap()];
        if !frozen {
            got.extend(params.iter().map(|&p| ex.grad(gpu(), p).unwrap()));
        }
        if train {
            got.extend(params.iter().map(|&p| ex.read(gpu(), p).unwrap()));
        }
        (got, stats.dispatches)
    };
    // Where the conv kernels run on textures (lavapipe), all five ops pack their input into a
    // texture and their weight gradients find it; two more packings are shared inside one
    // backward: the transposed conv packs its dy for its input gradient and again as its
    // weight gradient's x, the projection for its input gradient and its weight gradient.
    // Their 17 weight packings (forward and input gradient; the transposed conv's forward one
    // per output phase) run as one dispatch ahead of the run (ops/conv_pack_jobs.rs) where
    // they are kept, one each where not.
    // Elsewhere (storage buffers) nothing is kept and nothing changes.
    let textures = first_conv_on_textures();
    for (frozen, train) in [(false, false), (false, true), (true, false)] {
        let ((kept, d_kept), (plain, d_plain)) = (run(true, frozen, train), run(false, frozen, train));
        assert_eq!(kept, plain, "frozen {frozen}, train {train}: packings kept against none");
        let inputs = if frozen { 0 } else { 5 + 2 };
        let fewer = if textures { inputs + 17 - 1 } else { 0 };
        assert_eq!(d_plain - d_kept, fewer, "frozen {frozen}, train {train}: dispatches kept {d_kept}, plain {d_plain}");
    }
}

// A training run's narrow 3x3 head 64 wide (conv2d 16 -> 3 -> mse, a Phong head's shape): where
// `Auto` runs its forward on the unpacked input (a CPU adapter where that measured faster), the
// forward reads x from its stage texture, copied in, and keeps it, and the weight gradient
// (`conv_direct_backward_weight_3x3`) reads it there: one copy into a texture fewer than a run
// that keeps nothing, with gradients and parameters equal to the bit. Elsewhere both runs copy
// (or pack) alike.
#[test]
fn a_training_run_stages_a_heads_input_once() {
    use rendernet::ops::conv::{Conv, ConvKernel, Padding};
    let mut g = Graph::new();
    let x = g.input("x", &[1, 16, 6, 64]).unwrap();
    let w = g.param("h.weight", &[3, 16, 3, 3], Init::Xavier).unwrap();
    let b = g.param("h.bias", &[3], Init::Constant(0.01)).unwrap();
    let conv = Conv::conv2d([3, 3], [1, 1], Padding::Same);
    let y = g.apply("h", Op::Conv(conv), &[x, w, b]).unwrap();
    let target = g.input("target", &[1, 3, 6, 64]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[y, target]).unwrap();
    let run = |keep: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &f32v(&Rng(21).vec(16 * 6 * 64, -1.0, 1.0))).unwrap();
        ex.feed(gpu(), target, &f32v(&Rng(22).vec(3 * 6 * 64, -1.0, 1.0))).unwrap();
        ex.reuse_gpu_objects(keep);
        ex.want_grad(x);
        let before = gpu().pass_splits();
        ex.train_step(gpu(), loss, &Adam::new(0.01)).unwrap();
        let splits = gpu().pass_splits() - before;
        let got = vec![ex.grad(gpu(), x).unwrap(), ex.grad(gpu(), w).unwrap(), ex.grad(gpu(), b).unwrap(), ex.read(gpu(), w).unwrap()];
        (got, splits)
    };
    let ((kept, s_kept), (plain, s_plain)) = (run(true), run(false));
    assert_eq!(kept, plain, "stage kept against none");
    let cpu = gpu().info.device_type == wgpu::DeviceType::Cpu;
    let unpacked = conv.forward_reads_staged_unpacked(ConvKernel::Auto, gpu(), &[1, 16, 6, 64], &[3, 16, 3, 3]).unwrap();
    assert_eq!(s_plain - s_kept, u64::from(cpu && unpacked), "copies into textures: kept {s_kept}, plain {s_plain}");
}

// The resampling's pose gradient reads the grid and sampling map its forward packed (kept,
// gpu/kept.rs) instead of staging and packing them again: grid [2, 4, 7, 8, 9] and pose
// [2, 6] -> resample to 6 x 5 x 7 -> mse, the pose's (and the grid's) gradient asked for, as
// the inverse renderer asks. Against a run that keeps nothing: gradients equal to the bit,
// and the stage and pack dispatches gone where the resampling reads textures (lavapipe).
#[test]
fn the_pose_gradient_reads_the_grid_its_forward_packed() {
    let mut g = Graph::new();
    let grid = g.input("grid", &[2, 4, 7, 8, 9]).unwrap();
    let pose = g.input("pose", &[2, 6]).unwrap();
    let target = g.input("target", &[2, 4, 6, 5, 7]).unwrap();
    let r = g.apply("resample", Op::Resample([6, 5, 7]), &[grid, pose]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[r, target]).unwrap();
    let run = |keep: bool, grid_too: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), grid, &f32v(&Rng(4).vec(2 * 4 * 7 * 8 * 9, 0.0, 1.0))).unwrap();
        ex.feed(gpu(), pose, &f32v(&[0.9, 0.3, -0.2, 0.2, -0.1, 0.15, 1.1, -0.7, 0.4, -0.2, 0.1, 0.05])).unwrap();
        ex.feed(gpu(), target, &f32v(&Rng(5).vec(2 * 4 * 6 * 5 * 7, 0.0, 1.0))).unwrap();
        ex.reuse_gpu_objects(keep);
        ex.want_grad(pose);
        if grid_too {
            ex.want_grad(grid);
        }
        let stats = ex.backward(gpu(), loss).unwrap();
        let mut got = vec![ex.grad(gpu(), pose).unwrap()];
        if grid_too {
            got.push(ex.grad(gpu(), grid).unwrap());
        }
        (got, stats.dispatches)
    };
    let textures = first_conv_on_textures()
        && rendernet::ops::resample::textures_supported(gpu());
    for grid_too in [false, true] {
        let ((kept, d_kept), (plain, d_plain)) = (run(true, grid_too), run(false, grid_too));
        assert_eq!(kept, plain, "grid's gradient too: {grid_too}");
        assert_eq!(d_plain - d_kept, if textures { 2 } else { 0 }, "grid's gradient too: {grid_too}: dispatches kept {d_kept}, plain {d_plain}");
    }
}
