//! Conv3d, conv2d and their transposes against f64 references: forward, and every gradient
//! (input, weights, bias) against central finite differences of the reference forward (of
//! every value, or of 500 random ones in the larger tensors: `fd_sample`). The
//! cases cover the paper's layers (conv 5^3 s2, 3^3 s(1,1,2), 3^3; 2D 3x3, 4x4 SAME;
//! transposed 4x4 s2 and s1), even kernels (asymmetric SAME), 1x1, explicit asymmetric
//! padding, and random shapes. The tiled kernels' tests, which reuse these cases, are in
//! `conv/tiled.rs`.
//!
//! Tolerances: a conv value sums at most Cin*k^3 <= 3*125 products of values in [-1, 1] and
//! a weight gradient at most N*|out| <= 2*420 of them; f32 accumulation error is then
//! < ~sqrt(840)*6e-8*|terms| ~ 1e-5 absolute, so atol 1e-4 + rtol 1e-4 leaves 10x headroom
//! while a dropped tap or misplaced offset changes results by ~1e-1. The references are
//! linear in each input, so central differences are exact up to f64 roundoff (~1e-8).

mod common;
mod reference;

use common::*;
use reference::conv::{self as rc, Geom};
use rendernet::ops::conv::{self, Conv, ConvKernel, Padding};
use rendernet::gpu::Tensor;
use rendernet::ops::conv_transpose::ConvTranspose;

#[path = "conv/tiled.rs"]
mod tiled;
#[path = "conv/cols4.rs"]
mod cols4;
#[path = "conv/wide.rs"]
mod wide;

const ATOL: f64 = 1e-4;
const RTOL: f64 = 1e-4;
/// The most values of x or w a case differences (see `fd_sample`).
const FD_MAX: usize = 500;

/// The op under test.
#[derive(Clone, Copy, Debug)]
enum Op {
    Conv(Conv),
    Transposed(ConvTranspose),
}

impl Op {
    fn hyper(&self) -> Conv {
        match self {
            Op::Conv(c) => *c,
            Op::Transposed(t) => t.conv,
        }
    }
}

/// One test configuration. `input` is the op's input spatial size (depth 1 for 2D);
/// `output` overrides a transposed conv's default output size (PyTorch's output_padding).
#[derive(Clone, Copy, Debug)]
struct Case {
    op: Op,
    kernel: ConvKernel,
    d2: bool,
    n: usize,
    ci: usize,
    co: usize,
    input: [usize; 3],
    output: Option<[usize; 3]>,
}

fn shape(d2: bool, a: usize, b: usize, sp: [usize; 3]) -> Vec<usize> {
    if d2 { vec![a, b, sp[1], sp[2]] } else { vec![a, b, sp[0], sp[1], sp[2]] }
}

/// Padding per axis from the hyper-parameters, computing SAME independently of the crate.
/// `len` is the forward conv's input length on `axis`.
fn pads(c: &Conv, axis: usize, len: usize) -> (usize, usize) {
    match c.padding {
        Padding::Same => {
            let (_, b, a) = rc::same_pads(len, c.kernel[axis], c.stride[axis]);
            (b, a)
        }
        Padding::Explicit { before, after } => (before[axis], after[axis]),
    }
}

/// The reference geometry of a case.
fn geom(c: &Case) -> Geom {
    let h = c.op.hyper();
    let (mut output, mut before) = ([0; 3], [0; 3]);
    for a in 0..3 {
        let (len, k, s) = (c.input[a], h.kernel[a], h.stride[a]);
        match c.op {
            Op::Conv(_) => {
                let (b, af) = pads(&h, a, len);
                output[a] = (len + b + af - k) / s + 1;
                before[a] = b;
            }
            Op::Transposed(_) => {
                output[a] = match (c.output, h.padding) {
                    (Some(o), _) => o[a],
                    (None, Padding::Same) => len * s,
                    (None, Padding::Explicit { before, after }) => (len - 1) * s + k - before[a] - after[a],
                };
                before[a] = pads(&h, a, output[a]).0;
            }
        }
    }
    Geom { n: c.n, ci: c.ci, co: c.co, input: c.input, output, kernel: h.kernel, stride: h.stride, before }
}

