//! Values the executor makes without a dispatch, against the same graphs made with copies:
//! channel ranges as views of their input, a sigmoid reading its range in place, and
//! parameters concatenated along axis 0 laid out as one view (`graph/flat.rs`). Values and
//! gradients equal to the bit, and the dispatches counted.

#[path = "../kernels-tests/common/mod.rs"]
mod common;

use common::*;
use rendernet::graph::{Executor, Graph, Init, Op, Value};
use rendernet::ops::{adam::Adam, loss::Loss};

// Channel ranges of a batch of one are views of their input's buffer, not copies
// (`Executor::narrow_views`): x [n, 5, h, w] -> a joint 3x3 conv to 6 channels -> three
// ranges (3, 2 and 1 channels) and a range of the second -> sigmoids; between the ranges and
// their readers a second conv makes a tensor of the joint output's size, which would take the
// joint output's buffer if the views did not keep it alive. Against the same graph with the ranges kept for the
// caller (copies): equal to the bit, forward and gradients, with one dispatch fewer per range
// where the ranges can be views (n = 1 and channel planes a multiple of the binding alignment:
// 12 x 16 floats), none fewer where they cannot (a batch of two; with 9 x 7 floats a plane
// only the range at channel 0 starts aligned).
#[test]
fn channel_ranges_of_one_item_are_views_with_identical_values_and_gradients() {
    use rendernet::ops::conv::{Conv, Padding};
    let conv = || Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same));
    for (n, h, w) in [(1usize, 12usize, 16usize), (2, 12, 16), (1, 9, 7)] {
        let mut g = Graph::new();
        let x = g.input("x", &[n, 5, h, w]).unwrap();
        let wj = g.param("joint.weight", &[6, 5, 3, 3], Init::Xavier).unwrap();
        let bj = g.param("joint.bias", &[6], Init::Constant(0.1)).unwrap();
        let wz = g.param("other.weight", &[6, 5, 3, 3], Init::Xavier).unwrap();
        let bz = g.param("other.bias", &[6], Init::Constant(-0.1)).unwrap();
        let joint = g.apply("joint", conv(), &[x, wj, bj]).unwrap();
        let (starts, lens) = ([0usize, 3, 5], [3usize, 2, 1]);
        let mut ranges: Vec<Value> = (0..3).map(|k| g.apply(&format!("r{k}"), Op::Narrow(starts[k], lens[k]), &[joint]).unwrap()).collect();
        // A range of a range: channel 4 of the joint output (a view of a view where both align).
        ranges.push(g.apply("r3", Op::Narrow(1, 1), &[ranges[1]]).unwrap());
        let other = g.apply("other", conv(), &[x, wz, bz]).unwrap();
        let mut outs = vec![g.apply("other.sigmoid", Op::Sigmoid, &[other]).unwrap()];
        outs.extend(ranges.iter().enumerate().map(|(k, &r)| g.apply(&format!("s{k}"), Op::Sigmoid, &[r]).unwrap()));
        let mut loss = None;
        for (k, &o) in outs.iter().enumerate() {
            let t = g.input(&format!("t{k}"), &g.info(o).shape.clone()).unwrap();
            let l = g.apply(&format!("loss{k}"), Op::Loss(Loss::Mse), &[o, t]).unwrap();
            loss = Some(loss.map_or(l, |prev| g.apply(&format!("sum{k}"), Op::Add, &[prev, l]).unwrap()));
        }
        let loss = loss.unwrap();
        let run = |copies: bool, backward: bool| {
            let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
            ex.feed(gpu(), x, &f32v(&Rng(31).vec(n * 5 * h * w, -1.0, 1.0))).unwrap();
            for (k, &o) in outs.iter().enumerate() {
                let t = g.value(&format!("t{k}")).unwrap();
                ex.feed(gpu(), t, &f32v(&Rng(40 + k as u64).vec(g.info(o).shape.iter().product(), 0.0, 1.0))).unwrap();
                ex.keep(o);
            }
            if copies {
                ranges.iter().for_each(|&r| ex.keep(r));
            }
            ex.want_grad(x);
            let stats = if backward { ex.backward(gpu(), loss).unwrap() } else { ex.forward(gpu()).unwrap() };
            let mut got: Vec<Vec<f32>> = outs.iter().map(|&o| ex.read(gpu(), o).unwrap()).collect();
            if backward {
                got.push(ex.grad(gpu(), x).unwrap());
                got.extend([wj, bj, wz, bz].iter().map(|&p| ex.grad(gpu(), p).unwrap()));
            }
            (got, stats.dispatches)
        };
        // Ranges whose first element meets the binding alignment (on any device, start 0 does).
        let align = gpu().limits.min_storage_buffer_offset_alignment.max(16) as usize;
        let aligned = |s: usize| n == 1 && (s * h * w * 4).is_multiple_of(align);
        let views = starts.iter().chain(&[1]).filter(|&&s| aligned(s)).count() as u64;
        assert_eq!(views, if n == 1 { if h * w == 192 { 4 } else { 1 } } else { 0 }, "alignment {align}");
        for backward in [false, true] {
            let ((viewed, d_viewed), (copied, d_copied)) = (run(false, backward), run(true, backward));
            assert_eq!(viewed, copied, "n {n}, {h}x{w}, backward {backward}: ranges as views against copies");
            assert_eq!(d_copied - d_viewed, views, "n {n}, {h}x{w}, backward {backward}: dispatches");
        }
    }
}

