//! Conv3d, conv2d and their transposes against f64 references: forward, and every gradient
//! (input, weights, bias) against central finite differences of the reference forward. The
//! cases cover the paper's layers (conv 5^3 s2, 3^3 s(1,1,2), 3^3; 2D 3x3, 4x4 SAME;
//! transposed 4x4 s2 and s1), even kernels (asymmetric SAME), 1x1, explicit asymmetric
//! padding, and random shapes.
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
use rendernet::ops::conv_transpose::ConvTranspose;

const ATOL: f64 = 1e-4;
const RTOL: f64 = 1e-4;

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
    let dx = fd_grad(&x, |x| loss(x, &w, &b));
    assert_close(&format!("{c:?} dx"), &download(&tdx), &dx, ATOL, RTOL);
    let dw = fd_grad(&w, |w| loss(&x, w, &b));
    assert_close(&format!("{c:?} dw"), &download(&tdw), &dw, ATOL, RTOL);
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

/// Every case above, again with each family of tiled kernels forced (`ConvKernel::Buffers`
/// reads buffers, `ConvKernel::Texture` textures and subgroup shuffles for the forward and
/// backward-input passes).
fn check_fast(c: Case, seed: u64) {
    check(&Case { kernel: ConvKernel::Buffers, ..c }, seed);
    check(&Case { kernel: ConvKernel::Texture, ..c }, seed);
}

#[test]
fn fast_conv3d_forward_and_gradients() {
    check_fast(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 40);
    check_fast(conv3d([3, 3, 3], [1, 1, 2], Padding::Same), 41);
    check_fast(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 42);
    check_fast(conv3d([2, 3, 4], [1, 1, 1], Padding::Same), 43);
    check_fast(conv3d([1, 1, 1], [1, 1, 1], Padding::Same), 44);
    check_fast(conv3d([3, 3, 3], [2, 2, 2], explicit([1, 0, 2], [0, 2, 1])), 45);
}

#[test]
fn fast_conv2d_and_transposed_forward_and_gradients() {
    check_fast(conv2d([3, 3], [1, 1], Padding::Same), 50);
    check_fast(conv2d([4, 4], [1, 1], Padding::Same), 51);
    check_fast(conv2d([4, 3], [2, 1], Padding::explicit_2d([2, 0], [1, 1])), 52);
    check_fast(transposed2d([4, 4], [2, 2], Padding::Same, None), 53);
    check_fast(transposed2d([4, 4], [1, 1], Padding::Same, None), 54);
    check_fast(transposed2d([3, 3], [2, 2], Padding::explicit_2d([1, 1], [1, 1]), Some([1, 8, 10])), 55);
    check_fast(transposed3d([3, 2, 3], [1, 2, 2], explicit([1, 0, 2], [0, 1, 1]), None), 56);
}

/// Strided backward input (and transposed forward) runs one stride-1 conv per output phase
/// with a sub-kernel of the taps that reach it: a 1x1 stride-2 kernel (phases with no taps,
/// dx zero there), padding before larger than the kernel (negative phase padding), stride 3,
/// and stride (1, 2, 2) even kernels with explicit asymmetric padding and output_padding-style
/// larger outputs.
#[test]
fn fast_backward_input_by_phase() {
    check_fast(conv2d([1, 1], [2, 2], Padding::Same), 70);
    check_fast(conv2d([2, 3], [2, 3], Padding::explicit_2d([3, 1], [0, 2])), 71);
    check_fast(transposed2d([4, 4], [2, 2], Padding::explicit_2d([1, 2], [2, 1]), Some([1, 8, 10])), 72);
    check_fast(transposed3d([2, 4, 4], [1, 2, 2], explicit([0, 2, 1], [1, 1, 2]), Some([3, 8, 10])), 73);
}