fn w_shape(c: &Case) -> Vec<usize> {
    let k = c.op.hyper().kernel;
    match c.op {
        Op::Conv(_) => shape(c.d2, c.co, c.ci, k),
        Op::Transposed(_) => shape(c.d2, c.ci, c.co, k),
    }
}

fn reference(c: &Case, g: &Geom, x: &[f64], w: &[f64], b: Option<&[f64]>) -> Vec<f64> {
    match c.op {
        Op::Conv(_) => rc::conv(g, x, w, b),
        Op::Transposed(_) => rc::conv_transpose(g, x, w, b),
    }
}

/// A forward run: the inputs, the GPU's output and the reference's.
struct Forward {
    x: Vec<f64>,
    w: Vec<f64>,
    b: Vec<f64>,
    y: Vec<f64>,
    want: Vec<f64>,
    g: Geom,
}

/// Runs forward with bias on random inputs, on the GPU and in the reference.
fn forward(c: &Case, rng: &mut Rng) -> Forward {
    let g = geom(c);
    let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(c), shape(c.d2, c.n, c.co, g.output));
    let got_shape = match c.op {
        Op::Conv(op) => op.output_shape(&xs, &ws).unwrap(),
        Op::Transposed(op) => op.output_shape(&xs, &ws).unwrap(),
    };
    if c.output.is_none() {
        assert_eq!(got_shape, ys, "{c:?}: output_shape");
    }
    let numel = |s: &[usize]| s.iter().product::<usize>();
    let x = f32_round(&rng.vec(numel(&xs), -1.0, 1.0));
    let w = f32_round(&rng.vec(numel(&ws), -1.0, 1.0));
    let b = f32_round(&rng.vec(c.co, -1.0, 1.0));
    let (tx, tw, tb, ty) = (upload(&xs, &x), upload(&ws, &w), upload(&[c.co], &b), zeros(&ys));
    run(|p| match c.op {
        Op::Conv(op) => op.forward(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &ty),
        Op::Transposed(op) => op.forward(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &ty),
    });
    let want = reference(c, &g, &x, &w, Some(&b));
    Forward { y: download(&ty), x, w, b, want, g }
}

/// Forward against the reference, then every gradient against finite differences.
fn check(c: &Case, seed: u64) {
    let mut rng = Rng(seed);
    let Forward { x, w, b, y, want, g } = forward(c, &mut rng);
    assert_close(&format!("{c:?} forward"), &y, &want, ATOL, RTOL);

    let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(c), shape(c.d2, c.n, c.co, g.output));
    let r = f32_round(&rng.vec(want.len(), -1.0, 1.0));
    let (tx, tw, tr) = (upload(&xs, &x), upload(&ws, &w), upload(&ys, &r));
    let (tdx, tdw, tdb) = (zeros(&xs), zeros(&ws), zeros(&[c.co]));
    run(|p| {
        match c.op {
            Op::Conv(op) => {
                op.backward_input(c.kernel, gpu(), p, &tr, &tw, &tdx)?;
                op.backward_weight(c.kernel, gpu(), p, &tx, &tr, &tdw)?;
            }
            Op::Transposed(op) => {
                op.backward_input(c.kernel, gpu(), p, &tr, &tw, &tdx)?;
                op.backward_weight(c.kernel, gpu(), p, &tx, &tr, &tdw)?;
            }
        }
        conv::backward_bias(gpu(), p, &tr, &tdb)
    });
    let loss = |x: &[f64], w: &[f64], b: &[f64]| dot(&r, &reference(c, &g, x, w, Some(b)));
    // Large cases difference a random sample of each tensor (`fd_sample`): every value of
    // both is still checked against the reference through the forward above.
    let (at_x, at_w) = (fd_sample(x.len(), FD_MAX, &mut rng), fd_sample(w.len(), FD_MAX, &mut rng));
    let pick = |t: &Tensor, at: &[usize]| -> Vec<f64> {
        let all = download(t);
        at.iter().map(|&i| all[i]).collect()
    };
    let dx = fd_grad_at(&x, at_x.iter().copied(), |x| loss(x, &w, &b));
    assert_close(&format!("{c:?} dx"), &pick(&tdx, &at_x), &dx, ATOL, RTOL);
    let dw = fd_grad_at(&w, at_w.iter().copied(), |w| loss(&x, w, &b));
    assert_close(&format!("{c:?} dw"), &pick(&tdw, &at_w), &dw, ATOL, RTOL);
    let db = fd_grad(&b, |b| loss(&x, &w, b));
    assert_close(&format!("{c:?} db"), &download(&tdb), &db, ATOL, RTOL);
}

