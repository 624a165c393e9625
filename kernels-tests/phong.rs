//! Phong shading against the f64 reference: forward, finite-difference gradients of all four
//! inputs (normal map through its decode and normalisation, albedo grey and colour, mask,
//! all six light values per batch item), closed-form cases that pin the conventions
//! (encoding, view direction, reflection sign) which finite differences cannot, degenerate
//! pixels (pow of 0, a zero normal) and shape errors.

mod common;
mod reference;
use common::*;
use reference::phong::{Coeffs, kinks, phong};
use rendernet::ops::phong::{Inputs, Phong};

const PH: Phong = Phong { ambient: 0.15, kd: 0.8, ks: 0.4, shininess: 4.5 };

fn coeffs(p: Phong) -> Coeffs {
    Coeffs { ambient: p.ambient as f64, kd: p.kd as f64, ks: p.ks as f64, shininess: p.shininess as f64 }
}

/// GPU results: image, then gradients of normal, albedo, mask, light.
struct Out {
    image: Vec<f64>,
    grads: [Vec<f64>; 4],
}

fn run_phong(ph: Phong, [n, c, h, w]: [usize; 4], x: [&[f64]; 4], r: &[f64]) -> Out {
    let shapes = [vec![n, 3, h, w], vec![n, c, h, w], vec![n, 1, h, w], vec![n, 6]];
    let t: Vec<_> = (0..4).map(|i| upload(&shapes[i], x[i])).collect();
    let g: Vec<_> = shapes.iter().map(|s| zeros(s)).collect();
    let (image, tr) = (zeros(&[n, 3, h, w]), upload(&[n, 3, h, w], r));
    let inputs = Inputs { normal: &t[0], albedo: &t[1], mask: &t[2], light: &t[3] };
    let grads = Inputs { normal: &g[0], albedo: &g[1], mask: &g[2], light: &g[3] };
    run(|p| {
        ph.forward(gpu(), p, &inputs, &image)?;
        ph.backward(gpu(), p, &inputs, &tr, &grads)
    });
    Out { image: download(&image), grads: [0, 1, 2, 3].map(|i| download(&g[i])) }
}

/// Random inputs with every pixel at least `MARGIN` away from the kinks of max(0, n.l) and
/// max(0, r.v) (redrawn otherwise), and |2v - 1| >= 0.3 so normalisation is well
/// conditioned. Returns the inputs and counts of pixels lit with / without a highlight
/// and unlit, so the test can insist that every branch is exercised.
fn inputs(rng: &mut Rng, [n, c, h, w]: [usize; 4]) -> ([Vec<f64>; 4], [usize; 3]) {
    const MARGIN: f64 = 1e-2;
    let hw = h * w;
    let dirs: [[f64; 3]; 3] = [[0.3, -0.4, 0.85], [-0.5, 0.2, 0.7], [0.1, 0.6, 0.5]];
    let cols = [[0.9, 0.7, 1.1], [1.2, 0.8, 0.6], [0.5, 1.0, 0.9]];
    let mut light = Vec::new();
    for b in 0..n {
        let d = dirs[b % 3];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        light.extend(d.iter().map(|x| x / len));
        light.extend(cols[b % 3]);
    }
    let light = f32_round(&light);
    let mut normal = vec![0.0; n * 3 * hw];
    let mut counts = [0; 3];
    for b in 0..n {
        for px in 0..hw {
            loop {
                // z biased towards the camera so highlights occur, yet some pixels face away.
                let v = f32_round(&[rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0), rng.uniform(0.3, 1.0)]);
                let u2: f64 = v.iter().map(|x| (2.0 * x - 1.0).powi(2)).sum();
                let (d, s) = kinks([v[0], v[1], v[2]], &light[b * 6..b * 6 + 3]);
                if u2 < 0.09 || d.abs() < MARGIN || s.abs() < MARGIN {
                    continue;
                }
                counts[if d <= 0.0 { 2 } else if s > 0.0 { 0 } else { 1 }] += 1;
                for i in 0..3 {
                    normal[(b * 3 + i) * hw + px] = v[i];
                }
                break;
            }
        }
    }
    let albedo = f32_round(&rng.vec(n * c * hw, 0.1, 1.0));
    let mask = f32_round(&rng.vec(n * hw, 0.0, 1.0));
    ([normal, albedo, mask, light], counts)
}

