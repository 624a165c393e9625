//! The texture family's weight-gradient tile of 16 output channels a lane
//! (`conv_fast_backward_weight_tex16_w3`), against the reference kernels of `conv.rs`, whose
//! cases, helpers and tolerances it shares.

use super::*;

/// `conv_fast_backward_weight_tex16_w3` runs where its tiles walk 64 steps of 8 columns or more
/// (`conv_fast_weight::tex_tiling`; its unit test `wide_tiles_where_they_walk_64_steps` holds
/// for these shapes): on grids too large for finite differences of the f64 conv (1000 runs of
/// it per tensor), so this checks the weight gradient alone, against the reference kernel's
/// (`ConvKernel::Reference`, one weight a lane, itself checked against finite differences
/// above). 16 -> 20 in 3D on 8 x 32 x 57 (a second group of 16 output channels, 4 of them
/// real; rows of 8 steps, the last one 1 column wide), which runs the kernel at up to 256
/// tiles, so on CPU adapters of up to 16 threads and on GPUs (128); and 16 -> 12 in 2D, batch 2,
/// on 64 x 73 (rows of 10 steps, the last one 1 column wide), which runs it at up to 32 tiles
/// (2-thread CPU adapters such as CI's; `_tex8_w3` elsewhere); 24 -> 12 on 96 x 64 at up to 64,
/// and 36 -> 20 in 3D on 8 x 12 x 64 at up to 256. All four leave 1-4 (tap row, channel quad)
/// pairs past their whole groups of 8 to `conv_fast_backward_weight_tex16_w3_halves`
/// (`conv_fast_weight::leftover_pairs`): 4, 4, 2 (lanes idle) and 1 (with 2 output channel
/// groups).
#[test]
fn texture_weight_gradient_of_16_output_channels_a_lane() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    check_weight_gradient(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 16, 20, [8, 32, 57]), 170);
    check_weight_gradient(&with(conv2d([3, 3], [1, 1], Padding::Same), 2, 16, 12, [1, 64, 73]), 171);
    // 24 input channels (6 quads): 18 (tap row, quad) pairs, 2 past the whole groups, so
    // `_tex16_w3_halves` has idle pairs and its lanes 4-7 must take lanes 0-3's pairs.
    check_weight_gradient(&with(conv2d([3, 3], [1, 1], Padding::Same), 2, 24, 12, [1, 96, 64]), 172);
    // 36 input channels (9 quads) in 3D: 81 pairs, 1 past the whole groups, with 2 output
    // channel groups, on up to 256 tiles (16-thread CPU adapters, GPUs).
    check_weight_gradient(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 36, 20, [8, 12, 64]), 173);
}

/// The weight gradient of `c`'s kernel against the reference kernel's, on random x and dy.
fn check_weight_gradient(c: &Case, seed: u64) {
    let mut rng = Rng(seed);
    let g = geom(c);
    let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(c), shape(c.d2, c.n, c.co, g.output));
    let numel = |s: &[usize]| s.iter().product::<usize>();
    let x = f32_round(&rng.vec(numel(&xs), -1.0, 1.0));
    let r = f32_round(&rng.vec(numel(&ys), -1.0, 1.0));
    let (tx, tr) = (upload(&xs, &x), upload(&ys, &r));
    let dw = |kernel: ConvKernel| {
        let t = zeros(&ws);
        run(|p| match c.op {
            Op::Conv(op) => op.backward_weight(kernel, gpu(), p, &tx, &tr, &t),
            Op::Transposed(op) => op.backward_weight(kernel, gpu(), p, &tx, &tr, &t),
        });
        download(&t)
    };
    let want = dw(ConvKernel::Reference);
    // Sums of up to 14592 products of values in [-1, 1], in f32 in both kernels in different
    // orders: a value that cancels to near zero keeps the rounding of the whole sum (1.7e-4 seen
    // where |dw| reaches 139), so the absolute tolerance is 2e-5 of the largest |dw|; a wrong
    // channel, tap or position is off by whole products (~0.1-1 and more).
    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert_close(&format!("{c:?} dw"), &dw(c.kernel), &want, 2e-5 * scale, RTOL);
    assert!(want.iter().any(|v| v.abs() > 1.0), "{c:?}: a gradient of zeros tests nothing");
}
