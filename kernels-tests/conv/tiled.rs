//! The tiled conv kernels (`ConvKernel::Buffers` and `ConvKernel::Texture`, src/ops/conv_fast.rs)
//! against the reference kernels and the f64 references of `conv.rs`, whose cases, helpers and
//! tolerances they share: every layer form again per family, the texture family's special tiles
//! (direct first-layer kernels, narrow heads, packing through uniform windows), random shapes,
//! and both gradients in one call.

use super::*;

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
    // 32 input and 30 output channels: 8 quads of x for the forward and of dy for the input
    // gradient, which the 16-channel tile loops over inside its taps' loop.
    check_fast(Case { ci: 32, co: 30, input: [1, 4, 5], ..conv2d([3, 3], [1, 1], Padding::Same) }, 107);
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
/// `conv_direct_backward_weight`, its `_k5` form for 5 x 5 taps), which run the convs the
/// other families fold (few input channels), forced onto textures: 20 output channels (three groups of 8 over two of 16) at a width of 7 (the stage's scalar
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
    // 19 output columns at column stride 2: the `_k5` weight gradient's steps of 16 (a lane's two
    // positions ow and ow + 8, 16 input columns apart), the last step 3 wide.
    check(&with(conv2d([5, 5], [2, 2], Padding::Same), 1, 6, [1, 9, 37]), 113);
}

/// `conv_direct_backward_input_k5s2`, the first layer's input gradient (1 input channel, 5^3
/// at stride 2) with every phase in one dispatch, forced onto textures: pads of both parities
/// on every axis (a tile's first row meets its dy rows through taps 4 + s + r - 2m, s = 0 or
/// 1; a lane's two columns start at x + pw even), tiles of 16 dx rows part-filled (13 and 11
/// rows: the second half of 8 in part; 27: a second tile of 11; 20: a second tile whose second
/// half starts past the last row, one depth, batch 2), two
/// workgroups of 8 depths (10), two tiles of 16 columns for 16 (pw odd: the first tile's first
/// column is off the grid, the second holds the last), 6 and 7 dy channels (two quads, the
/// second part-filled); and a transposed conv to 1 channel, whose forward it is
/// too, with the bias and one dy quad of 3 channels.
#[test]
fn direct_backward_input_of_one_channel() {
    let with = |c: Case, ci: usize, co: usize, input: [usize; 3]| Case { ci, co, input, kernel: ConvKernel::Texture, ..c };
    check(&with(conv3d([5, 5, 5], [2, 2, 2], explicit([1, 0, 3], [2, 1, 0])), 1, 6, [7, 13, 16]), 110);
    check(&with(conv3d([5, 5, 5], [2, 2, 2], explicit([2, 1, 0], [0, 2, 3])), 1, 7, [10, 11, 13]), 111);
    check(&with(conv3d([5, 5, 5], [2, 2, 2], explicit([0, 1, 2], [1, 2, 2])), 1, 5, [4, 27, 9]), 114);
    // 20 rows, one depth, batch 2: the second tile's second half starts past the last row.
    check(&with(conv3d([5, 5, 5], [2, 2, 2], explicit([2, 1, 2], [2, 2, 2])), 1, 5, [1, 20, 9]), 115);
    check(&with(transposed3d([5, 5, 5], [2, 2, 2], explicit([1, 2, 1], [2, 1, 2]), None), 3, 1, [3, 5, 4]), 112);
}

/// The texture family's 4- and 8-channel tiles (`conv_fast_forward_tex4`, its `_rows3` form,
/// `..._tex8`, `..._backward_weight_tex4` and `_tex8`, their `_w3` forms) on heads with enough input channels not to fold
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
    // Column stride 2 and a width-2 kernel, where a lane's W taps share no x: one tap a lane
    // (`..._backward_weight_tex4`, `_tex8`); the 3x3 cases above take three (`_w3`), the last
    // at row stride 2 and explicit padding.
    check(&with(conv2d([3, 3], [1, 2], Padding::Same), 8, 3, [1, 5, 11]), 105);
    check(&with(conv2d([3, 2], [1, 1], Padding::Same), 12, 7, [1, 6, 9]), 106);
    check(&with(conv2d([3, 3], [2, 1], Padding::explicit_2d([0, 2], [1, 0])), 8, 4, [1, 7, 19]), 108);
}