fn forward_and_fd(c: usize, seed: u64) {
    let dims = [2, c, 5, 7];
    let mut rng = Rng(seed);
    let (x, counts) = inputs(&mut rng, dims);
    assert!(counts.iter().all(|&k| k >= 3), "every shading branch needs pixels: {counts:?}");
    let r = f32_round(&rng.vec(2 * 3 * 35, -1.0, 1.0));
    let got = run_phong(PH, dims, [&x[0], &x[1], &x[2], &x[3]], &r);
    let k = coeffs(PH);
    let f = |x: &[Vec<f64>; 4]| phong(k, dims, &x[0], &x[1], &x[2], &x[3]);
    // Outputs are O(1) from ~30 f32 operations including pow (exp2/log2, a few ulps each).
    assert_close(&format!("phong forward C={c}"), &got.image, &f(&x), 1e-5, 1e-4);
    let names = ["normal", "albedo", "mask", "light"];
    for i in 0..4 {
        let want = fd_grad(&x[i], |xi| {
            let mut xs = x.clone();
            xs[i] = xi.to_vec();
            dot(&r, &f(&xs))
        });
        // Per-pixel gradients are O(1..10) (1/|u| <= 3.3, the highlight's derivative up to
        // shininess); the light's sum 35 pixels, so its f32 error grows ~sqrt(35) times.
        // 2e-4 absolute is >10x the expected error and far below any dropped term.
        assert_close(&format!("phong d{} C={c}", names[i]), &got.grads[i], &want, 2e-4, 1e-4);
    }
}

#[test]
fn grey_albedo_forward_and_gradients() {
    forward_and_fd(1, 11);
}

#[test]
fn colour_albedo_forward_and_gradients() {
    forward_and_fd(3, 12);
}

/// One pixel per case, [1, 3, 1, 1], flat normal `v` under light `l`; returns the image.
fn one_pixel(ph: Phong, v: [f64; 3], l: [f64; 3], col: [f64; 3], a: [f64; 3], m: f64) -> Out {
    let light = [l[0], l[1], l[2], col[0], col[1], col[2]];
    run_phong(ph, [1, 3, 1, 1], [&v, &a, &[m], &light], &[0.7, -0.3, 0.5])
}

#[test]
fn closed_form_cases_pin_the_conventions() {
    let (col, a, m) = ([0.9, 0.5, 0.25], [0.75, 0.5, 1.0], 0.5);
    // A normal facing the light, both along the view: n.l = 1 and r.v = 1, so
    // I = m col (A (ambient + kd) + ks). Encoded (0.5, 0.5, 1) decodes to (0, 0, 1) exactly.
    let got = one_pixel(PH, [0.5, 0.5, 1.0], [0.0, 0.0, 1.0], col, a, m).image;
    let k = coeffs(PH);
    let want: Vec<f64> = (0..3).map(|c| m * col[c] * (a[c] * (k.ambient + k.kd) + k.ks)).collect();
    assert_close("facing the light", &got, &want, 1e-6, 1e-6);
    // Light tilted by t towards +x over a normal facing the camera: n.l = cos t and
    // r = (-sin t, 0, cos t), so r.v = cos t as well. A flipped r or view would zero it.
    let t: f64 = 0.6;
    let l = [(t.sin() as f32) as f64, 0.0, (t.cos() as f32) as f64];
    let got = one_pixel(PH, [0.5, 0.5, 1.0], l, col, a, m).image;
    let ct = l[2];
    let want: Vec<f64> = (0..3).map(|c| m * col[c] * (a[c] * (k.ambient + k.kd * ct) + k.ks * ct.powf(k.shininess))).collect();
    assert_close("tilted light", &got, &want, 1e-6, 1e-5);
    // The normal map's x decodes to +x: a normal tilted towards +x, lit from +x, is brighter
    // than one tilted towards -x (a sign slip in the decode would swap them).
    let lx = [0.6, 0.0, 0.8];
    let right = one_pixel(PH, [0.8, 0.5, 0.9], lx, col, a, m).image;
    let left = one_pixel(PH, [0.2, 0.5, 0.9], lx, col, a, m).image;
    assert!(right[0] > left[0] + 0.1, "decode sign: {right:?} vs {left:?}");
}