// A channel range that only the sigmoid right after it reads is never copied
// (`Executor::range_sigmoids`): x [n, 5, 6, 9] -> a joint 3x3 conv to 6 channels -> four
// pairs of a range (3, 2, 1 and 6 channels) and its sigmoid -> MSE each; batch 2 and 1. Against
// the same graph with the ranges kept for the caller (copied): values and every gradient equal
// to the bit, one dispatch fewer per range in a forward and one more fewer in a backward. A
// range whose gradient is asked for is not read in place: its gradient is there to read.
#[test]
fn a_sigmoid_reads_its_channel_range_in_place_with_identical_values_and_gradients() {
    use rendernet::ops::conv::{Conv, Padding};
    for n in [2usize, 1] {
        let (h, w) = (6usize, 9usize);
        let mut g = Graph::new();
        let x = g.input("x", &[n, 5, h, w]).unwrap();
        let wj = g.param("joint.weight", &[6, 5, 3, 3], Init::Xavier).unwrap();
        let bj = g.param("joint.bias", &[6], Init::Constant(0.1)).unwrap();
        let joint = g.apply("joint", Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same)), &[x, wj, bj]).unwrap();
        let (mut ranges, mut outs, mut loss) = (Vec::new(), Vec::new(), None);
        // The last range is all 6 channels: its sigmoid's output has the joint output's size, so
        // it would take the joint output's buffer if that were not kept alive for the sigmoid.
        for (k, (start, len)) in [(0usize, 3usize), (3, 2), (5, 1), (0, 6)].into_iter().enumerate() {
            ranges.push(g.apply(&format!("r{k}"), Op::Narrow(start, len), &[joint]).unwrap());
            outs.push(g.apply(&format!("s{k}"), Op::Sigmoid, &[ranges[k]]).unwrap());
            let t = g.input(&format!("t{k}"), &[n, len, h, w]).unwrap();
            let l = g.apply(&format!("loss{k}"), Op::Loss(Loss::Mse), &[outs[k], t]).unwrap();
            loss = Some(loss.map_or(l, |prev| g.apply(&format!("sum{k}"), Op::Add, &[prev, l]).unwrap()));
        }
        let loss = loss.unwrap();
        // `ranges`: keep (copies), want their gradients, or neither (read in place).
        let run = |ranges_too: Option<bool>, backward: bool| {
            let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
            ex.feed(gpu(), x, &f32v(&Rng(51).vec(n * 5 * h * w, -1.0, 1.0))).unwrap();
            for (k, &o) in outs.iter().enumerate() {
                let len = g.info(o).shape[1];
                ex.feed(gpu(), g.value(&format!("t{k}")).unwrap(), &f32v(&Rng(60 + k as u64).vec(n * len * h * w, 0.0, 1.0))).unwrap();
                ex.keep(o);
            }
            match ranges_too {
                Some(true) => ranges.iter().for_each(|&r| ex.keep(r)),
                Some(false) => ranges.iter().for_each(|&r| ex.want_grad(r)),
                None => {}
            }
            ex.want_grad(x);
            let stats = if backward { ex.backward(gpu(), loss).unwrap() } else { ex.forward(gpu()).unwrap() };
            let mut got: Vec<Vec<f32>> = outs.iter().map(|&o| ex.read(gpu(), o).unwrap()).collect();
            if backward {
                got.extend([x, wj, bj].iter().map(|&v| ex.grad(gpu(), v).unwrap()));
                if ranges_too == Some(false) {
                    assert!(ranges.iter().all(|&r| ex.grad(gpu(), r).is_ok()), "a range's gradient was asked for");
                }
            }
            (got, stats.dispatches)
        };
        for backward in [false, true] {
            let ((fused, d_fused), (copied, d_copied)) = (run(None, backward), run(Some(true), backward));
            assert_eq!(fused, copied, "n {n}, backward {backward}: ranges read in place against copies");
            assert_eq!(d_copied - d_fused, if backward { 8 } else { 4 }, "n {n}, backward {backward}: dispatches");
        }
        let (graded, _) = run(Some(false), true);
        assert_eq!(graded, run(None, true).0, "n {n}: with the ranges' gradients asked for");
    }
}