/// The texture family's weight gradient with three W taps a lane past 8 output channels
/// (`conv_fast_backward_weight_tex8_w3` in groups of 8 output channels, 4 or more input
/// channel quads; fewer input channels than 16 fold 3x3 taps here): 16 -> 20 (a third group
/// part-filled, dy packed at 32 channels) in 3D, and 16 -> 9 (the second group one channel)
/// at row stride 2 with explicit padding (2 columns before), batch 2; 8 -> 12 (two quads)
/// takes one tap a lane (`..._tex`). Small grids: the finite differences run the f64 conv
/// 1000 times per tensor.
#[test]
fn texture_weight_gradients_of_three_w_taps_a_lane() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    check(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 16, 20, [2, 3, 9]), 130);
    check(&with(conv2d([3, 3], [2, 1], Padding::explicit_2d([0, 2], [1, 0])), 2, 16, 9, [1, 9, 13]), 131);
    check(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 8, 12, [2, 3, 9]), 132);
}

/// The narrow heads' weight gradient on x in place (`conv_direct_backward_weight_3x3` and
/// `_3x3x8`: a lane has a kernel depth's 3 x 3 taps of one channel; column stride 1, at most 8
/// output channels, rows of whole staging rows so x is copied into its stage), against finite differences: 16 -> 3 (a quad of dy with one
/// padding channel) with `Same` padding (strips start 3 columns early), 16 -> 5 (two dy quads)
/// with 2 columns before and none after (2 early), 12 -> 8 in 3D
/// (depth taps, channels not a multiple of 16) and 16 -> 2 unpadded (steps start on a texel),
/// batch 2 where 2D. Then on a second adapter settled to store its packings (so only a copy
/// splits the pass): the weight gradient of the first case splits its pass once on a CPU
/// adapter (x copied into the stage; the channel-quad tiles would pack it with stores), never
/// elsewhere.
#[test]
fn heads_weight_gradient_reads_x_in_its_stage() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    let head = with(conv2d([3, 3], [1, 1], Padding::Same), 2, 16, 3, [1, 5, 64]);
    check(&head, 140);
    check(&with(conv2d([3, 3], [1, 1], Padding::explicit_2d([1, 2], [0, 0])), 2, 16, 5, [1, 7, 64]), 141);
    check(&with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 12, 8, [2, 3, 64]), 142);
    check(&with(conv2d([3, 3], [1, 1], Padding::explicit_2d([0, 0], [0, 0])), 2, 16, 2, [1, 4, 64]), 143);
    let (splits, cpu) = splits_where_packings_copy_from(&head, usize::MAX, &|op, gpu, p, x, dw, dy| op.backward_weight(head.kernel, gpu, p, x, dy, dw));
    assert_eq!(splits, u64::from(cpu), "splits of the head's weight gradient");
}

/// A call on a conv: its op, the adapter, the pass and tensors of its input, weight and output shapes.
type OnConv<'a> = dyn Fn(&Conv, &rendernet::Gpu, &mut wgpu::ComputePass<'_>, &Tensor, &Tensor, &Tensor) -> rendernet::Result<()> + 'a;
/// The pass splits of one call of `f` (conv `c`'s op, the adapter, the pass, and zero tensors
/// of `c`'s input, weight and output shapes) on a second adapter settled to copy in the
/// packings of at least `min_texels` texels and store the others, where only a copy into a
/// texture splits a pass; and whether that adapter is a CPU.
fn splits_where_packings_copy_from(c: &Case, min_texels: usize, f: &OnConv) -> (u64, bool) {
    let stores = rendernet::Gpu::new().expect("a second adapter");
    assert!(stores.settle_pack_copies(min_texels));
    let Op::Conv(op) = c.op else { panic!("{c:?} is not a conv") };
    let g = geom(c);
    let zeros = |s: &[usize]| Tensor::zeros(&stores, s).unwrap();
    let (x, w, y) = (zeros(&shape(c.d2, c.n, c.ci, g.input)), zeros(&w_shape(c)), zeros(&shape(c.d2, c.n, c.co, g.output)));
    let before = stores.pass_splits();
    stores.run(|p| f(&op, &stores, p, &x, &w, &y)).unwrap();
    (stores.pass_splits() - before, stores.info.device_type == wgpu::DeviceType::Cpu)
}