fn conv3d(kernel: [usize; 3], stride: [usize; 3], padding: Padding) -> Case {
    let op = Op::Conv(Conv::conv3d(kernel, stride, padding));
    Case { op, kernel: ConvKernel::Reference, d2: false, n: 2, ci: 3, co: 5, input: [5, 6, 7], output: None }
}

fn conv2d(kernel: [usize; 2], stride: [usize; 2], padding: Padding) -> Case {
    let op = Op::Conv(Conv::conv2d(kernel, stride, padding));
    Case { op, kernel: ConvKernel::Reference, d2: true, n: 2, ci: 3, co: 5, input: [1, 7, 9], output: None }
}

fn explicit(before: [usize; 3], after: [usize; 3]) -> Padding {
    Padding::Explicit { before, after }
}

#[test]
fn conv3d_3x3x3_same() {
    check(&conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 10);
}

#[test]
fn conv3d_3x3x3_stride_1_1_2_same() {
    check(&conv3d([3, 3, 3], [1, 1, 2], Padding::Same), 11);
}

#[test]
fn conv3d_5x5x5_stride_2_same() {
    check(&conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 12);
}

#[test]
fn conv3d_even_2x3x4_same_is_asymmetric() {
    // SAME pads (0,1), (1,1), (1,2): the even axes pad more after than before.
    check(&conv3d([2, 3, 4], [1, 1, 1], Padding::Same), 13);
    check(&conv3d([2, 3, 4], [1, 1, 2], Padding::Same), 14);
}

#[test]
fn conv3d_1x1x1() {
    check(&conv3d([1, 1, 1], [1, 1, 1], Padding::Same), 15);
}

#[test]
fn conv3d_explicit_asymmetric_stride_2() {
    check(&conv3d([3, 3, 3], [2, 2, 2], explicit([1, 0, 2], [0, 2, 1])), 16);
}

#[test]
fn conv2d_3x3_and_4x4_same() {
    check(&conv2d([3, 3], [1, 1], Padding::Same), 20);
    check(&conv2d([4, 4], [1, 1], Padding::Same), 21);
}

#[test]
fn conv2d_strided_1x1_and_explicit() {
    check(&conv2d([3, 3], [2, 1], Padding::Same), 22);
    check(&conv2d([1, 1], [1, 1], Padding::Same), 23);
    check(&conv2d([4, 3], [2, 1], Padding::explicit_2d([2, 0], [1, 1])), 24);
}

fn transposed2d(kernel: [usize; 2], stride: [usize; 2], padding: Padding, output: Option<[usize; 3]>) -> Case {
    let op = Op::Transposed(ConvTranspose::conv2d(kernel, stride, padding));
    Case { op, kernel: ConvKernel::Reference, d2: true, n: 2, ci: 3, co: 5, input: [1, 4, 5], output }
}

fn transposed3d(kernel: [usize; 3], stride: [usize; 3], padding: Padding, output: Option<[usize; 3]>) -> Case {
    let op = Op::Transposed(ConvTranspose::conv3d(kernel, stride, padding));
    Case { op, kernel: ConvKernel::Reference, d2: false, n: 2, ci: 3, co: 5, input: [3, 4, 5], output }
}

#[test]
fn conv_transpose2d_4x4_same_stride_2_and_1() {
    check(&transposed2d([4, 4], [2, 2], Padding::Same, None), 30);
    check(&transposed2d([4, 4], [1, 1], Padding::Same, None), 31);
}

