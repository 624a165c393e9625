//! The gradient guard: NaN and Inf are flagged wherever they sit (odd sizes, last element),
//! clean tensors are not, the summary flag ORs the slots, and a guarded Adam step leaves
//! parameters, moments and all untouched when the summary is set.

mod common;
use common::*;
use rendernet::ops::{adam::Adam, finite};

#[test]
fn flags_nan_and_inf_and_nothing_else() {
    // 131: not a multiple of the 64-wide workgroup (the scalar entry point); 260: four values
    // a load (the vec4 one), its last quad in a second round of the workgroup's loop.
    for n in [131, 260] {
        flags_nan_and_inf_in(n);
    }
}

fn flags_nan_and_inf_in(n: usize) {
    let mut rng = Rng(9);
    let clean: Vec<f32> = rng.vec(n, -1e30, 1e30).iter().map(|&v| v as f32).collect();
    let mut with_nan = clean.clone();
    with_nan[n - 1] = f32::NAN;
    let mut with_inf = clean.clone();
    with_inf[65] = f32::NEG_INFINITY;
    let g = gpu();
    let ts: Vec<_> = [&clean, &with_nan, &with_inf].iter().map(|v| rendernet::Tensor::from_slice(g, &[n], v).unwrap()).collect();
    let flags = zeros(&[5]);
    run(|p| {
        for (k, t) in ts.iter().enumerate() {
            finite::check(g, p, t, &flags, k + 1)?;
        }
        finite::any(g, p, &flags, 3)
    });
    assert_eq!(download(&flags), [1.0, 0.0, 1.0, 1.0, 0.0]);
    run(|p| {
        finite::check(g, p, &ts[0], &flags, 2)?;
        finite::check(g, p, &ts[0], &flags, 3)?;
        finite::any(g, p, &flags, 3)
    });
    assert_eq!(download(&flags), [0.0, 0.0, 0.0, 0.0, 0.0], "a clean step clears the flags");
    // The summary sees the first slot alone and the last slot alone.
    for bad in [1, 3] {
        run(|p| {
            for k in 1..=3 {
                finite::check(g, p, if k == bad { &ts[1] } else { &ts[0] }, &flags, k)?;
            }
            finite::any(g, p, &flags, 3)
        });
        let mut want = [0.0; 5];
        (want[0], want[bad]) = (1.0, 1.0);
        assert_eq!(download(&flags), want, "only slot {bad} is set");
    }
    assert!(gpu().run(|p| finite::check(g, p, &ts[0], &flags, 0)).is_err(), "slot 0 is the summary");
}

#[test]
fn guarded_adam_skips_a_poisoned_step() {
    // 7 values run the scalar entry point, 8 the vec4 one; each reads the guard.
    for n in [7, 8] {
        let (param, grad) = (upload(&[n], &vec![0.5; n]), upload(&[n], &vec![0.25; n]));
        let (m, v) = (zeros(&[n]), zeros(&[n]));
        let guard = upload(&[1], &[1.0]);
        let adam = Adam::new(0.1);
        run(|p| adam.step_guarded(gpu(), p, 1, &param, &grad, &m, &v, Some(&guard)));
        assert_eq!(download(&param), vec![0.5; n], "n {n}, set guard: parameters untouched");
        assert_eq!(download(&m), vec![0.0; n], "n {n}, set guard: moments untouched");
        guard.write(gpu(), &[0.0]).unwrap();
        run(|p| adam.step_guarded(gpu(), p, 1, &param, &grad, &m, &v, Some(&guard)));
        // The first Adam step moves every parameter by exactly lr (bias-corrected m / sqrt(v) = 1).
        assert_close(&format!("n {n}, clear guard: a normal step"), &download(&param), &vec![0.4; n], 1e-6, 1e-5);
    }
}

#[test]
fn chunked_check_flags_exactly_the_chunks_holding_nan_or_inf() {
    // 1004 values = 251 quads in 7 chunks of 36 quads (the last holds 35): an Inf in the
    // first quad of chunk 3, a NaN in the very last value (chunk 6); chunk 2 ends one quad
    // before the Inf, so an off-by-one in the chunk bounds flags it too.
    let n = 1004;
    let mut v: Vec<f32> = Rng(5).vec(n, -1e30, 1e30).iter().map(|&x| x as f32).collect();
    v[4 * 36 * 3 + 2] = f32::INFINITY;
    v[n - 1] = f32::NAN;
    let g = gpu();
    let x = rendernet::Tensor::from_slice(g, &[n], &v).unwrap();
    let flags = zeros(&[9]);
    let chunks = g.run(|p| {
        let c = finite::check_chunks(g, p, &x, &flags, 7)?;
        finite::any(g, p, &flags, c)?;
        Ok(c)
    }).unwrap();
    assert_eq!(chunks, 7);
    assert_eq!(download(&flags), [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0]);
    let odd = zeros(&[6]);
    let err = g.run(|p| finite::check_chunks(g, p, &odd, &flags, 2)).unwrap_err().to_string();
    assert!(err.contains("multiple of 4"), "{err}");
    let err = g.run(|p| finite::check_chunks(g, p, &x, &flags, 9)).unwrap_err().to_string();
    assert!(err.contains("chunks"), "{err}");
}