/// The narrow 3x3 heads' forward on the unpacked input (`conv_nchw_forward3x3`, forced by
/// `ConvKernel::Nchw`; the backward passes run the texture family): heights past one block of
/// 8 rows and short of it (9, 17, 7, 3, 10), one vec4 column (width 4) and several (8, 12,
/// 20, 16), 1 to 8 output channels (5 and 8: a second group of 4, part-filled and full), 1, 5,
/// 7, 16 and 64 input channels (64 fills the weight block), batch 2 with a bias. Then, with no
/// bias: a 3x3 stride-1 transposed conv from 2 to 7 channels, whose input gradient is a
/// forward conv of 7 to 2 channels the kernel computes (width 8). Each conv case first asserts
/// that the kernel runs, so a narrower `fits` fails here instead of quietly testing the
/// texture family.
#[test]
fn unpacked_heads_forward() {
    for (ci, co, input, seed) in [(5, 3, [1, 7, 12], 120), (16, 4, [1, 9, 8], 121), (1, 1, [1, 17, 4], 122), (64, 2, [1, 3, 20], 123), (16, 5, [1, 10, 16], 124), (7, 8, [1, 9, 12], 125)] {
        let c = Case { ci, co, input, kernel: ConvKernel::Nchw, ..conv2d([3, 3], [1, 1], Padding::Same) };
        let Op::Conv(op) = c.op else { unreachable!() };
        let unpacked = op.forward_reads_unpacked(c.kernel, gpu(), &shape(true, c.n, ci, input), &w_shape(&c)).unwrap();
        assert!(unpacked, "{c:?}: the unpacked kernel does not run");
        check(&c, seed);
    }
    check(&Case { ci: 2, co: 7, input: [1, 5, 8], kernel: ConvKernel::Nchw, ..transposed2d([3, 3], [1, 1], Padding::Same, None) }, 126);
}

/// The unpacked heads' forward on x copied into the direct kernels' stage texture
/// (`conv_nchw_forward3x3_stage`: rows of whole staging rows, width 64): 16 -> 3 over 9 rows
/// (a part-filled block of 8), 5 -> 8 (two groups of 4, a part-filled input quad) over 10, batch
/// 2 with a bias, against the f64 reference and finite differences. Then, on a second adapter
/// settled to store its packings, the 16 -> 3 forward splits its pass once on a CPU adapter (x
/// copied in; the buffer kernel reads x where it lies) and never elsewhere.
#[test]
fn unpacked_heads_forward_reads_x_in_its_stage() {
    let head = Case { ci: 16, co: 3, input: [1, 9, 64], kernel: ConvKernel::Nchw, ..conv2d([3, 3], [1, 1], Padding::Same) };
    check(&head, 150);
    check(&Case { ci: 5, co: 8, input: [1, 10, 64], ..head }, 151);
    let (splits, cpu) = splits_where_packings_copy_from(&head, usize::MAX, &|op, gpu, p, x, w, y| op.forward(head.kernel, gpu, p, x, w, None, y));
    assert_eq!(splits, u64::from(cpu), "splits of the head's forward");
}

