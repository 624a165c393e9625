//! The texture family's forward tile of 4 columns a lane (`conv_fast_forward_tex_w4`) and the
//! forward tiles' fused PReLU (`_prelu` entry points), against the f64 references of `conv.rs`,
//! whose cases, helpers and tolerances they share.

use super::*;

/// `conv_fast_forward_tex_w4` (a lane 4 columns x 4 rows x 16 channels, the 3 W taps in one
/// loop step, vec4 stores along W), which runs a texture forward of more than 8 output channels
/// with 3 W taps at column stride 1 on rows of whole column quads, 28 or more of them
/// (`conv_fast::cols4`; its unit test `cols4_runs_the_kernel_tests_shapes` holds for these
/// shapes, so a narrower rule fails there instead of quietly testing the 8-column tile), and the
/// input gradient of such convs: 8 -> 20 (two input quads; a second channel group part-filled;
/// fewer input channels fold into the direct kernels) on 7 x 28 (a row block of 4 and one of 3;
/// lane 7 past the row's end);
/// 16 -> 12 3D (depth taps off the grid, 4 input quads) on 3 x 5 x 32, whose input gradient
/// (12 -> 16) runs it too; 12 -> 3 at row stride 2 with explicit padding, batch 2 on 9 x 32,
/// whose input gradient runs it per row phase (rows 64 values apart, the second phase 32 values
/// in); and a 3x3 stride-1 transposed conv 4 -> 9 on 5 x 60 (two blocks of 32 columns).
#[test]
fn texture_forward_of_four_columns_a_lane() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    check(&with(conv2d([3, 3], [1, 1], Padding::Same), 1, 8, 20, [1, 7, 28]), 160);
    check(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 16, 12, [3, 5, 32]), 161);
    check(&with(conv2d([3, 3], [2, 1], Padding::explicit_2d([0, 1], [2, 1])), 2, 12, 3, [1, 9, 32]), 162);
    check(&with(transposed2d([3, 3], [1, 1], Padding::Same, None), 1, 4, 9, [1, 5, 60]), 163);
}

/// `Conv::forward_prelu` (the texture family's `_prelu` entry points) against the f64
/// reference conv then PReLU, on every forward tile that writes an output: 16 channels (8 in,
/// not folded; 20 out: a second, part-filled group), 8 (7 out), 4 (3 out, 5x5 taps) and its `_rows3` form (3x3,
/// row stride 1), and the direct kernels of few input channels (`conv_direct_forward` and
/// `_k5s2`), and transposed convs, whose forward runs those tiles per output phase. Slopes
/// include 0, negative and > 1 values, so a slope read for the wrong channel
/// or not applied shows; where the texture kernels do not run the conv, `fuses_prelu` is false
/// and `forward_prelu` an error.
#[test]
fn texture_forward_with_fused_prelu() {
    // What the texture kernels need, not `fuses_prelu` itself (a broken one would skip the test).
    if !(gpu().has_subgroups_of_8() && gpu().reads_rgba32f_storage()) {
        eprintln!("skipped: this adapter does not run the texture kernels");
        return;
    }
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { ci, co, input, kernel: ConvKernel::Texture, ..c };
    let cases = [
        with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 8, 20, [3, 9, 10]),
        with(conv2d([3, 3], [2, 1], Padding::Same), 8, 7, [1, 13, 5]),
        with(conv2d([5, 5], [1, 1], Padding::Same), 8, 3, [1, 6, 9]),
        with(conv2d([3, 3], [1, 1], Padding::Same), 16, 3, [1, 11, 5]),
        // 4 columns a lane (`conv_fast_forward_tex_w4`): 20 channels, two row blocks, 28 columns.
        with(conv2d([3, 3], [1, 1], Padding::Same), 8, 20, [1, 6, 28]),
        with(conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 1, 9, [5, 19, 11]),
        with(conv3d([3, 3, 3], [2, 1, 1], Padding::Same), 1, 3, [4, 5, 9]),
        // Transposed (one stride-1 conv per output phase, each applying the slopes): the
        // decoder's 4x4 stride 2 to 20 and to 7 channels, and a 3D one.
        with(transposed2d([4, 4], [2, 2], Padding::Same, None), 16, 20, [1, 5, 6]),
        with(transposed2d([4, 4], [2, 2], Padding::Same, None), 8, 7, [1, 6, 4]),
        with(transposed3d([3, 2, 3], [1, 2, 2], explicit([1, 0, 2], [0, 1, 1]), None), 5, 6, [3, 4, 5]),
    ];
    for (k, c) in cases.into_iter().enumerate() {
        let g = geom(&c);
        let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(&c), shape(c.d2, c.n, c.co, g.output));
        let fuses = match c.op {
            Op::Conv(op) => op.fuses_prelu(c.kernel, gpu(), &xs, &ws),
            Op::Transposed(op) => op.fuses_prelu(c.kernel, gpu(), &xs, &ws, &ys),
        };
        assert!(fuses.unwrap(), "{c:?} should fuse");
        let mut rng = Rng(400 + k as u64);
        let x = f32_round(&rng.vec(xs.iter().product(), -1.0, 1.0));
        let w = f32_round(&rng.vec(ws.iter().product(), -1.0, 1.0));
        let b = f32_round(&rng.vec(c.co, -1.0, 1.0));
        let mut alpha = f32_round(&rng.vec(c.co, -0.5, 1.5));
        alpha[0] = 0.0;
        let (tx, tw, tb, ta, ty) = (upload(&xs, &x), upload(&ws, &w), upload(&[c.co], &b), upload(&[c.co], &alpha), zeros(&ys));
        run(|p| match c.op {
            Op::Conv(op) => op.forward_prelu(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &ta, &ty),
            Op::Transposed(op) => op.forward_prelu(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &ta, &ty),
        });
        let s = ys[2..].iter().product();
        let want = reference::activations::prelu(&reference(&c, &g, &x, &w, Some(&b)), &alpha, c.co, s);
        assert_close(&format!("{c:?} forward + prelu"), &download(&ty), &want, ATOL, RTOL);
        // The plain forward of the same conv is unchanged by the slopes' binding.
        let y = zeros(&ys);
        run(|p| match c.op {
            Op::Conv(op) => op.forward(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &y),
            Op::Transposed(op) => op.forward(c.kernel, gpu(), p, &tx, &tw, Some(&tb), &y),
        });
        assert_close(&format!("{c:?} forward"), &download(&y), &reference(&c, &g, &x, &w, Some(&b)), ATOL, RTOL);
    }
    // The reference kernels apply no PReLU: refused with a clear error, not a wrong result.
    let op = conv::Conv::conv2d([3, 3], [1, 1], Padding::Same);
    let (x, w, a, y) = (zeros(&[1, 4, 5, 5]), zeros(&[4, 4, 3, 3]), zeros(&[4]), zeros(&[1, 4, 5, 5]));
    assert!(!op.fuses_prelu(ConvKernel::Reference, gpu(), x.shape(), w.shape()).unwrap());
    let err = gpu().run(|p| op.forward_prelu(ConvKernel::Reference, gpu(), p, &x, &w, None, &a, &y)).unwrap_err();
    assert!(err.to_string().contains("fuses_prelu"), "{err}");
}