/// The tiled kernels at channel counts that are not multiples of their tile (inputs padded to
/// 4, outputs to 16 with zeros; the texture family's 4- and 8-channel tiles): 1, 2, 3, 4, 5 in
/// and 1, 3, 5, 7, 8, 20 out, conv and transposed, including the first layer's shapes (3D, 1 or
/// 4 input channels to 8 or 20, 5^3 stride 2: the texture family's direct kernels) and the 1-
/// and 3-channel heads.
#[test]
fn fast_small_channel_counts_forward_and_gradients() {
    let with = |c: Case, ci: usize, co: usize| Case { ci, co, ..c };
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 3), 60);
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 8), 58);
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 4, 7), 59);
    // 20 out: three groups of 8 output channels in the direct kernels, over two of 16.
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 20), 57);
    check_fast(with(conv3d([3, 3, 3], [2, 1, 1], Padding::Same), 2, 1), 61);
    check_fast(with(conv3d([3, 2, 3], [1, 2, 1], explicit([1, 0, 2], [0, 1, 1])), 5, 5), 62);
    check_fast(with(conv2d([3, 3], [1, 1], Padding::Same), 3, 1), 63);
    check_fast(with(conv2d([3, 3], [1, 1], Padding::Same), 5, 3), 64);
    check_fast(with(conv2d([4, 3], [2, 1], Padding::explicit_2d([2, 0], [1, 1])), 1, 5), 65);
    check_fast(with(transposed2d([4, 4], [2, 2], Padding::Same, None), 2, 3), 66);
    check_fast(with(transposed2d([3, 3], [2, 2], Padding::explicit_2d([1, 1], [1, 1]), Some([1, 8, 10])), 5, 1), 67);
    check_fast(with(transposed3d([4, 4, 4], [2, 2, 2], Padding::Same, None), 1, 5), 68);
    check_fast(with(transposed3d([3, 2, 3], [1, 2, 2], explicit([1, 0, 2], [0, 1, 1]), None), 3, 3), 69);
}

/// The texture family's direct kernels (`conv_direct_forward`, its `_k5s2` form,
/// `conv_direct_backward_weight`, its `_k5` form for 5 tap rows), which run the convs the other families fold (few input
/// channels), forced onto textures:
/// 20 output channels (three groups of 8 over two of 16) at a width of 7 (the stage's scalar
/// path); 2 input channels, a 3x7 kernel at stride (1, 2) with explicit padding (two chunks of
/// 4 W taps) at width 12 (the stage's vec4 path); 3 output channels (dy packed 4 to a texel).
#[test]
fn direct_kernels_of_few_input_channels() {
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { ci, co, input, kernel: ConvKernel::Texture, ..c };
    check(&with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 20, [5, 6, 7]), 97);
    check(&with(conv2d([3, 7], [1, 2], Padding::explicit_2d([1, 2], [1, 4])), 2, 6, [1, 6, 12]), 98);
    check(&with(conv3d([3, 3, 3], [2, 1, 1], Padding::Same), 1, 3, [4, 5, 9]), 99);
    // 5x5 at row stride 2 (`conv_direct_forward_k5s2`): two tiles of output rows (oh 10), two
    // input channels, a second group of output channels partly filled.
    check(&with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 2, 9, [3, 19, 11]), 100);
    // The same at column stride 1, where the fifth W tap falls on every position of a texel.
    check(&with(conv2d([5, 5], [2, 1], Padding::Same), 1, 5, [1, 17, 9]), 104);
}

/// The texture family's 4- and 8-channel tiles (`conv_fast_forward_tex4`, its `_rows3` form,
/// `..._tex8`, `..._backward_weight_tex4`) on heads with enough input channels not to fold
/// (8 -> 3, 16 -> 1, 12 -> 7, 3x3), forced onto textures: with fewer input channels the direct
/// kernels run instead.
#[test]
fn texture_heads_of_at_most_eight_output_channels() {
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { ci, co, input, kernel: ConvKernel::Texture, ..c };
    check(&with(conv2d([3, 3], [1, 1], Padding::Same), 8, 3, [1, 5, 9]), 88);
    check(&with(conv2d([3, 3], [1, 1], Padding::Same), 16, 1, [1, 6, 7]), 89);
    // Two tiles of output rows (oh 11, 9; 3 channels: `conv_fast_forward_tex4_rows3`, whose 3
    // tap rows share their input rows; 7: `..._tex8`); and 3 tap rows at row stride 2, which
    // `..._tex8` runs.
    check(&with(conv2d([3, 3], [1, 1], Padding::Same), 8, 3, [1, 11, 5]), 101);
    check(&with(conv2d([3, 3], [1, 1], Padding::Same), 12, 7, [1, 9, 10]), 102);
    check(&with(conv2d([3, 3], [2, 1], Padding::Same), 8, 6, [1, 13, 5]), 103);
}