fn f32v(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

// Parameters that only a concatenation along axis 0 reads lie back to back in the flat
// buffers, so the concatenation is a view and its gradient a view that the parts' gradients
// are ranges of (the Phong heads' weights and biases): x [1, 5, 6, 9] -> one 3x3 conv to 6
// channels on the weights [3 + 2 + 1, 5, 3, 3] and biases [3 + 2 + 1] of three parts ->
// sigmoid -> MSE. Against the same graph where a sigmoid nobody uses also reads a weight part
// and a bias part, so neither concatenation is a joint (copies): the output, every part's
// gradient and the parts after two Adam steps equal to the bit; a forward makes 6 dispatches
// fewer (the copies), and a backward 6 more fewer. The biases' parts (3, 2 and 1 floats) start
// unaligned. With a spare parameter that gets no gradient, Adam takes each parameter's own
// views, and a joint's: the same values again; and with the parts declared in reverse.
#[test]
fn parameters_concatenated_along_axis_0_are_one_view_with_identical_values_and_gradients() {
    use rendernet::ops::conv::{Conv, Padding};
    let (h, w, sizes) = (6usize, 9usize, [3usize, 2, 1]);
    let build = |copies: bool, spare: bool, reversed: bool| {
        let mut g = Graph::new();
        let x = g.input("x", &[1, 5, h, w]).unwrap();
        let mut parts = (vec![x; 3], vec![x; 3]);
        // Declared in the concatenation's order or the reverse: the layout follows the former.
        for k in if reversed { [2, 1, 0] } else { [0, 1, 2] } {
            parts.0[k] = g.param(&format!("p{k}.weight"), &[sizes[k], 5, 3, 3], Init::Xavier).unwrap();
            parts.1[k] = g.param(&format!("p{k}.bias"), &[sizes[k]], Init::Constant(0.1 * k as f32 - 0.1)).unwrap();
        }
        if spare {
            g.param("spare", &[4], Init::Constant(1.0)).unwrap();
        }
        if copies {
            g.apply("unused.w", Op::Sigmoid, &[parts.0[1]]).unwrap();
            g.apply("unused.b", Op::Sigmoid, &[parts.1[2]]).unwrap();
        }
        let wj = g.apply("joint.weight", Op::ConcatAxis0(sizes.to_vec()), &parts.0).unwrap();
        let bj = g.apply("joint.bias", Op::ConcatAxis0(sizes.to_vec()), &parts.1).unwrap();
        let y = g.apply("joint", Op::Conv(Conv::conv2d([3, 3], [1, 1], Padding::Same)), &[x, wj, bj]).unwrap();
        let y = g.apply("joint.sigmoid", Op::Sigmoid, &[y]).unwrap();
        let t = g.input("t", &[1, 6, h, w]).unwrap();
        let loss = g.apply("loss", Op::Loss(Loss::Mse), &[y, t]).unwrap();
        let params: Vec<Value> = parts.0.iter().chain(&parts.1).copied().collect();
        (g, x, t, y, loss, params)
    };
    let run = |copies: bool, spare: bool, reversed: bool| {
        let (g, x, t, y, loss, params) = build(copies, spare, reversed);
        let mut ex = Executor::new(gpu(), g, 7).unwrap();
        ex.feed(gpu(), x, &f32v(&Rng(8).vec(5 * h * w, -1.0, 1.0))).unwrap();
        ex.feed(gpu(), t, &f32v(&Rng(9).vec(6 * h * w, 0.0, 1.0))).unwrap();
        ex.keep(y);
        let fw = ex.forward(gpu()).unwrap().dispatches;
        let mut got = vec![ex.read(gpu(), y).unwrap()];
        let bw = ex.backward(gpu(), loss).unwrap().dispatches;
        got.extend(params.iter().map(|&p| ex.grad(gpu(), p).unwrap()));
        for _ in 0..2 {
            ex.train_step(gpu(), loss, &Adam::new(1e-2)).unwrap();
        }
        got.extend(params.iter().map(|&p| ex.read(gpu(), p).unwrap()));
        (got, fw, bw)
    };
    for (spare, reversed) in [(false, false), (true, false), (false, true)] {
        let ((joint, fw_j, bw_j), (copied, fw_c, bw_c)) = (run(false, spare, reversed), run(true, spare, reversed));
        let case = format!("spare parameter {spare}, declared in reverse {reversed}");
        assert_eq!(joint, copied, "{case}: joints against copies");
        // The copies' graph also runs its two unused sigmoids in a forward.
        assert_eq!((fw_c - fw_j, bw_c - bw_j), (6 + 2, 12 + 2), "{case}: dispatches");
    }
    // Only the parts that want a gradient get one, as when the concatenation copied.
    let (g, _, _, _, loss, params) = build(false, false, false);
    let mut ex = Executor::new(gpu(), g, 7).unwrap();
    ex.freeze_params();
    ex.want_grad(params[0]);
    ex.backward(gpu(), loss).unwrap();
    assert!(ex.grad(gpu(), params[0]).is_ok());
    assert!(ex.grad(gpu(), params[1]).is_err(), "a frozen part has no gradient");
}

// A joint's part may start unaligned, and a resize-convolution's projection binds its weight:
// the executor refuses the pair with a clear error instead of a binding failure.
#[test]
fn a_joint_part_cannot_be_a_resize_convolution() {
    let mut g = Graph::new();
    let a = g.param("a.weight", &[1, 2, 4, 4], Init::Xavier).unwrap();
    let b = g.param("b.weight", &[2, 2, 4, 4], Init::Xavier).unwrap();
    g.apply("w", Op::ConcatAxis0(vec![1, 2]), &[a, b]).unwrap();
    let lone = g.param("lone.weight", &[1, 2, 4, 4], Init::Xavier).unwrap();
    let mut ex = Executor::new(gpu(), g, 1).unwrap();
    let e = ex.keep_resize_conv(gpu(), a).unwrap_err().to_string();
    assert!(e.contains("'a.weight'") && e.contains("concatenation"), "{e}");
    ex.keep_resize_conv(gpu(), lone).unwrap();
}

// An add hands its output's gradient on as one input's first gradient, the same tensor with no
// copy (`Executor::hands_on`): h = prelu(x), inner = h + h, outer = h + inner, MSE against a
// target. outer's backward hands dy to h; inner's then sums two more contributions into that
// very tensor. Against the same graph with outer's gradient asked for by the caller (so dy
// stays outer's and h gets a copy): gradients equal to the bit, one dispatch fewer, and both
// match finite differences of mse(3 prelu(x), t).
#[test]
fn an_add_hands_its_gradient_on_without_a_copy() {
    let (shape, n) = ([1usize, 3, 5, 7], 105usize);
    let mut g = Graph::new();
    let x = g.input("x", &shape).unwrap();
    let t = g.input("target", &shape).unwrap();
    let alpha = g.param("act.alpha", &[3], Init::Constant(0.25)).unwrap();
    let h = g.apply("act", Op::Prelu, &[x, alpha]).unwrap();
    let inner = g.apply("inner", Op::Add, &[h, h]).unwrap();
    let outer = g.apply("outer", Op::Add, &[h, inner]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[outer, t]).unwrap();
    let mut rng = Rng(5);
    // Away from PReLU's kink at 0 so finite differences are clean.
    let xv: Vec<f64> = f32_round(&rng.vec(n, -2.0, 2.0)).into_iter().map(|v| if v.abs() < 0.01 { 0.5 } else { v }).collect();
    let tv = f32_round(&rng.vec(n, -1.0, 1.0));
    let run = |copy: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &f32v(&xv)).unwrap();
        ex.feed(gpu(), t, &f32v(&tv)).unwrap();
        ex.want_grad(x);
        if copy {
            ex.want_grad(outer);
        }
        ex.training = false;
        let stats = ex.backward(gpu(), loss).unwrap();
        (stats.dispatches, ex.grad(gpu(), x).unwrap(), ex.grad(gpu(), alpha).unwrap())
    };
    let (handed, copied) = (run(false), run(true));
    assert_eq!(handed.1, copied.1, "d loss / d x");
    assert_eq!(handed.2, copied.2, "d loss / d alpha");
    assert_eq!(handed.0 + 1, copied.0, "dispatches handing dy on, then copying it");
    let prelu = |x: &[f64], a: f64| -> Vec<f64> { x.iter().map(|&v| if v > 0.0 { v } else { a * v }).collect() };
    let reference = |x: &[f64], a: &[f64]| -> f64 {
        let y: Vec<f64> = x.chunks(35).zip(a).flat_map(|(c, &a)| prelu(c, a)).collect();
        y.iter().zip(&tv).map(|(y, t)| (3.0 * y - t).powi(2)).sum::<f64>() / n as f64
    };
    let a = [0.25; 3];
    let f64v = |v: &[f32]| -> Vec<f64> { v.iter().map(|&v| v as f64).collect() };
    // Sums of a few f32 terms over 105 values: errors ~1e-7 of gradients ~1e-2.
    assert_close("d loss / d x", &f64v(&handed.1), &fd_grad(&xv, |x| reference(x, &a)), 1e-6, 1e-3);
    assert_close("d loss / d alpha", &f64v(&handed.2), &fd_grad(&a, |a| reference(&xv, a)), 1e-6, 1e-3);
}