/// Only packings of at least the settled size are copied in (each copy splits the pass, at a
/// cost that does not shrink with the texture): conv3d 32->32 3^3 on 1x8x8x16 packs its
/// weights into 32 x 216 = 6912 texels (through windows: 108 KiB) and x into 16 x 8 x 64 = 8192.
/// Settled at 0, 6913, 8192 and 8193 texels, a CPU adapter splits its forward pass 2, 1, 1, 0 times.
#[test]
fn only_packings_of_the_settled_size_are_copied_in() {
    let c = Case { n: 1, ci: 32, co: 32, input: [8, 8, 16], kernel: ConvKernel::Texture, ..conv3d([3, 3, 3], [1, 1, 1], Padding::Same) };
    for (min_texels, copies) in [(0, 2), (6913, 1), (8192, 1), (8193, 0)] {
        let (splits, cpu) = splits_where_packings_copy_from(&c, min_texels, &|op, gpu, p, x, w, y| op.forward(c.kernel, gpu, p, x, w, None, y));
        assert_eq!(splits, if cpu && copies_on_this_adapter() { copies } else { 0 }, "splits with copies from {min_texels} texels");
    }
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

/// The texture family's packings on a CPU adapter write their texels into a staging buffer and
/// copy it into the texture, splitting the pass (src/gpu/passes.rs); in a pass they cannot
/// split (one a caller began on its own encoder) they write the texture with texture stores.
/// Both must give the same bits in all three passes, for every packing: x or dy of a width not
/// a multiple of 4 (`conv_fast_pack_tex_buf`), of whole vec4s (`_w4_buf`), through uniform
/// windows (`_window_buf`, planes of 2048 vec4s); the first layer's stage of a width not a
/// multiple of 4, of whole vec4s, of 64 (x copied in as it lies: no dispatch) and through
/// windows (26384 vec4s); the weights, through windows in the second case. The split count shows
/// the copies ran (on a CPU adapter; elsewhere neither path splits).
#[test]
fn packings_copied_in_equal_texture_stores() {
    let with = |c: Case, n: usize, ci: usize, co: usize, input: [usize; 3]| Case { n, ci, co, input, kernel: ConvKernel::Texture, ..c };
    let first = conv3d([5, 5, 5], [2, 2, 2], Padding::Same);
    // The weights of the second case a view into a larger buffer, as in the flat parameter
    // buffer: only there do they fit the windows (see weight_packing_through_uniform_windows).
    let cases = [
        (with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 1, 5, 6, [3, 5, 7]), None),
        (with(conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 2, 8, 17, [4, 3, 8]), Some(1032)),
        (with(conv2d([1, 1], [1, 1], Padding::Same), 2, 5, 5, [1, 64, 128]), None),
        (with(first, 1, 1, 8, [5, 6, 10]), None),
        (with(first, 2, 1, 8, [3, 5, 12]), None),
        (with(first, 1, 1, 8, [3, 4, 64]), None),
        (with(first, 2, 1, 8, [17, 97, 32]), None),
    ];
    let cpu = copies_on_this_adapter();
    for (seed, (c, w_at)) in (340u64..).zip(cases) {
        let before = gpu().pass_splits();
        let copied = passes_on(&c, c.kernel, seed, w_at, true);
        let splits = gpu().pass_splits() - before;
        let stored = passes_on(&c, c.kernel, seed, w_at, false);
        assert_eq!(gpu().pass_splits() - before, splits, "{c:?}: a pass the ops cannot split was split");
        assert_eq!(splits > 0, cpu, "{c:?}: {splits} splits");
        for (k, what) in ["forward", "dx", "dw"].iter().enumerate() {
            assert!(copied[k] == stored[k], "{c:?} {what}: copied-in packings differ from texture stores");
        }
    }
}

