//! Inverse rendering: the gradient of the image loss with respect to camera azimuth,
//! elevation, log radius and light azimuth and elevation (chained on the host from the
//! network's pose and light gradients) against central finite differences of the same
//! loss, through the shipped network; and the command line.
//!
//! Tolerance: the loss is smooth only piecewise (trilinear resampling and PReLU have kinks),
//! so differences over 0.4 degree steps match the analytic gradient to ~10%, not to float
//! precision; 30% still catches a wrong sign, a missing degree-to-radian factor (57x) or a
//! swapped component.

use rendernet::Gpu;
use rendernet::invert::Inverter;
use rendernet::nn::render::TINY_PHONG_WEIGHTS;
use rendernet::nn::rendernet::Preset;
use rendernet::reference::{self, Light, Shader, View};
use rendernet::voxel;

#[test]
fn pose_and_light_gradients_match_finite_differences() {
    let gpu = Gpu::new().unwrap();
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    // At 32^3: the weights read 64^3 grids, and the finite differences below straddle fewer
    // of the trilinear resampling's kinks when the grid they upsample is smooth at that scale.
    let grid = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap().resample_to(32).unwrap();
    let (view, light) = (View { azimuth: 40.0, elevation: 75.0, radius: 3.6 }, Light { azimuth: 20.0, elevation: 70.0, ..Light::default() });
    let target = reference::RayMarcher::new(&gpu).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let inv = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", Light::default()).unwrap();
    // A start off the truth in every unknown, so every gradient component is far from zero.
    let base = [52.0, 95.0, 3.9f64.ln(), 45.0, 90.0];
    let h = [0.4, 0.4, 0.004, 0.4, 0.4];
    let mut points = vec![base];
    for j in 0..5 {
        for s in [1.0, -1.0] {
            let mut p = base;
            p[j] += s * h[j];
            points.push(p);
        }
    }
    let r = inv.gradient(&gpu, &grid, &target, &points).unwrap();
    let g = r[0].1;
    let fds: Vec<f64> = (0..5).map(|j| (r[1 + 2 * j].0 - r[2 + 2 * j].0) / (2.0 * h[j])).collect();
    for j in 0..5 {
        eprintln!("unknown {j}: analytic {:.3e}, finite difference {:.3e}", g[j], fds[j]);
    }
    for (j, &fd) in fds.iter().enumerate() {
        assert!(fd.abs() > 1e-6, "unknown {j}: the loss does not move ({fd:e}); the test would prove nothing");
        assert!((g[j] - fd).abs() <= 0.3 * fd.abs(), "unknown {j}: analytic {} vs finite difference {fd}", g[j]);
    }
}