#[test]
fn conv_transpose2d_explicit_and_output_padding() {
    check(&transposed2d([3, 3], [2, 1], Padding::explicit_2d([1, 0], [0, 2]), None), 32);
    // PyTorch k3 s2 p1 output_padding 1: 4x5 -> 8x10 rather than the default 7x9.
    check(&transposed2d([3, 3], [2, 2], Padding::explicit_2d([1, 1], [1, 1]), Some([1, 8, 10])), 33);
}

#[test]
fn conv_transpose3d_same_and_explicit() {
    check(&transposed3d([4, 4, 4], [2, 2, 2], Padding::Same, None), 34);
    check(&transposed3d([3, 2, 3], [1, 2, 2], explicit([1, 0, 2], [0, 1, 1]), None), 35);
}

/// Random shapes and hyper-parameters, forward only (the gradients share these kernels and
/// are checked above on every padding and stride form).
#[test]
fn random_shapes_forward() {
    for seed in 100..108u64 {
        let mut rng = Rng(seed);
        let mut pick = |lo: usize, hi: usize| lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
        // Seeds 100..108 cover {2D, 3D} x {SAME, explicit} x {conv, transposed}; the rest is random.
        let d2 = seed % 8 >= 4;
        let mut kernel = [pick(1, 4), pick(1, 4), pick(1, 4)];
        let mut stride = [pick(1, 3), pick(1, 3), pick(1, 3)];
        let mut input = [pick(4, 7), pick(4, 7), pick(4, 7)];
        let (mut before, mut after) = ([0; 3], [0; 3]);
        for a in 0..3 {
            before[a] = pick(0, kernel[a] - 1);
            after[a] = pick(0, kernel[a] - 1);
        }
        if d2 {
            (kernel[0], stride[0], input[0], before[0], after[0]) = (1, 1, 1, 0, 0);
        }
        let padding = if (seed / 2) % 2 == 0 { Padding::Same } else { explicit(before, after) };
        let (n, ci, co) = (pick(1, 3), pick(1, 5), pick(1, 5));
        let h = Conv { kernel, stride, padding };
        let op = if seed % 2 == 0 { Op::Conv(h) } else { Op::Transposed(ConvTranspose { conv: h }) };
        let c = Case { op, kernel: ConvKernel::Reference, d2, n, ci, co, input, output: None };
        let Forward { y, want, .. } = forward(&c, &mut Rng(seed + 1000));
        assert_close(&format!("seed {seed}: {c:?} forward"), &y, &want, ATOL, RTOL);
    }
}