/// Widths that are multiples of 4 (12 and 8, not powers of two), where the texture family
/// packs its unfolded operands four voxels along W per load (`conv_fast_pack_tex_w4`): the
/// forward's x and the backward passes' dy (12 wide at stride 1; 4 wide after stride 3), with
/// channel counts that leave a part-filled quad (5 and 3 in, 7 and 6 out), 2 batch items; and
/// the first layers' input as the direct kernels stage it, four voxels along W per vec4 load.
#[test]
fn fast_widths_a_multiple_of_four() {
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { ci, co, input, ..c };
    check_fast(with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 5, 7, [3, 5, 12]), 90);
    check_fast(with(conv2d([3, 3], [1, 1], Padding::Same), 3, 6, [1, 6, 8]), 91);
    check_fast(with(conv2d([3, 3], [1, 3], Padding::Same), 6, 5, [1, 3, 12]), 92);
    // First layers (`conv_direct_*` on the input staged by `conv_direct_stage_w4`), which the
    // other families fold: 5^3 stride 2 folding H and W, 1 and 4 input channels; 3^3 on 1
    // channel folding W only;
    // 5x5 on a 4-wide grid, whose windows run off both sides.
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 8, [5, 6, 12]), 93);
    check_fast(with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 4, 7, [3, 7, 8]), 94);
    check_fast(with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 5, [3, 5, 8]), 95);
    check_fast(with(conv2d([5, 5], [1, 1], Padding::Same), 1, 3, [1, 5, 4]), 96);
}

/// The texture family's packings through uniform windows (src/gpu/window.rs; on CPU adapters,
/// widths a multiple of 4) against the reference kernels, all three passes, and the number of
/// forward dispatches that shows the windows ran (elsewhere: one packing, one weight packing,
/// the conv). Cases: a 1x1 conv (never folded) on 2 items of 5 channels (a quad with one real
/// channel) over planes of 2048 vec4s, packed per item and quad (4 dispatches), dy's 5 channels
/// padded to 16 for the weight gradient (two quads of none); planes of 4097 vec4s, so channel 1 starts
/// one vec4 past a binding alignment of 32 bytes and the chunks take 4095 rows, not 4096 (2
/// dispatches); the first layer's input staged for the direct kernels, 26384 vec4s in two
/// dispatches of four windows, the second's third window moved back to end at the tensor's end
/// (its fourth binds it again). Tolerances as in `fast_matches_reference_on_random_shapes`
/// (sums of at most 2 * 9 * 49 * 16 products here).
#[test]
fn packing_through_uniform_windows() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    let cases = [
        (with(conv2d([1, 1], [1, 1], Padding::Same), 2, 5, 5, [1, 64, 128]), 4),
        (with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 4, 3, [17, 241, 4]), 2),
        (with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 2, 1, 8, [17, 97, 32]), 2),
    ];
    for (seed, (c, windows)) in (300u64..).zip(cases) {
        let slow = passes(&c, ConvKernel::Reference, seed);
        let fast = passes(&c, ConvKernel::Texture, seed);
        for (k, what) in ["forward", "dx", "dw"].iter().enumerate() {
            assert_close(&format!("{c:?} {what}"), &fast[k], &slow[k], 1e-3, 1e-4);
        }
        let g = geom(&c);
        let (tx, tw, ty) = (zeros(&shape(c.d2, c.n, c.ci, g.input)), zeros(&w_shape(&c)), zeros(&shape(c.d2, c.n, c.co, g.output)));
        let Op::Conv(op) = c.op else { unreachable!() };
        let before = gpu().dispatch_count();
        run(|p| op.forward(ConvKernel::Texture, gpu(), p, &tx, &tw, None, &ty));
        let want = if gpu().info.device_type == wgpu::DeviceType::Cpu { windows + 2 } else { 3 };
        assert_eq!(gpu().dispatch_count() - before, want, "forward dispatches of {c:?}");
    }
}

/// The texture family's weight packing through uniform windows (`conv_fast_pack_weights_tex_window`,
/// CPU adapters) against the reference kernels, all three passes: weights of two windows read
/// flipped for a stride-2 backward input (four phases' sub-kernels); weights of less than one
/// window that are a view into a larger buffer (as in the flat parameter buffer; offset 4128
/// bytes), at stride (1, 1, 2); weights of four windows, the
/// last moved back to end at the buffer's end. Tolerances as in
/// `fast_matches_reference_on_random_shapes`.
#[test]
fn weight_packing_through_uniform_windows() {
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { n: 1, ci, co, input, kernel: ConvKernel::Texture, ..c };
    let cases = [
        (with(conv2d([3, 3], [2, 2], Padding::Same), 64, 40, [1, 7, 9]), None),
        (with(conv3d([3, 3, 3], [1, 1, 2], Padding::Same), 12, 20, [3, 5, 6]), Some(1032)),
        (with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 40, 48, [3, 4, 5]), None),
    ];
    for (seed, (c, w_at)) in (320u64..).zip(cases) {
        let slow = passes_with(&c, ConvKernel::Reference, seed, w_at);
        let fast = passes_with(&c, ConvKernel::Texture, seed, w_at);
        for (k, what) in ["forward", "dx", "dw"].iter().enumerate() {
            assert_close(&format!("{c:?} weights at {w_at:?}: {what}"), &fast[k], &slow[k], 1e-3, 1e-4);
        }
    }
}