#[test]
fn invert_cli_reports_a_pose_and_rejects_a_wrong_image_size() {
    let dir = std::env::temp_dir().join(format!("rendernet-invert-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let small = dir.join("small.png");
    image::RgbImage::new(64, 64).save(&small).unwrap();
    let out = dir.join("out.png");
    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    let o = run(&["invert", "--image", small.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("64x64") && err.contains("128x128"), "{err}");
    // A tiny search: 4 x 2 coarse starts, one refined for 3 steps.
    let o = run(&["invert", "--azimuths", "4", "--elevations", "2", "--starts", "1", "--steps", "3", "--json", "--out", out.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["azimuth", "elevation", "radius", "light_azimuth", "light_elevation", "mse", "pose_error_degrees", "light_error_degrees"] {
        assert!(j[key].as_f64().is_some_and(f64::is_finite), "{key} missing in {text}");
    }
    // 3 refinement steps and the light polish's 3 / 2 = 1, each curve with its start.
    assert_eq!(j["curve"].as_array().map(Vec::len), Some(4 + 2), "{text}");
    let png = image::open(&out).unwrap();
    assert_eq!((png.width(), png.height()), (256, 128));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `invert --prior`: shape, camera and light together, with the shipped prior (the flag
/// without a value) and a tiny search; the grid file, the three-panel picture and the
/// JSON's errors and IoU come out, and an output format it cannot write is refused before
/// any work.
#[test]
fn invert_cli_with_a_prior_writes_the_recovered_grid() {
    use rendernet::graph::Executor;
    use rendernet::nn::prior::{PriorPreset, ShapePrior};
    let gpu = Gpu::new().unwrap();
    let dir = std::env::temp_dir().join(format!("rendernet-invert-prior-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let prior = dir.join("prior.safetensors");
    Executor::new(&gpu, ShapePrior::build(&PriorPreset::small(), 1, false).unwrap().graph, 2).unwrap().save_params(&gpu, &prior).unwrap();
    let (out, vox) = (dir.join("out.png"), dir.join("shape.binvox"));
    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    let p = prior.to_str().unwrap();
    let o = run(&["invert", "--prior", p, "--out-voxels", dir.join("shape.obj").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("shape.obj") && err.contains(".binvox"), "{err}");
    let args = ["invert", "--prior", "--shape", "chair", "--resolution", "32", "--azimuths", "4", "--elevations", "2", "--starts", "1", "--steps", "2",
        "--rounds", "1", "--shape-steps", "2", "--json", "--out", out.to_str().unwrap(), "--out-voxels", vox.to_str().unwrap()];
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["azimuth", "light_azimuth", "pose_error_degrees", "light_error_degrees", "voxel_iou"] {
        assert!(j[key].as_f64().is_some_and(f64::is_finite), "{key} missing in {text}");
    }
    assert_eq!(j["shape_loss_curve"].as_array().map(Vec::len), Some(3), "{text}");
    assert_eq!(rendernet::voxel::binvox::Binvox::read(&vox).unwrap().grid.dims(), [32; 3]);
    let png = image::open(&out).unwrap();
    assert_eq!((png.width(), png.height()), (384, 128));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shape recovery's graph: the shape prior's decoder in front of RenderNet. The gradient of
/// the image loss with respect to the latent code (through the decoder, the resampling and
/// the whole network) against central finite differences of the same loss, on three code
/// entries; the decoder is an untrained (seeded) one, RenderNet the shipped weights, both
/// loaded into one executor from their own files. Tolerance 10%: the code moves the grid
/// smoothly (sigmoid decoder), so the differences matched to 0.1% and 2% when written; a
/// gradient that skipped the decoder or the resampling would be off by orders of magnitude.
#[test]
fn shape_code_gradient_matches_finite_differences() {
    use rendernet::graph::{Executor, Op};
    use rendernet::nn::camera::{light_values, pose_for_view};
    use rendernet::nn::prior::{PriorPreset, ShapePrior, decoder_with_renderer};
    use rendernet::nn::rendernet::{Head, phong_of};
    use rendernet::ops::loss::Loss;
    let gpu = Gpu::new().unwrap();
    let (pp, rp) = (PriorPreset::small(), Preset::tiny());
    let prior = Executor::new(&gpu, ShapePrior::build(&pp, 1, false).unwrap().graph, 7).unwrap();
    let file = std::env::temp_dir().join(format!("rendernet-prior-test-{}.safetensors", std::process::id()));
    prior.save_params(&gpu, &file).unwrap();
    let prior_bytes = std::fs::read(&file).unwrap();
    let _ = std::fs::remove_file(&file);
    let (mut net, code) = decoder_with_renderer(&pp, &rp, Head::Phong(phong_of(&Light::default())), 1, [32, 32]).unwrap();
    let [h, w] = [net.graph.info(net.image).shape[2], net.graph.info(net.image).shape[3]];
    let target = net.graph.input("target", &[1, 3, h, w]).unwrap();
    let loss = net.graph.apply("loss", Op::Loss(Loss::Mse), &[net.image, target]).unwrap();
    let mut ex = Executor::new(&gpu, net.graph.clone(), 0).unwrap();
    ex.load_params_parts(&gpu, &[(TINY_PHONG_WEIGHTS, "tiny", ""), (&prior_bytes, "prior", "dec.")]).unwrap();
    // Both files whole would clash on nothing but leave the prior's encoder unexpected.
    let err = ex.load_params_parts(&gpu, &[(TINY_PHONG_WEIGHTS, "tiny", ""), (&prior_bytes, "prior", "")]).unwrap_err().to_string();
    assert!(err.contains("unexpected 'enc.conv0.weight'"), "{err}");
    ex.freeze_params();
    ex.want_grad(code);
    ex.keep(loss);
    ex.training = false;
    let view = View { azimuth: 30.0, elevation: 70.0, radius: 3.3 };
    ex.feed(&gpu, net.pose, &pose_for_view(&view, rp.input, rp.cam, Some([16, 16, 32, 32]))).unwrap();
    ex.feed(&gpu, net.light.unwrap(), &light_values(&Light::default())).unwrap();
    ex.feed(&gpu, target, &vec![0.3; 3 * h * w]).unwrap();
    let z: Vec<f32> = (0..pp.latent).map(|i| 0.3 + 0.4 * ((i * 37 % 64) as f32 / 64.0)).collect();
    assert_code_gradient(&gpu, &mut ex, code, loss, &z, 0.1);
}

/// The analytic gradient of `loss` with respect to the input `code` at `z` against central
/// finite differences of step `step`. Single code entries move an f32 loss by less than its
/// rounding; directional derivatives gather them all: along the gradient itself (its norm)
/// and along a fixed mixed-sign direction (the dot product with the gradient).
fn assert_code_gradient(gpu: &Gpu, ex: &mut rendernet::graph::Executor, code: rendernet::graph::Value, loss: rendernet::graph::Value, z: &[f32], step: f64) {
    let loss_at = |ex: &mut rendernet::graph::Executor, z: &[f32]| {
        ex.feed(gpu, code, z).unwrap();
        ex.forward(gpu).unwrap();
        ex.read(gpu, loss).unwrap()[0] as f64
    };
    ex.feed(gpu, code, z).unwrap();
    ex.backward(gpu, loss).unwrap();
    let g: Vec<f64> = ex.grad(gpu, code).unwrap().iter().map(|&v| v as f64).collect();
    let norm = g.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mixed: Vec<f64> = (0..z.len()).map(|i| if i % 3 == 0 { 1.0 } else { -0.5 } / (z.len() as f64).sqrt()).collect();
    for (name, dir) in [("gradient direction", g.iter().map(|v| v / norm).collect::<Vec<_>>()), ("mixed direction", mixed)] {
        let at = |s: f64| z.iter().zip(&dir).map(|(&a, d)| (a as f64 + s * d) as f32).collect::<Vec<f32>>();
        let fd = (loss_at(ex, &at(step)) - loss_at(ex, &at(-step))) / (2.0 * step);
        let analytic: f64 = g.iter().zip(&dir).map(|(a, d)| a * d).sum();
        eprintln!("{name}: analytic {analytic:.3e}, finite difference {fd:.3e}");
        assert!(fd.abs() > 1e-7, "{name}: the loss does not move ({fd:e}); the test would prove nothing");
        assert!((analytic - fd).abs() <= 0.1 * fd.abs(), "{name}: analytic {analytic} vs finite difference {fd}");
    }
}

/// The texture decoder in front of a coloured RenderNet (decoded RGB times the occupancy,
/// beside the occupancy): the image loss's gradient with respect to the texture code matches
/// finite differences. The renderer is the shipped colour network, so the texture reaches the
/// image through the colour it learned (its first conv and its composited colour path); the
/// decoder is the shipped one.
#[test]
fn texture_code_gradient_matches_finite_differences() {
    use rendernet::graph::{Executor, Op};
    use rendernet::nn::camera::{input_values, light_values, pose_for_view};
    use rendernet::nn::rendernet::{Head, phong_of};
    use rendernet::nn::texture::{TexturePreset, decoder_with_renderer};
    use rendernet::ops::loss::Loss;
    use rendernet::voxel::shapes::TEXTURE_CODE;
    let gpu = Gpu::new().unwrap();
    let (tp, rp) = (TexturePreset::small(), Preset::tiny().with_colour());
    assert!(decoder_with_renderer(&tp, &Preset::tiny(), Head::Phong(phong_of(&Light::default())), 1, [32, 32]).is_err(), "a grey renderer has no colour to take");
    let odd = rendernet::nn::texture::TextureDecoder::build(&TexturePreset { res: 12, ..TexturePreset::small() }, 1, false);
    assert!(odd.is_err_and(|e| e.to_string().contains("multiple of 8")), "a 12^3 texture cannot be decoded from 4^3 doublings");
    let (mut net, code, occupancy) = decoder_with_renderer(&tp, &rp, Head::Phong(phong_of(&Light::default())), 1, [32, 32]).unwrap();
    let [h, w] = [net.graph.info(net.image).shape[2], net.graph.info(net.image).shape[3]];
    let target = net.graph.input("target", &[1, 3, h, w]).unwrap();
    let loss = net.graph.apply("loss", Op::Loss(Loss::Mse), &[net.image, target]).unwrap();
    let mut ex = Executor::new(&gpu, net.graph.clone(), 3).unwrap();
    // The shipped decoder: a fresh one paints nothing (its colour layers start at zero), so
    // the code would have no gradient to check.
    let parts = [(rendernet::nn::render::TINY_PHONG_COLOUR_WEIGHTS, "tiny-phong-colour", ""), (rendernet::nn::texture::TEXTURE_SMALL_WEIGHTS, "texture", "tex.")];
    ex.load_params_parts(&gpu, &parts).unwrap();
    ex.freeze_params();
    ex.want_grad(code);
    ex.keep(loss);
    ex.training = false;
    let view = View { azimuth: 30.0, elevation: 70.0, radius: 3.3 };
    ex.feed(&gpu, occupancy, &input_values(&voxel::bunny().resample_to(tp.res).unwrap())).unwrap();
    ex.feed(&gpu, net.pose, &pose_for_view(&view, rp.input, rp.cam, Some([16, 16, 32, 32]))).unwrap();
    ex.feed(&gpu, net.light.unwrap(), &light_values(&Light::default())).unwrap();
    ex.feed(&gpu, target, &vec![0.3; 3 * h * w]).unwrap();
    let z: Vec<f32> = (0..TEXTURE_CODE).map(|i| 0.2 + 0.6 * ((i * 5 % 9) as f32 / 9.0)).collect();
    assert_code_gradient(&gpu, &mut ex, code, loss, &z, 0.2);
}

/// The code search runs end to end on a shipped RenderNet and a (seeded, untrained) prior:
/// the image loss falls at every step, the recovered grid is the prior's 32^3 in 0..1, and a starting code
/// of the wrong length is refused. (Recovery quality needs a trained prior; eval-invert
/// measures that.)
#[test]
fn shape_search_lowers_the_image_loss() {
    use rendernet::graph::Executor;
    use rendernet::invert::{ShapeOptions, ShapeView};
    use rendernet::nn::prior::{PriorPreset, ShapePrior};
    let gpu = Gpu::new().unwrap();
    let pp = PriorPreset::small();
    let prior = Executor::new(&gpu, ShapePrior::build(&pp, 1, false).unwrap().graph, 3).unwrap();
    let file = std::env::temp_dir().join(format!("rendernet-prior-search-{}.safetensors", std::process::id()));
    prior.save_params(&gpu, &file).unwrap();
    let prior_bytes = std::fs::read(&file).unwrap();
    let _ = std::fs::remove_file(&file);
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let grid = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let (view, light) = (View::default(), Light::default());
    let target = reference::RayMarcher::new(&gpu).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let inv = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", Light::default()).unwrap();
    let o = ShapeOptions { steps: 6, lr: 0.05, ..ShapeOptions::default() };
    let one = [ShapeView { image: &target, view, light }];
    let est = inv.recover_shape(&gpu, &pp, &prior_bytes, &one, &o).unwrap();
    assert_eq!(est.curve.len(), 7);
    // An untrained decoder barely reacts to its code, so the loss falls only a little, but
    // it must fall at every step (the curve keeps the best so far: a wrong-signed gradient
    // would leave it flat).
    assert!(est.curve.windows(2).all(|w| w[1] < w[0]), "the loss did not fall at every step: {:?}", est.curve);
    assert_eq!(est.grid.dims(), [32; 3]);
    assert!(est.grid.occupancy().iter().all(|&v| v > 0.0 && v < 1.0));
    let bad = ShapeOptions { start: Some(vec![0.5; 3]), ..o };
    assert!(inv.recover_shape(&gpu, &pp, &prior_bytes, &one, &bad).unwrap_err().to_string().contains("3 entries"));
    assert!(inv.recover_shape(&gpu, &pp, &prior_bytes, &[], &o).unwrap_err().to_string().contains("at least one image"));
}

/// Multi-start picks the start that explains the images: a prior whose decoder reacts
/// strongly to its code (fc weights scaled up), code statistics holding 11 random codes,
/// and two images (two views, two lights) rendered by the same decoder and network from
/// the 7th. Scoring in batches must find it among the 12 starts (the mean code first), so
/// the best start's decoded grid is the 7th code's; a wrong item order (codes or views
/// mixed up in the batch) picks another. The stats survive the weights file, and the
/// parameter loader ignores them. With the silhouette term the true code's loss grows by
/// a small amount only (its mask against its own render's foreground: 0.0038 measured; a
/// wrong or inverted mask target gives tenths).
#[test]
fn multi_start_finds_the_training_code_that_rendered_the_images() {
    use rendernet::graph::Executor;
    use rendernet::invert::{ShapeOptions, ShapeView};
    use rendernet::nn::camera::grid_from_input_values;
    use rendernet::nn::prior::{CodeStats, PriorPreset, ShapePrior, decoder_with_renderer};
    use rendernet::nn::rendernet::{Head, phong_of};
    let gpu = Gpu::new().unwrap();
    let pp = PriorPreset::small();
    let prior = Executor::new(&gpu, ShapePrior::build(&pp, 1, false).unwrap().graph, 5).unwrap();
    for (name, gain) in [("dec.fc.weight", 40.0), ("dec.up0.weight", 4.0), ("dec.up1.weight", 4.0), ("dec.up2.weight", 4.0), ("dec.out.weight", 4.0)] {
        let v = prior.graph().value(name).unwrap();
        let w: Vec<f32> = prior.read(&gpu, v).unwrap().iter().map(|x| x * gain).collect();
        prior.feed(&gpu, v, &w).unwrap();
    }
    let file = std::env::temp_dir().join(format!("rendernet-prior-multistart-{}.safetensors", std::process::id()));
    prior.save_params(&gpu, &file).unwrap();
    // Code k: high on every 11th entry from k, low elsewhere, so no two decode alike.
    let codes: Vec<f32> = (0..11 * pp.latent).map(|i| if (i % pp.latent) % 11 == i / pp.latent { 0.95 } else { 0.05 }).collect();
    let stats = CodeStats::of(codes.clone(), pp.latent).unwrap();
    rendernet::train::prior::attach_code_stats(&file, &stats).unwrap();
    let bytes = std::fs::read(&file).unwrap();
    let _ = std::fs::remove_file(&file);
    assert_eq!(CodeStats::from_weights(&bytes, "prior").unwrap().as_ref(), Some(&stats));
    let mut reload = Executor::new(&gpu, ShapePrior::build(&pp, 1, false).unwrap().graph, 0).unwrap();
    reload.load_params_bytes(&gpu, &bytes, "prior").expect("stats are not unexpected parameters");
    // The images: code 6 decoded and rendered full frame by the shipped network.
    let p = Preset::tiny();
    let head_light = Light::default();
    let (net, code) = decoder_with_renderer(&pp, &p, Head::Phong(phong_of(&head_light)), 1, [p.cam, p.cam]).unwrap();
    let mut ex = Executor::new(&gpu, net.graph.clone(), 0).unwrap();
    ex.load_params_parts(&gpu, &[(TINY_PHONG_WEIGHTS, "tiny", ""), (&bytes, "prior", "dec.")]).unwrap();
    ex.training = false;
    ex.keep(net.image);
    ex.keep(net.grid);
    let truth = &codes[6 * pp.latent..7 * pp.latent];
    ex.feed(&gpu, code, truth).unwrap();
    let (shots, images) = two_shots(&gpu, &mut ex, &net, p.input, &p, head_light);
    let truth_grid = grid_from_input_values(&ex.read(&gpu, net.grid).unwrap(), pp.res).unwrap();
    let views: Vec<ShapeView> = images.iter().zip(&shots).map(|(image, (view, light))| ShapeView { image, view: *view, light: *light }).collect();
    let inv = Inverter::new(p, TINY_PHONG_WEIGHTS, "embedded", head_light).unwrap();
    let o = ShapeOptions { steps: 2, candidates: 11, keep: 1, ..ShapeOptions::default() };
    let est = inv.recover_shape(&gpu, &pp, &bytes, &views, &o).unwrap();
    // The silhouette term of the true code is small (the network's mask against the
    // foreground of its own render); a term fed the wrong mask would not be.
    let plain = inv.recover_shape(&gpu, &pp, &bytes, &views, &ShapeOptions { silhouette: false, ..o.clone() }).unwrap();
    let term = est.curve[0] - plain.curve[0];
    assert!(term > 0.0 && term < 0.02, "silhouette term of the true code {term} (measured 0.0038)");
    let other = grid_from_input_values(&{
        ex.feed(&gpu, code, &codes[..pp.latent]).unwrap();
        ex.forward(&gpu).unwrap();
        ex.read(&gpu, net.grid).unwrap()
    }, pp.res).unwrap();
    let spread = other.occupancy().iter().zip(truth_grid.occupancy()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(spread > 0.1, "codes 0 and 6 decode alike (max difference {spread}): the test cannot tell them apart");
    let diff = est.start_grid.occupancy().iter().zip(truth_grid.occupancy()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(diff < 1e-4, "the best start is not the code that rendered the images (max difference {diff})");
}

/// Texture multi-start: two images rendered through the shipped texture decoder and colour
/// network from the code of the 6th of 8 starting paints (a painted bunny, two views and
/// lights); scoring the 8 starts in batches must pick that paint (its loss is near 0, the
/// others' are not: a wrong item order picks another), and the descent from it never rises.
/// A grey network is refused.
#[test]
fn texture_search_finds_the_paint_that_rendered_the_images() {
    use rendernet::graph::Executor;
    use rendernet::invert::{ShapeView, TextureOptions, texture_starts};
    use rendernet::nn::camera::input_values;
    use rendernet::nn::render::TINY_PHONG_COLOUR_WEIGHTS;
    use rendernet::nn::rendernet::{Head, phong_of};
    use rendernet::nn::texture::{TEXTURE_SMALL_WEIGHTS, TexturePreset, decoder_with_renderer};
    let gpu = Gpu::new().unwrap();
    let (tp, rp) = (TexturePreset::small(), Preset::tiny().with_colour());
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let shape = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let head_light = Light::default();
    let (net, code, occupancy) = decoder_with_renderer(&tp, &Preset { input: tp.res, ..rp.clone() }, Head::Phong(phong_of(&head_light)), 1, [rp.cam, rp.cam]).unwrap();
    let mut ex = Executor::new(&gpu, net.graph.clone(), 0).unwrap();
    ex.load_params_parts(&gpu, &[(TINY_PHONG_COLOUR_WEIGHTS, "colour", ""), (TEXTURE_SMALL_WEIGHTS, "texture", "tex.")]).unwrap();
    ex.training = false;
    ex.keep(net.image);
    let starts = texture_starts(8);
    ex.feed(&gpu, code, &starts[5].code()).unwrap();
    ex.feed(&gpu, occupancy, &input_values(&shape.resample_to(tp.res).unwrap())).unwrap();
    let (shots, images) = two_shots(&gpu, &mut ex, &net, tp.res, &rp, head_light);
    let views: Vec<ShapeView> = images.iter().zip(&shots).map(|(image, (view, light))| ShapeView { image, view: *view, light: *light }).collect();
    let inv = Inverter::new(rp, TINY_PHONG_COLOUR_WEIGHTS, "colour", head_light).unwrap();
    let o = TextureOptions { steps: 3, candidates: 8, keep: 1, ..TextureOptions::default() };
    let est = inv.recover_texture(&gpu, &tp, TEXTURE_SMALL_WEIGHTS, &shape, &views, &o).unwrap();
    let (got, want) = (est.start_paint.code(), starts[5].code());
    assert!(got.iter().zip(&want).all(|(a, b)| (a - b).abs() < 1e-5), "the best start {got:?} is not the paint that rendered the images {want:?}");
    eprintln!("texture search curve {:?}", est.curve);
    assert!(est.curve[0] < 1e-3, "the true paint's loss {} (measured 1.7e-4: the window crop against the full frame)", est.curve[0]);
    assert!(est.curve.windows(2).all(|w| w[1] <= w[0]), "{:?}", est.curve);
    assert_eq!(est.curve.len(), 4);
    assert_eq!(est.grid.dims(), shape.dims());
    assert!(est.grid.colour().is_some());
    let others = {
        let o1 = TextureOptions { start: Some(starts[0].code()), steps: 0, ..o.clone() };
        inv.recover_texture(&gpu, &tp, TEXTURE_SMALL_WEIGHTS, &shape, &views, &o1).unwrap().curve[0]
    };
    assert!(others > 10.0 * est.curve[0].max(1e-5), "another paint scores {others}, the true one {}: the test cannot tell them apart", est.curve[0]);
    let grey = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "grey", head_light).unwrap();
    let err = grey.recover_texture(&gpu, &tp, TEXTURE_SMALL_WEIGHTS, &shape, &views, &o).unwrap_err().to_string();
    assert!(err.contains("coloured"), "{err}");
}

/// `invert --texture`: the paint of a painted chair at the scene flags' camera and light,
/// with a tiny search; the .vox file keeps colour, the three-panel picture and the JSON's
/// scores come out; a binvox output (no colour) is refused before any work, and grey
/// weights with a message saying why.
#[test]
fn invert_cli_with_texture_writes_a_painted_grid() {
    let dir = std::env::temp_dir().join(format!("rendernet-invert-texture-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (out, vox) = (dir.join("out.png"), dir.join("painted.vox"));
    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    let o = run(&["invert", "--texture", "--out-voxels", dir.join("x.binvox").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("x.binvox") && err.contains(".vox"), "{err}");
    let o = run(&["invert", "--texture", "--preset", "nano", "--out", out.to_str().unwrap(), "--out-voxels", vox.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("grey grids") && err.contains("--colour"), "grey weights: {err}");
    let args = ["invert", "--texture", "--shape", "chair", "--seed", "9001", "--colour", "--texture-starts", "4", "--texture-keep", "1", "--texture-steps", "2",
        "--json", "--out", out.to_str().unwrap(), "--out-voxels", vox.to_str().unwrap()];
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["object_psnr", "turned_object_psnr"] {
        assert!(j[key].as_f64().is_some_and(f64::is_finite), "{key} missing in {text}");
    }
    assert_eq!(j["code"].as_array().map(Vec::len), Some(9), "{text}");
    assert_eq!(j["loss_curve"].as_array().map(Vec::len), Some(3), "{text}");
    assert!(voxel::vox::read(&vox).unwrap().colour().is_some());
    let png = image::open(&out).unwrap();
    assert_eq!((png.width(), png.height()), (384, 128));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two cameras and lights, and the network's full-frame images at them (`ex` runs `net`, its
/// code already fed; `input` is the side of the grid it reads): the images the multi-start
/// tests search for.
fn two_shots(gpu: &Gpu, ex: &mut rendernet::graph::Executor, net: &rendernet::nn::rendernet::RenderNet, input: usize, p: &Preset, head_light: Light) -> ([(View, Light); 2], Vec<reference::Image>) {
    use rendernet::nn::camera::{light_values, pose_for_view};
    let shots = [(View { azimuth: 35.0, elevation: 70.0, radius: 3.3 }, Light { azimuth: 30.0, elevation: 60.0, ..head_light }),
                 (View { azimuth: 200.0, elevation: 100.0, radius: 3.5 }, Light { azimuth: 120.0, elevation: 80.0, ..head_light })];
    let images = shots
        .iter()
        .map(|(view, light)| {
            ex.feed(gpu, net.pose, &pose_for_view(view, input, p.cam, None)).unwrap();
            ex.feed(gpu, net.light.unwrap(), &light_values(light)).unwrap();
            ex.forward(gpu).unwrap();
            reference::Image { channels: 3, size: p.image_for(p.cam), data: ex.read(gpu, net.image).unwrap() }
        })
        .collect();
    (shots, images)
}

/// `eval-invert` end to end on a small held-out Phong set: one record per sample, every
/// angle in 0..180, and the front/behind light split agreeing with the dataset's own lights
/// (the true light's direction towards the camera, sample by sample, in the split's order).
/// Seed 5's four views light from both sides, so a flipped side test shows.
#[test]
fn eval_invert_reports_every_sample_and_splits_lights_by_side() {
    let dir = std::env::temp_dir().join(format!("rendernet-eval-invert-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.join("set");
    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    let o = run(&["dataset", "--count", "4", "--views", "1", "--res", "16", "--image", "128", "--seed", "5", "--test-fraction", "1", "--out", d.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&["eval-invert", "--data", d.to_str().unwrap(), "--samples", "0", "--steps", "1", "--starts", "1", "--azimuths", "4", "--elevations", "2", "--json"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    let per = j["per_sample"].as_array().unwrap();
    assert_eq!((j["samples"].as_u64(), per.len()), (Some(4), 4));
    let ds = rendernet::data::Dataset::open(&d).unwrap();
    let test = ds.split(rendernet::data::Split::Test);
    let mut front = 0;
    for (i, s) in per.iter().enumerate() {
        for k in ["pose_degrees", "network_pose_degrees", "light_degrees", "light_optimum_degrees", "light_exact_degrees", "light_exact_truth_degrees"] {
            let a = s[k].as_f64().unwrap();
            assert!((0.0..=180.0).contains(&a), "sample {i}: {k} = {a}");
        }
        let truth = rendernet::invert::light_direction(&test.get(i).unwrap().light)[2] > 0.0;
        assert_eq!(s["light_in_front"].as_bool(), Some(truth), "sample {i}");
        front += truth as u64;
    }
    assert!(front > 0 && front < 4, "seed 5 should light from both sides: {front} of 4 in front");
    assert_eq!(j["lights_in_front"].as_u64(), Some(front));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `Inverter::with_light_network`: the camera is searched through tiny, then the light is
/// base's best at that camera (of the 5-degree polish grid). The estimate keeps tiny's own
/// light beside it, and here the two differ, so an ignored light network fails the first
/// assertion. The command refuses a preset with no shipped weights and the flag with
/// --prior when it parses its arguments.
#[test]
fn a_light_network_picks_the_light_at_the_recovered_camera() {
    use rendernet::invert::InvertOptions;
    use rendernet::nn::render::BASE_PHONG_WEIGHTS;
    let gpu = Gpu::new().unwrap();
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let grid = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let (view, light) = (View { azimuth: 40.0, elevation: 75.0, radius: 3.6 }, Light { azimuth: 20.0, elevation: 70.0, ..Light::default() });
    let target = reference::RayMarcher::new(&gpu).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let base = || Inverter::new(Preset::base(), BASE_PHONG_WEIGHTS, "embedded base", Light::default()).unwrap();
    let tiny = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded tiny", Light::default()).unwrap();
    let o = InvertOptions { azimuths: 4, elevations: 2, keep: 1, steps: 3, ..Default::default() };
    let est = tiny.with_light_network(base()).unwrap().invert(&gpu, &grid, &target, &o, |_, _| {}).unwrap();
    let (want, _) = base().light_optimum(&gpu, &grid, &target, &est.view).unwrap();
    assert_eq!((est.light.azimuth, est.light.elevation), (want.azimuth, want.elevation));
    let own = (est.search_light.azimuth, est.search_light.elevation);
    assert_ne!(own, (want.azimuth, want.elevation), "tiny's own light is base's pick; the test would prove nothing");
    assert!(est.mse.is_finite() && est.image.size == 128);

    let run = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    for (args, says) in [(&["invert", "--light-network", "paper"][..], "paper"), (&["invert", "--prior", "--light-network", "base"][..], "--prior")] {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("--light-network") && err.contains(says), "{args:?}: {err}");
    }
}

/// `--pick exact` (`Pick::Exact`, the default): the exact renderer's maps of the known grid
/// rank the search's hypotheses. Of the true camera, its far-side twin, a view 40 degrees
/// round and one 15 degrees higher, `Inverter::exact_scores` puts the truth first (the
/// target is the reference renderer's own image of that grid, so the truth scores near zero:
/// only the 20-degree light grid's step is left). A small search then ends at a camera whose
/// exact score is no worse than the network's own pick's (measured, not guaranteed: the
/// polish scores under finer lights than the ranking; here 17.9 against 228), its light is
/// the exact light at that camera and within 5 degrees of the truth (the bunny's exact light
/// at the true camera is exact: the target is drawn from this grid; 5 degrees leaves room
/// for a camera a degree off), and with `Pick::Network` the estimate is the network's pick.
#[test]
fn the_exact_renderer_picks_the_camera_among_the_hypotheses() {
    use rendernet::invert::{InvertOptions, Pick};
    let gpu = Gpu::new().unwrap();
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let grid = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let view = View { azimuth: 200.0, elevation: 70.0, radius: 3.8 };
    let light = Light { azimuth: 20.0, elevation: 70.0, ..Light::default() };
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let target = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let inv = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded tiny", Light::default()).unwrap();
    let views = [
        View { azimuth: 20.0, ..view },
        View { azimuth: 240.0, ..view },
        view,
        View { elevation: 55.0, ..view },
    ];
    let s = inv.exact_scores(&gpu, &grid, &target, &views).unwrap();
    eprintln!("exact scores (twin, +40 azimuth, truth, 15 higher): {s:?}");
    for k in [0, 1, 3] {
        assert!(s[2] < s[k], "view {k} scores {} against the truth's {}", s[k], s[2]);
    }

    let o = InvertOptions { azimuths: 4, elevations: 2, keep: 1, steps: 3, ..Default::default() };
    assert_eq!(o.pick, Pick::Exact, "the default");
    let est = inv.invert(&gpu, &grid, &target, &o, |_, _| {}).unwrap();
    let s = inv.exact_scores(&gpu, &grid, &target, &[est.view, est.network_view]).unwrap();
    eprintln!("exact scores of the estimate and the network's pick: {s:?}");
    assert!(s[0] <= s[1], "the exact pick scores {} against the network's {}", s[0], s[1]);
    // The light is the exact light of every direction at the camera found, and near the truth.
    let exact = inv.light_exact(&gpu, &grid, &target, &est.view).unwrap();
    assert_eq!((est.light.azimuth, est.light.elevation), (exact.azimuth, exact.elevation));
    let off = rendernet::invert::angle_between(rendernet::invert::light_direction(&light), rendernet::invert::light_direction(&est.light));
    assert!(off < 5.0, "light {off:.1} degrees from the truth");
    let net = inv.invert(&gpu, &grid, &target, &InvertOptions { pick: Pick::Network, ..o }, |_, _| {}).unwrap();
    assert_eq!((net.view.azimuth, net.view.elevation), (net.network_view.azimuth, net.network_view.elevation));
}
