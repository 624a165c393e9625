//! Adam against an f64 reference over several steps, parameter and both moments. There is
//! no finite-difference test: an optimiser step has no gradient of its own.

mod common;
mod reference;
use common::*;
use reference::adam::{Hyper, step};
use rendernet::ops::adam::Adam;

/// Six steps of `adam` on a fresh state of `shape`, checking parameter, m and v after each.
fn six_steps(adam: Adam, seed: u64, shape: [usize; 4]) {
    let n: usize = shape.iter().product();
    let mut rng = Rng(seed);
    let h = Hyper { lr: adam.lr as f64, beta1: adam.beta1 as f64, beta2: adam.beta2 as f64, eps: adam.eps as f64 };
    let mut param = f32_round(&rng.vec(n, -1.0, 1.0));
    let (mut m, mut v) = (vec![0.0; n], vec![0.0; n]);
    let (tp, tg, tm, tv) = (upload(&shape, &param), zeros(&shape), zeros(&shape), zeros(&shape));
    for t in 1..=6u32 {
        // A fresh gradient each step, of varying scale so v's history matters.
        let g = f32_round(&rng.vec(n, -1.0, 1.0).iter().map(|x| x * t as f64).collect::<Vec<_>>());
        tg.write(gpu(), &g.iter().map(|&x| x as f32).collect::<Vec<_>>()).unwrap();
        run(|p| adam.step(gpu(), p, t, &tp, &tg, &tm, &tv));
        step(h, t, &mut param, &g, &mut m, &mut v);
        // The f32 state follows the f64 one to a few ulps per step; an update is ~lr = 1e-2,
        // so a wrong bias correction or beta shows at >= 1e-4 while the f32 drift over six
        // steps stays < 1e-6.
        assert_close(&format!("param after step {t}"), &download(&tp), &param, 2e-6, 1e-5);
        assert_close(&format!("m after step {t}"), &download(&tm), &m, 1e-6, 1e-5);
        assert_close(&format!("v after step {t}"), &download(&tv), &v, 1e-6, 1e-5);
    }
}

#[test]
fn several_steps_match_the_reference() {
    // Odd, non-power-of-two parameter shape (a conv weight), more than one workgroup: the
    // scalar entry point.
    six_steps(Adam { lr: 0.01, ..Adam::new(0.0) }, 31, [5, 3, 3, 7]);
}

#[test]
fn several_steps_of_four_parameters_per_invocation_match_the_reference() {
    // 504 values, a multiple of 4 (the vec4 entry point), 126 invocations: two workgroups,
    // the second partly past the end.
    six_steps(Adam { lr: 0.01, ..Adam::new(0.0) }, 33, [8, 3, 3, 7]);
}

#[test]
fn several_steps_with_other_betas_match_the_reference() {
    // The original's beta1 = 0.5 makes beta1 and 1 - beta1 equal, which would hide a swap.
    six_steps(Adam { lr: 0.01, beta1: 0.8, beta2: 0.95, eps: 1e-8 }, 32, [5, 3, 3, 7]);
    six_steps(Adam { lr: 0.01, beta1: 0.8, beta2: 0.95, eps: 1e-8 }, 34, [4, 1, 1, 3]);
}

#[test]
fn the_first_step_moves_each_parameter_by_lr() {
    // With bias correction, step 1 is param -= lr * g / (|g| + eps): a move of lr against the
    // gradient's sign whatever its scale (the tell-tale of correct bias correction).
    let adam = Adam::new(1e-3);
    let g = [2.0, -0.5, 1e-2];
    let (tp, tg, tm, tv) = (upload(&[3], &[0.0; 3]), upload(&[3], &g), zeros(&[3]), zeros(&[3]));
    run(|p| adam.step(gpu(), p, 1, &tp, &tg, &tm, &tv));
    assert_close("first step", &download(&tp), &[-1e-3, 1e-3, -1e-3], 1e-8, 1e-5);
}

#[test]
fn bad_arguments_are_errors_not_panics() {
    let (a, b) = (zeros(&[2, 3]), zeros(&[3, 2]));
    let adam = Adam::new(1e-3);
    for (args, what) in [([&a, &b, &a, &a], "grad"), ([&a, &a, &b, &a], "m"), ([&a, &a, &a, &b], "v")] {
        let err = gpu().run(|p| adam.step(gpu(), p, 1, args[0], args[1], args[2], args[3])).unwrap_err().to_string();
        assert!(err.contains("adam_step") && err.contains(what), "{err}");
    }
    let err = gpu().run(|p| adam.step(gpu(), p, 0, &a, &a, &a, &a)).unwrap_err().to_string();
    assert!(err.contains("1-based"), "{err}");
    let err = gpu().run(|p| Adam { beta2: 1.0, ..adam }.step(gpu(), p, 1, &a, &a, &a, &a)).unwrap_err().to_string();
    assert!(err.contains("beta2"), "{err}");
}