/// Runs all three passes of `c` with `kernel` on fixed random inputs; returns (y, dx, dw).
fn passes(c: &Case, kernel: ConvKernel, seed: u64) -> [Vec<f64>; 3] {
    passes_with(c, kernel, seed, None)
}

/// [`passes`] with the weights, where `w_at` says so, a view at that value offset of a buffer
/// 16384 values longer than they need.
fn passes_with(c: &Case, kernel: ConvKernel, seed: u64, w_at: Option<usize>) -> [Vec<f64>; 3] {
    let g = geom(c);
    let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(c), shape(c.d2, c.n, c.co, g.output));
    let numel = |s: &[usize]| s.iter().product::<usize>();
    let mut rng = Rng(seed);
    let (x, w) = (rng.vec(numel(&xs), -1.0, 1.0), rng.vec(numel(&ws), -1.0, 1.0));
    let (b, r) = (rng.vec(c.co, -1.0, 1.0), rng.vec(numel(&ys), -1.0, 1.0));
    let tw = match w_at {
        None => upload(&ws, &w),
        Some(at) => {
            let big = zeros(&[at + w.len() + 16384]);
            let t = rendernet::Tensor::view(big.into_buffer(), at as u64 * 4, &ws).unwrap();
            t.write(gpu(), &w.iter().map(|&v| v as f32).collect::<Vec<_>>()).unwrap();
            t
        }
    };
    let (tx, tb, tr) = (upload(&xs, &x), upload(&[c.co], &b), upload(&ys, &r));
    let (ty, tdx, tdw) = (zeros(&ys), zeros(&xs), zeros(&ws));
    run(|p| match c.op {
        Op::Conv(op) => {
            op.forward(kernel, gpu(), p, &tx, &tw, Some(&tb), &ty)?;
            op.backward_input(kernel, gpu(), p, &tr, &tw, &tdx)?;
            op.backward_weight(kernel, gpu(), p, &tx, &tr, &tdw)
        }
        Op::Transposed(op) => {
            op.forward(kernel, gpu(), p, &tx, &tw, Some(&tb), &ty)?;
            op.backward_input(kernel, gpu(), p, &tr, &tw, &tdx)?;
            op.backward_weight(kernel, gpu(), p, &tx, &tr, &tdw)
        }
    });
    [download(&ty), download(&tdx), download(&tdw)]
}

