//! The resize-convolution projection kernel (`shaders/resize_conv.wgsl`): against an f64
//! reference built another way (Gram-Schmidt, not the crate's matrix inverse) on an odd
//! weight shape, and inside training steps, where it must keep a transposed conv's weight
//! in the subspace while an unconstrained run leaves it. It is an optimiser-side projection,
//! not a graph op, so it has no backward pass to check.
//!
//! Tolerance: each output sums 16 products of values ~1 in f32 (error ~1e-6), so 1e-5
//! absolute; a wrong projector entry or a missed tap moves outputs by ~1e-1.

mod common;
#[path = "reference/resize_conv.rs"]
mod reference;
use common::*;
use rendernet::graph::{Executor, Graph, Init, Op};
use rendernet::ops::conv::Padding;
use rendernet::ops::conv_transpose::ConvTranspose;
use rendernet::ops::{adam::Adam, loss::Loss, resize_conv};

#[test]
fn projects_every_kernel_like_the_reference() {
    let shape = [3, 5, 4, 4];
    let w = f32_round(&Rng(4).vec(3 * 5 * 16, -1.0, 1.0));
    let t = upload(&shape, &w);
    let proj = resize_conv::projector(gpu()).unwrap();
    run(|p| resize_conv::project(gpu(), p, &proj, &t));
    let want = reference::project(&w);
    assert_close("GPU projection", &download(&t), &want, 1e-5, 0.0);
    let mut cpu: Vec<f32> = w.iter().map(|&v| v as f32).collect();
    rendernet::graph::resize_conv::project(&mut cpu);
    assert_close("CPU projection", &cpu.iter().map(|&v| v as f64).collect::<Vec<_>>(), &want, 1e-5, 0.0);
    assert!(want.iter().zip(&w).any(|(a, b)| (a - b).abs() > 0.1), "random kernels must move");
    let bad = zeros(&[3, 5, 3, 3]);
    let err = rendernet::Gpu::run(gpu(), |p| resize_conv::project(gpu(), p, &proj, &bad)).unwrap_err().to_string();
    assert!(err.contains("[Cin, Cout, 4, 4]"), "{err}");
}

/// Two training steps of a 4x4 stride-2 transposed conv: with `keep_resize_conv` the weight
/// ends in the subspace (projection leaves it unchanged), without it Adam moves it out. The
/// step's loss comes back in its own submit and equals the kept loss value.
#[test]
fn training_keeps_marked_transposed_convs_resize_convolutions() {
    let mut g = Graph::new();
    let x = g.input("x", &[1, 3, 5, 4]).unwrap();
    let target = g.input("target", &[1, 2, 10, 8]).unwrap();
    let w = g.param("up.weight", &[3, 2, 4, 4], Init::XavierUpsample).unwrap();
    let b = g.param("up.bias", &[2], Init::Constant(0.0)).unwrap();
    let y = g.apply("up", Op::ConvTranspose(ConvTranspose::conv2d([4, 4], [2, 2], Padding::Same)), &[x, w, b]).unwrap();
    let loss = g.apply("loss", Op::Loss(Loss::Mse), &[y, target]).unwrap();
    let mut rng = Rng(8);
    let (xs, ts) = (rng.vec(60, -1.0, 1.0), rng.vec(160, 0.0, 1.0));
    let weights_after = |keep: bool| {
        let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
        ex.feed(gpu(), x, &xs.iter().map(|&v| v as f32).collect::<Vec<_>>()).unwrap();
        ex.feed(gpu(), target, &ts.iter().map(|&v| v as f32).collect::<Vec<_>>()).unwrap();
        if keep {
            ex.keep_resize_conv(gpu(), w).unwrap();
        }
        for _ in 0..2 {
            let s = ex.train_step(gpu(), loss, &Adam::new(0.05)).unwrap();
            assert_eq!(s.loss, Some(ex.read(gpu(), loss).unwrap()[0]), "{s:?}");
        }
        ex.read(gpu(), w).unwrap().iter().map(|&v| v as f64).collect::<Vec<_>>()
    };
    let kept = weights_after(true);
    assert_close("kept weight, projected again", &reference::project(&kept), &kept, 1e-6, 0.0);
    let free = weights_after(false);
    let off = reference::project(&free).iter().zip(&free).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(off > 1e-3, "unconstrained Adam should leave the subspace (max distance {off})");
    let mut ex = Executor::new(gpu(), g.clone(), 3).unwrap();
    assert!(ex.keep_resize_conv(gpu(), b).unwrap_err().to_string().contains("up.bias"));
}