#[test]
fn bad_shapes_are_errors() {
    let c = Conv::conv3d([3, 3, 3], [1, 1, 1], Padding::Same);
    let (x, w, b, y) = (zeros(&[2, 3, 5, 6, 7]), zeros(&[5, 3, 3, 3, 3]), zeros(&[5]), zeros(&[2, 5, 5, 6, 7]));
    let expect_err = |what: &str, r: rendernet::Result<()>, needle: &str| {
        let e = r.expect_err(what).to_string();
        assert!(e.contains(needle), "{what}: error `{e}` should mention `{needle}`");
    };
    let run = |f: &dyn Fn(&mut wgpu::ComputePass<'_>) -> rendernet::Result<()>| gpu().run(|p| f(p));
    // Channel mismatch: weights expect 4 input channels.
    let w4 = zeros(&[5, 4, 3, 3, 3]);
    expect_err("channels", run(&|p| c.forward(ConvKernel::Auto, gpu(), p, &x, &w4, Some(&b), &y)), "channels");
    // Wrong output shape, wrong bias, wrong kernel size.
    let y_bad = zeros(&[2, 5, 5, 6, 6]);
    expect_err("output", run(&|p| c.forward(ConvKernel::Auto, gpu(), p, &x, &w, Some(&b), &y_bad)), "conv_forward");
    expect_err("bias", run(&|p| c.forward(ConvKernel::Auto, gpu(), p, &x, &w, Some(&zeros(&[4])), &y)), "bias");
    let w_k = zeros(&[5, 3, 3, 3, 2]);
    expect_err("kernel", run(&|p| c.forward(ConvKernel::Auto, gpu(), p, &x, &w_k, None, &y)), "kernel");
    // Backward passes check their gradients' shapes.
    expect_err("dx", run(&|p| c.backward_input(ConvKernel::Auto, gpu(), p, &y_bad, &w, &x)), "dy");
    expect_err("dw", run(&|p| c.backward_weight(ConvKernel::Auto, gpu(), p, &x, &y, &w4)), "channels");
    expect_err("db", run(&|p| conv::backward_bias(gpu(), p, &y, &zeros(&[4]))), "db");
    // 2D input with a 3D kernel; a kernel larger than the padded input.
    let c2 = Conv::conv2d([3, 3], [1, 1], Padding::Same);
    assert!(c.output_shape(&[2, 3, 7, 9], &[5, 3, 3, 3]).is_err());
    assert!(c2.output_shape(&[2, 3, 7, 9], &[5, 3, 3, 3]).is_ok());
    let big = Conv::conv2d([5, 5], [1, 1], Padding::Explicit { before: [0; 3], after: [0; 3] });
    assert!(big.output_shape(&[1, 1, 4, 9], &[1, 1, 5, 5]).unwrap_err().to_string().contains("larger"));
    // Transposed: output that the equivalent conv does not map back to the input.
    let t = ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same);
    let (tx, tw) = (zeros(&[2, 3, 4, 5]), zeros(&[3, 5, 4, 4]));
    assert_eq!(t.output_shape(tx.shape(), tw.shape()).unwrap(), vec![2, 5, 8, 10]);
    let ty_bad = zeros(&[2, 5, 8, 11]);
    expect_err("transposed y", run(&|p| t.forward(ConvKernel::Auto, gpu(), p, &tx, &tw, None, &ty_bad)), "does not fit");
    let tw_bad = zeros(&[5, 3, 4, 4]);
    expect_err("transposed w", run(&|p| t.forward(ConvKernel::Auto, gpu(), p, &tx, &tw_bad, None, &zeros(&[2, 5, 8, 10]))), "conv_transpose");
    assert!(t.output_shape(&[2, 4, 4, 5], tw.shape()).is_err());
}

/// `Init::XavierUpsample` makes a 4x4 stride-2 transposed conv start as nearest upsampling
/// followed by a 3x3 conv: a constant input then gives a constant output away from the
/// border (every output phase sums the same weights), i.e. no checkerboard. Plain Xavier
/// weights do not (checked too, so the assertion can fail).
#[test]
fn upsample_init_gives_no_checkerboard() {
    use rendernet::graph::Init;
    let (ci, co, h, w) = (3, 2, 6, 7);
    let (oh, ow) = (2 * h, 2 * w);
    let g = Geom {
        n: 1,
        ci,
        co,
        input: [1, h, w],
        output: [1, oh, ow],
        kernel: [1, 4, 4],
        stride: [1, 2, 2],
        before: [0, rc::same_pads(oh, 4, 2).1, rc::same_pads(ow, 4, 2).1],
    };
    let x = vec![1.0; ci * h * w];
    // Largest spread of one channel's interior values (rows and columns 2.. from each edge).
    let spread = |init: Init| {
        let wt: Vec<f64> = init.values(&[ci, co, 4, 4], 5, 9).into_iter().map(f64::from).collect();
        let y = rc::conv_transpose(&g, &x, &wt, None);
        (0..co)
            .map(|c| {
                let v: Vec<f64> = (2..oh - 2).flat_map(|r| (2..ow - 2).map(move |q| (r, q))).map(|(r, q)| y[(c * oh + r) * ow + q]).collect();
                v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
            })
            .fold(0.0, f64::max)
    };
    // f32 weights summed in f64: the interior is equal to ~1e-6.
    assert!(spread(Init::XavierUpsample) < 1e-5, "phases differ: {}", spread(Init::XavierUpsample));
    assert!(spread(Init::Xavier) > 1e-2, "plain Xavier unexpectedly flat: {}", spread(Init::Xavier));
}