#[test]
fn degenerate_pixels_give_zero_highlight_and_finite_gradients() {
    let (col, a, m) = ([0.9, 0.5, 0.25], [0.75, 0.5, 1.0], 0.5);
    for shininess in [0.0, 1.0, 4.5] {
        let ph = Phong { shininess, ..PH };
        // Light grazing a camera-facing normal: n.l = 0 and r.v = 0 exactly, so only the
        // ambient term is left and pow(0, shininess) and its derivative must give 0, not NaN.
        // Then a zero normal (encoded 0.5): n = 0 under the clamp, again n.l = 0.
        for v in [[0.5, 0.5, 1.0], [0.5, 0.5, 0.5]] {
            let got = one_pixel(ph, v, [1.0, 0.0, 0.0], col, a, m);
            let want: Vec<f64> = (0..3).map(|c| m * col[c] * a[c] * PH.ambient as f64).collect();
            assert_close(&format!("ambient only, shininess {shininess}, v {v:?}"), &got.image, &want, 1e-6, 1e-6);
            for g in &got.grads {
                assert!(g.iter().all(|x| x.is_finite()), "shininess {shininess}, v {v:?}: gradient {g:?}");
            }
            // At r.v = 0 the highlight contributes no gradient: the same as with no highlight.
            let plain = one_pixel(Phong { ks: 0.0, ..ph }, v, [1.0, 0.0, 0.0], col, a, m);
            for (g, want) in got.grads.iter().zip(&plain.grads) {
                assert_eq!(g, want, "shininess {shininess}, v {v:?}: the highlight moved a gradient");
            }
        }
    }
}

#[test]
fn bad_shapes_are_errors_not_panics() {
    let (nm, a1, a2, mk, l6) = (zeros(&[2, 3, 4, 5]), zeros(&[2, 1, 4, 5]), zeros(&[2, 2, 4, 5]), zeros(&[2, 1, 4, 5]), zeros(&[2, 6]));
    let (l5, img, bad_img, nm4) = (zeros(&[2, 5]), zeros(&[2, 3, 4, 5]), zeros(&[2, 3, 5, 4]), zeros(&[2, 4, 4, 5]));
    let ok = Inputs { normal: &nm, albedo: &a1, mask: &mk, light: &l6 };
    let cases = [
        (Inputs { albedo: &a2, ..ok }, &img, "albedo"),
        (Inputs { light: &l5, ..ok }, &img, "light"),
        (Inputs { normal: &nm4, ..ok }, &img, "normal"),
        (Inputs { mask: &a2, ..ok }, &img, "mask"),
        (ok, &bad_img, "image"),
    ];
    for (x, out, what) in cases {
        let err = gpu().run(|p| PH.forward(gpu(), p, &x, out)).unwrap_err().to_string();
        assert!(err.contains("phong_forward") && err.contains(what), "{err}");
    }
    // Gradients must match their inputs' shapes.
    let bad = Inputs { light: &l5, ..ok };
    let err = gpu().run(|p| PH.backward(gpu(), p, &ok, &img, &bad)).unwrap_err().to_string();
    assert!(err.contains("phong_backward") && err.contains("light gradient"), "{err}");
    let err = gpu().run(|p| Phong { shininess: -1.0, ..PH }.forward(gpu(), p, &ok, &img)).unwrap_err().to_string();
    assert!(err.contains("shininess"), "{err}");
}