/// The tiled kernels against the reference kernels on random shapes with channel counts that
/// are not multiples of the tiles (4 input channels, 16 output channels, 8 positions) and
/// spatial sizes not multiples of 8. Sums here reach Cin*k^3 <= 20*27 (forward, dx) and
/// N*|out| <= 2*900 (dw) products of values in [-1, 1]; both kernels' f32 errors are then
/// ~sqrt(1800)*6e-8*|terms| < 1e-4 apart, so atol 1e-3 + rtol 1e-4 still catches any
/// dropped term (>= 1e-2 for uniform data).
#[test]
fn fast_matches_reference_on_random_shapes() {
    for seed in 200..210u64 {
        let mut rng = Rng(seed);
        let mut pick = |lo: usize, hi: usize| lo + (rng.next_u64() % (hi - lo + 1) as u64) as usize;
        let d2 = seed % 2 == 1;
        let mut kernel = [pick(1, 3), pick(1, 4), pick(1, 4)];
        let mut stride = [pick(1, 3), pick(1, 2), pick(1, 3)];
        let mut input = [pick(3, 6), pick(3, 9), pick(5, 19)];
        // Explicit padding up to k + 1 before (more than the kernel: negative phase padding);
        // inputs of at least k + 2 keep both the conv's and the transposed conv's output
        // non-empty.
        let (mut before, mut after) = ([0; 3], [0; 3]);
        for a in 0..3 {
            before[a] = pick(0, kernel[a] + 1);
            after[a] = pick(0, kernel[a] - 1);
            input[a] = input[a].max(kernel[a] + 2);
        }
        if d2 {
            (kernel[0], stride[0], input[0], before[0], after[0]) = (1, 1, 1, 0, 0);
        }
        // Every third case at stride 1.
        if seed % 3 == 0 {
            stride = [1, 1, 1];
        }
        let (n, ci, co) = (pick(1, 2), pick(1, 20), pick(1, 35));
        let padding = if seed % 3 == 1 { explicit(before, after) } else { Padding::Same };
        let h = Conv { kernel, stride, padding };
        let op = if seed % 4 < 2 { Op::Conv(h) } else { Op::Transposed(ConvTranspose { conv: h }) };
        let c = Case { op, kernel: ConvKernel::Buffers, d2, n, ci, co, input, output: None };
        let slow = passes(&c, ConvKernel::Reference, seed);
        for kernel in [ConvKernel::Buffers, ConvKernel::Texture] {
            let fast = passes(&c, kernel, seed);
            for (k, what) in ["forward", "dx", "dw"].iter().enumerate() {
                assert_close(&format!("seed {seed}: {kernel:?} {c:?} {what}"), &fast[k], &slow[k], 1e-3, 1e-4);
            }
        }
    }
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

/// `Conv::backward` (both gradients in one call) equals `backward_input` then
/// `backward_weight` exactly on every kernel family, and on textures packs dy once where the
/// two packings agree (16 or at most 4 output channels: one dispatch fewer) but not where
/// they differ (8 or 20: dy padded to 8 or 20 channels for dx, 16 or 32 for dw).
#[test]
fn backward_in_one_call_equals_the_two_passes_and_packs_dy_once() {
    let textures = gpu().has_subgroups_of_8() && gpu().reads_rgba32f_storage();
    for (k, (c, co)) in [
        (conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 16),
        (conv2d([3, 3], [1, 1], Padding::Same), 3),
        (conv3d([3, 3, 3], [2, 1, 2], Padding::Same), 16),
        (conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 8),
        (conv2d([4, 3], [2, 1], Padding::explicit_2d([2, 0], [1, 1])), 20),
    ]
    .into_iter()
    .enumerate()
    {
        let Op::Conv(op) = c.op else { unreachable!() };
        let c = Case { co, ..c };
        let g = geom(&c);
        let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(&c), shape(c.d2, c.n, c.co, g.output));
        let mut rng = Rng(300 + k as u64);
        let mut up = |s: &[usize]| upload(s, &rng.vec(s.iter().product(), -1.0, 1.0));
        let (tx, tw, tdy) = (up(&xs), up(&ws), up(&ys));
        for kernel in [ConvKernel::Reference, ConvKernel::Buffers, ConvKernel::Texture] {
            let (dx1, dw1, dx2, dw2) = (zeros(&xs), zeros(&ws), zeros(&xs), zeros(&ws));
            let d0 = gpu().dispatch_count();
            run(|p| {
                op.backward_input(kernel, gpu(), p, &tdy, &tw, &dx1)?;
                op.backward_weight(kernel, gpu(), p, &tx, &tdy, &dw1)
            });
            let d1 = gpu().dispatch_count();
            run(|p| op.backward(kernel, gpu(), p, &tx, &tw, &tdy, Some(&dx2), Some(&dw2)));
            let d2 = gpu().dispatch_count();
            let what = format!("{kernel:?} {co} channels {:?}", op);
            assert_eq!(download(&dx2), download(&dx1), "dx, {what}");
            assert_eq!(download(&dw2), download(&dw1), "dw, {what}");
            let shared = textures && kernel == ConvKernel::Texture && (co == 16 || co <= 4);
            assert_eq!(d2 - d1, d1 - d0 - shared as u64, "dispatches, {what}");
        }
        // Either gradient alone.
        let (dx, dw) = (zeros(&xs), zeros(&ws));
        run(|p| op.backward(ConvKernel::Texture, gpu(), p, &tx, &tw, &tdy, Some(&dx), None));
        run(|p| op.backward(ConvKernel::Texture, gpu(), p, &tx, &tw, &tdy, None, Some(&dw)));
        let (dx1, dw1) = (zeros(&xs), zeros(&ws));
        run(|p| op.backward_input(ConvKernel::Texture, gpu(), p, &tdy, &tw, &dx1));
        run(|p| op.backward_weight(ConvKernel::Texture, gpu(), p, &tx, &tdy, &dw1));
        assert_eq!((download(&dx), download(&dw)), (download(&dx1), download(&dw1)), "one gradient at a time, {co} channels");
    }
}