/// The first layer's stage of a grid whose rows are whole staging rows (width 64) is x copied
/// in as it lies, with no dispatch, on a CPU adapter even where the packings store their texels
/// (`RENDERNET_PACK_COPIES=store`, or a calibration that found copies no faster): there the
/// copy replaces a dispatch, its loads and its stores. A second adapter settled to store runs
/// the forward and the weight gradient, the two passes that stage x: one split each on a CPU
/// adapter (none elsewhere), and the same bits as the shared adapter, which copies.
#[test]
fn a_first_layer_grid_of_whole_rows_is_copied_in_where_packings_store() {
    let c = Case { n: 1, ci: 1, co: 8, input: [3, 4, 64], kernel: ConvKernel::Texture, ..conv3d([5, 5, 5], [2, 2, 2], Padding::Same) };
    let want = passes(&c, c.kernel, 360);
    let stores = rendernet::Gpu::new().expect("a second adapter");
    assert!(stores.settle_pack_copies(usize::MAX));
    let Op::Conv(op) = c.op else { unreachable!() };
    let g = geom(&c);
    let (xs, ws, ys) = (shape(c.d2, c.n, c.ci, g.input), w_shape(&c), shape(c.d2, c.n, c.co, g.output));
    let put = |s: &[usize], v: &[f64]| Tensor::from_slice(&stores, s, &v.iter().map(|&x| x as f32).collect::<Vec<_>>()).unwrap();
    // passes()'s draws, in its order.
    let mut rng = Rng(360);
    let numel = |s: &[usize]| s.iter().product::<usize>();
    let (x, w) = (rng.vec(numel(&xs), -1.0, 1.0), rng.vec(numel(&ws), -1.0, 1.0));
    let (b, r) = (rng.vec(c.co, -1.0, 1.0), rng.vec(numel(&ys), -1.0, 1.0));
    let (tx, tw, tb, tr) = (put(&xs, &x), put(&ws, &w), put(&[c.co], &b), put(&ys, &r));
    let (ty, tdw) = (Tensor::zeros(&stores, &ys).unwrap(), Tensor::zeros(&stores, &ws).unwrap());
    let before = stores.pass_splits();
    stores.run(|p| op.forward(c.kernel, &stores, p, &tx, &tw, Some(&tb), &ty)).unwrap();
    stores.run(|p| op.backward_weight(c.kernel, &stores, p, &tx, &tr, &tdw)).unwrap();
    let splits = stores.pass_splits() - before;
    assert_eq!(splits, if copies_on_this_adapter() { 2 } else { 0 }, "{splits} splits");
    let got = |t: &Tensor| t.to_vec(&stores).unwrap().iter().map(|&v| v as f64).collect::<Vec<_>>();
    assert!(got(&ty) == want[0], "forward differs from the shared adapter's");
    assert!(got(&tdw) == want[2], "weight gradient differs from the shared adapter's");
}

/// [`passes`] with the weights, where `w_at` says so, a view at that value offset of a buffer
/// 16384 values longer than they need.
fn passes_with(c: &Case, kernel: ConvKernel, seed: u64, w_at: Option<usize>) -> [Vec<f64>; 3] {
    passes_on(c, kernel, seed, w_at, true)
}

/// [`passes_with`], in a pass the ops may split (`run`) or may not (`run_unsplit`).
fn passes_on(c: &Case, kernel: ConvKernel, seed: u64, w_at: Option<usize>, split: bool) -> [Vec<f64>; 3] {
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
    let record = |p: &mut wgpu::ComputePass<'_>| match c.op {
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
    };
    if split { run(record) } else { run_unsplit(record) }
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

/// `Conv::backward` (both gradients in one call) equals `backward_input` then
/// `backward_weight` exactly on every kernel family, and on textures packs dy once where the
/// two packings agree (16 or at most 8 output channels: one dispatch fewer; 5 and 8 pad dy
/// to 8 channels for both) but not where they differ (20: dy padded to 20 channels for dx,
/// 32 for dw).
#[test]
fn backward_in_one_call_equals_the_two_passes_and_packs_dy_once() {
    let textures = gpu().has_subgroups_of_8() && gpu().reads_rgba32f_storage();
    for (k, (c, co)) in [
        (conv3d([3, 3, 3], [1, 1, 1], Padding::Same), 16),
        (conv2d([3, 3], [1, 1], Padding::Same), 3),
        (conv3d([3, 3, 3], [2, 1, 2], Padding::Same), 16),
        (conv3d([5, 5, 5], [2, 2, 2], Padding::Same), 8),
        (conv2d([3, 3], [1, 1], Padding::Same), 5),
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
            let shared = textures && kernel == ConvKernel::Texture && (co == 16 || co <= 8);
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
