//! The texture family's weight-gradient tile of 16 output channels a lane
//! (`conv_fast_backward_weight_tex16_w3`), against the reference kernels of `conv.rs`, whose
//! cases, helpers and tolerances it shares.

use super::*;

/// `conv_fast_backward_weight_tex16_w3` runs where its tiles walk 64 steps of 8 columns or more
/// (`conv_fast_weight::tex_tiling`: on a 2-thread CPU adapter, which CI is, these shapes
/// qualify; its unit test `wide_tiles_where_they_walk_64_steps` holds for them): grids too
/// large for finite differences of the f64 conv (1000 runs of it per tensor), so the weight
/// gradient is checked against the reference kernel's (`ConvKernel::Reference`, one weight a
/// lane, itself checked against finite differences above), the other outputs as everywhere.
/// 16 -> 20 in 3D on 4 x 16 x 32 (a second group of 16 output channels, 4 of them real), and
/// 16 -> 12 in 2D, batch 2, on 64 x 72 (rows of 9 steps, the last one column wide).
#[test]
fn texture_weight_gradient_of_16_output_channels_a_lane() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    check_weight_gradient(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 16, 20, [4, 16, 32]), 170);
    check_weight_gradient(&with(conv2d([3, 3], [1, 1], Padding::Same), 2, 16, 12, [1, 64, 72]), 171);
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
    // Sums of 2048-9216 products of values in [-1, 1] (|dw| up to ~100), in f32 in both kernels
    // in different orders: the reference conv tests' tolerances, relative.
    assert_close(&format!("{c:?} dw"), &dw(c.kernel), &want, ATOL, RTOL);
    assert!(want.iter().any(|v| v.abs() > 1.0), "{c:?}: a gradient of zeros tests nothing");
}
