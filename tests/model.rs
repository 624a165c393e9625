//! RenderNet end to end: the presets build with the expected shapes; `dataset`, `train`
//! (with resume) and `eval` work from the command line; and the shipped weights render a
//! shape the network never saw close to the reference renderer, so a broken kernel or a
//! mis-loaded weight fails here.

use rendernet::nn::render::{Renderer, TINY_PHONG_WEIGHTS};
use rendernet::nn::rendernet::{Head, Preset, RenderNet, phong_of};
use rendernet::reference::{self, Light, Shader, View};
use rendernet::Gpu;
use rendernet::metrics::Scores;
use std::process::Command;

#[test]
fn presets_build_with_the_papers_shapes() {
    let head = Head::Phong(phong_of(&Light::default()));
    let p = Preset::tiny();
    let net = RenderNet::build(&p, head, 2, [p.cam, p.cam], true).unwrap();
    assert_eq!(net.graph.info(net.image).shape, [2, 3, 128, 128]);
    let crop = RenderNet::build(&p, head, 1, [16, 8], true).unwrap();
    assert_eq!(crop.graph.info(crop.image).shape, [1, 3, 32, 16]);
    let paper = Preset::paper();
    let big = RenderNet::build(&paper, head, 1, [paper.cam, paper.cam], false).unwrap();
    assert_eq!(big.graph.info(big.image).shape, [1, 3, 512, 512]);
    // The projection folds 16 channels x 32 depth (128 / 4) into K = 512 inputs.
    let proj = big.graph.value("proj.weight").unwrap();
    assert_eq!(big.graph.info(proj).shape, [1024, 16 * 32, 1, 1]);
    assert!(RenderNet::build(&p, head, 1, [6, 8], false).is_err(), "windows must be multiples of 4");
    assert!(Preset::by_name("huge").unwrap_err().to_string().contains("paper, ec or ec-deep"));
}

fn rendernet(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_rendernet")).args(args).output().unwrap();
    let (o, e) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "rendernet {args:?} failed:\n{o}\n{e}");
    o.to_string()
}

/// `dataset`, `train`, `--resume` and `eval` from the command line. A run interrupted at
/// step 2 and resumed to step 4 must end with weights bit-identical to an uninterrupted
/// 4-step run: that holds only if every kernel is deterministic (no float atomics), the
/// checkpoint carries the Adam moments and the step, and the resumed run draws the same
/// samples, crops, corruptions and dropout masks.
#[test]
fn dataset_train_resume_and_eval_from_the_command_line() {
    let dir = std::env::temp_dir().join(format!("rendernet-model-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (data, ckpt) = (dir.join("data"), dir.join("net.ckpt"));
    let d = data.to_str().unwrap();
    rendernet(&["dataset", "--count", "2", "--views", "2", "--res", "16", "--image", "128", "--seed", "3", "--out", d]);
    let c = ckpt.to_str().unwrap();
    // A fixed crop keeps the window schedule independent of --steps; augmentation on, so
    // the resumed run must also repeat the corruptions.
    let common = ["--data", d, "--eval-samples", "1", "--eval-every", "2", "--crop", "16", "--batch", "2", "--augment-dropout", "0.5", "--augment-salt", "0.1"];
    let out = rendernet(&[&["train", "--steps", "2", "--out", c][..], &common[..]].concat());
    assert!(out.contains("final held-out PSNR"), "{out}");
    for f in [ckpt.clone(), ckpt.with_extension("weights.safetensors"), ckpt.with_extension("curve.png")] {
        assert!(f.exists(), "{} missing", f.display());
    }
    let after_two = tensors_of(&ckpt.with_extension("weights.safetensors"));
    let out = rendernet(&[&["train", "--steps", "4", "--resume", c, "--out", c][..], &common[..]].concat());
    assert!(out.contains("final held-out PSNR"), "{out}");
    // The log spans the interruption: losses of steps 1..=4 and evaluations at 2 and 4.
    let log = std::fs::read_to_string(ckpt.with_extension("log.csv")).unwrap();
    let losses = log.lines().filter(|l| l.ends_with(',')).count();
    assert_eq!(losses, 4, "{log}");
    assert!(log.contains("\n2,,") && log.contains("\n4,,"), "{log}");
    // The weights record the images seen across the interruption (4 steps x batch 2).
    let meta = rendernet::graph::params::load_safetensors(&ckpt.with_extension("weights.safetensors")).unwrap().1;
    assert_eq!(meta.get("images").map(String::as_str), Some("8"), "{meta:?}");
    assert!(meta.get("train_seconds").and_then(|s| s.parse::<f64>().ok()).is_some(), "{meta:?}");
    let straight = dir.join("straight.ckpt");
    rendernet(&[&["train", "--steps", "4", "--out", straight.to_str().unwrap()][..], &common[..]].concat());
    let (resumed, uninterrupted) = (tensors_of(&ckpt.with_extension("weights.safetensors")), tensors_of(&straight.with_extension("weights.safetensors")));
    assert_eq!(resumed.len(), uninterrupted.len());
    let moved = resumed.iter().zip(&after_two).filter(|(a, b)| a.1 != b.1).count();
    assert!(moved * 2 > resumed.len(), "steps 3-4 changed only {moved} of {} tensors", resumed.len());
    for ((n, a), (_, b)) in resumed.iter().zip(&uninterrupted) {
        assert!(a == b, "{n}: the resumed run's weights differ from the uninterrupted run's");
    }
    let w = ckpt.with_extension("weights.safetensors");
    let out = rendernet(&["eval", "--weights", w.to_str().unwrap(), "--data", d, "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("eval --json: {e}\n{out}"));
    let n = j["per_shape"].as_object().map_or(0, |o| o.len());
    assert!(n > 0, "{out}");
    for key in ["psnr_mean", "object_psnr_mean", "ssim_mean", "black_image_psnr"] {
        let v = j[key].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v > 0.0, "{key} = {v} in {out}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Name -> raw bytes of every tensor of a safetensors file, sorted by name.
fn tensors_of(p: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let bytes = std::fs::read(p).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let mut v: Vec<(String, Vec<u8>)> = st.tensors().into_iter().map(|(n, t)| (n, t.data().to_vec())).collect();
    v.sort();
    v
}

/// The shipped weights on a shape no training set contains (the Stanford bunny, a real
/// mesh; training used procedural chairs, tables, sofas and primitives) at a close view,
/// scored by object PSNR (the box around the object: full-frame PSNR would mostly score the
/// black background) against the anti-aliased reference.
#[test]
fn shipped_weights_render_an_unseen_shape_close_to_the_reference() {
    let gpu = Gpu::new().unwrap();
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let grid = rendernet::voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let view = View { azimuth: 120.0, elevation: 80.0, radius: 3.3 };
    let light = Light { azimuth: -40.0, elevation: 50.0, ..Light::default() };
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128).unwrap();
    let img = net.render(&gpu, &grid, &view, &light).unwrap();
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let s = Scores::of(&img, &truth);
    let black = Scores::black_floor(&truth);
    eprintln!("object PSNR {:.2} dB (all-black {:.2}), full-frame {:.2}, SSIM {:.3}, mask IoU {:.3}", s.object_psnr, black.object_psnr, s.psnr, s.ssim, s.iou);
    assert!(s.object_psnr > MIN_OBJECT_DB, "shipped weights: object PSNR {:.2} dB, expected > {MIN_OBJECT_DB} (all-black {:.2})", s.object_psnr, black.object_psnr);
    // The silhouette is the mask head's alone (object PSNR barely sees the background).
    assert!(s.iou > MIN_MASK_IOU, "shipped weights: mask IoU {:.3}, expected > {MIN_MASK_IOU}", s.iou);
}

/// The shipped weights (fine-tuned at a 64^3 input) measured 17.30 dB object PSNR on this
/// view on lavapipe (the 32^3 weights before them: 18.82, which this light from behind the
/// left suited better; the first weights: 11.33; an all-black image: 7.05); the threshold
/// sits just under it (drivers differ in float rounding by far less than 0.3 dB), so a
/// regression of the weights, a broken kernel or a mis-loaded tensor fails here.
const MIN_OBJECT_DB: f64 = 17.0;
/// The same render's mask IoU against the reference's silhouette (measured 0.976; set under it).
const MIN_MASK_IOU: f64 = 0.95;

/// The shipped base weights (the most accurate rung, trained on a GPU) on a procedural chair
/// no training set drew, at the paper's closest framing (radius 3.3), against the
/// anti-aliased reference: object PSNR above a threshold set just under the measured value.
#[test]
fn shipped_base_weights_render_an_unseen_chair_close_to_the_reference() {
    use rendernet::nn::render::BASE_PHONG_WEIGHTS;
    let gpu = Gpu::new().unwrap();
    let grid = rendernet::voxel::Family::Chair.generate(9001).to_grid(64).unwrap();
    let (view, light) = (View { radius: 3.3, ..View::default() }, Light::default());
    let mut net = Renderer::new(&gpu, Preset::base().with_input(64), BASE_PHONG_WEIGHTS, "embedded base", 128).unwrap();
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let s = Scores::of(&net.render(&gpu, &grid, &view, &light).unwrap(), &truth);
    let black = Scores::black_floor(&truth);
    eprintln!("object PSNR {:.2} dB (all-black {:.2}), full-frame {:.2}", s.object_psnr, black.object_psnr, s.psnr);
    assert!(s.object_psnr > MIN_BASE_OBJECT_DB, "base weights: object PSNR {:.2} dB, expected > {MIN_BASE_OBJECT_DB}", s.object_psnr);
}

/// The shipped base weights measured 20.44 dB object PSNR on this chair on lavapipe (`render
/// --quality best --shape chair --seed 9001 --radius 3.3 --compare`; tiny: 17.19; an
/// all-black image: 6.57); the threshold sits just under it.
const MIN_BASE_OBJECT_DB: f64 = 20.1;

/// Above the trained image side the network draws at the camera-grid density it learned and
/// the image is upscaled: the default bunny at 256 px scores within 1.5 dB object PSNR of its
/// 128 px picture (tiny: 22.37 at 128, measured 21.56 at 256). Drawn directly at twice the
/// density, as the old code did, it fell to ~17 dB.
#[test]
fn images_above_the_trained_side_keep_the_trained_quality() {
    let gpu = Gpu::new().unwrap();
    let grid = rendernet::voxel::bunny();
    let (view, light) = (View::default(), Light::default());
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let marcher = reference::RayMarcher::new(&gpu).with_options(opts);
    let score = |size: usize| {
        let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded tiny", size).unwrap();
        let img = net.render(&gpu, &grid, &view, &light).unwrap();
        assert_eq!((img.size, net.size(), net.drawn_size()), (size, size, size.min(128)));
        Scores::of(&img, &marcher.render(&gpu, &grid, &view, &light, Shader::Phong, size as u32).unwrap()).object_psnr
    };
    let (native, big) = (score(128), score(256));
    eprintln!("object PSNR {native:.2} dB at 128 px, {big:.2} at 256");
    assert!(big > native - 1.5, "256 px: {big:.2} dB against {native:.2} at 128");
}

/// Both shipped colour models render a painted chair in its colours: object PSNR against the
/// coloured reference above a threshold set just under each one's measured value, and far
/// above what the same weights draw from the chair without its paint (white voxels), so the
/// colour must reach the image. The chair (seed 9001) is none the colour dataset draws (its
/// shape seeds are hashed from the dataset seed).
#[test]
fn shipped_colour_weights_render_a_painted_chair_in_its_colours() {
    use rendernet::nn::render::{BASE_PHONG_COLOUR_WEIGHTS, TINY_PHONG_COLOUR_WEIGHTS};
    let gpu = Gpu::new().unwrap();
    let painted = rendernet::voxel::Family::Chair.generate(9001).to_coloured_grid(64, 9001).unwrap();
    let white = rendernet::voxel::VoxelGrid::new([64; 3], painted.occupancy().to_vec()).unwrap();
    let (view, light) = (View::default(), Light::default());
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &painted, &view, &light, Shader::Phong, 128).unwrap();
    let black = Scores::black_floor(&truth);
    for (preset, weights, min_db) in [(Preset::tiny(), TINY_PHONG_COLOUR_WEIGHTS, MIN_TINY_COLOUR_OBJECT_DB), (Preset::base(), BASE_PHONG_COLOUR_WEIGHTS, MIN_BASE_COLOUR_OBJECT_DB)] {
        let name = preset.name;
        let mut net = Renderer::new(&gpu, preset, weights, "embedded colour", 128).unwrap();
        let s = Scores::of(&net.render(&gpu, &painted, &view, &light).unwrap(), &truth);
        let unpainted = Scores::of(&net.render(&gpu, &white, &view, &light).unwrap(), &truth);
        eprintln!("{name}: object PSNR {:.2} dB, unpainted {:.2}, all-black {:.2}", s.object_psnr, unpainted.object_psnr, black.object_psnr);
        assert!(s.object_psnr > min_db, "{name} colour weights: object PSNR {:.2} dB, expected > {min_db}", s.object_psnr);
        assert!(s.object_psnr > unpainted.object_psnr + 2.0, "{name}: the paint moved object PSNR only {:.2} -> {:.2} dB", unpainted.object_psnr, s.object_psnr);
    }
}

/// The shipped contour weights draw a procedural chair they never saw, at the paper's closest
/// framing (radius 3.3), close to the reference line drawing: full-frame PSNR above a
/// threshold just under the measured value, and well above an all-white image's.
#[test]
fn shipped_contour_weights_draw_an_unseen_chair() {
    use rendernet::nn::render::TINY_CONTOUR_WEIGHTS;
    let gpu = Gpu::new().unwrap();
    let grid = rendernet::voxel::Family::Chair.generate(9001).to_grid(64).unwrap();
    let (view, light) = (View { radius: 3.3, ..View::default() }, Light::default());
    let mut net = Renderer::for_shader(&gpu, Preset::tiny(), Shader::Contour, TINY_CONTOUR_WEIGHTS, "embedded contour", 128).unwrap();
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Contour, 128).unwrap();
    let s = Scores::on_background(&net.render(&gpu, &grid, &view, &light).unwrap(), &truth, 1.0);
    let white = Scores::background_floor(&truth, 1.0);
    eprintln!("full-frame PSNR {:.2} dB (all-white {:.2}), object {:.2} (all-white {:.2})", s.psnr, white.psnr, s.object_psnr, white.object_psnr);
    assert!(s.psnr > MIN_CONTOUR_DB, "contour weights: full-frame PSNR {:.2} dB, expected > {MIN_CONTOUR_DB}", s.psnr);
    assert!(s.object_psnr > white.object_psnr + 3.0, "object PSNR {:.2} dB is near an all-white image's {:.2}", s.object_psnr, white.object_psnr);
}

/// The shipped contour weights measured 16.61 dB full frame (object 12.10; an all-white
/// image 11.77 / 7.03) on this chair on lavapipe (`render --shader contour --shape chair
/// --seed 9001 --radius 3.3 --compare`); the threshold sits just under it.
const MIN_CONTOUR_DB: f64 = 16.3;

/// The shipped tiny colour weights measured 21.49 dB object PSNR on this chair at the default
/// view on lavapipe (the same weights on the unpainted chair: 13.74; an all-black image:
/// 12.41); the threshold sits just under it.
const MIN_TINY_COLOUR_OBJECT_DB: f64 = 21.2;

/// The shipped base colour weights measured 22.70 dB on the same chair and view; the
/// threshold sits just under it.
const MIN_BASE_COLOUR_OBJECT_DB: f64 = 22.4;

/// Cropping the camera grid to the object (the default) leaves the default scene's picture
/// close to what the whole-frame run draws: within 0.01 dB of object PSNR against the
/// reference with a margin as wide as the network's receptive field (~18 camera voxels), and
/// at the default margin within 0.2 dB and never more than 0.05 dB worse (the 64^3 weights
/// measured 22.37 cropped against 22.22 whole: the context 12-18 voxels out still moves them;
/// the 32^3 weights agreed within 0.05), while the network sees at most half the frame.
#[test]
fn cropping_to_the_object_keeps_the_picture_and_halves_the_work() {
    use rendernet::nn::render::{CROP_MARGIN, object_window};
    let gpu = Gpu::new().unwrap();
    let bunny = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/fixtures/bunny64.safetensors")).unwrap();
    let grid = rendernet::voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let (view, light) = (View::default(), Light::default());
    let opts = reference::Options { supersample: 2, ..reference::Options::default() };
    let truth = reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let score = |margin: Option<usize>| {
        let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 128).unwrap().with_crop_margin(margin);
        Scores::of(&net.render(&gpu, &grid, &view, &light).unwrap(), &truth).object_psnr
    };
    let (full, wide, default) = (score(None), score(Some(18)), score(Some(CROP_MARGIN)));
    eprintln!("object PSNR: whole frame {full:.3}, margin 18 {wide:.3}, margin {CROP_MARGIN} {default:.3}");
    assert!((wide - full).abs() <= 0.01, "{wide} vs {full}");
    assert!((default - full).abs() <= 0.2 && default >= full - 0.05, "{default} vs {full}");
    let w = object_window(&grid.resample_to(32).unwrap(), &view, 64, CROP_MARGIN);
    assert!(w[2] * w[3] * 2 <= 64 * 64, "window {w:?} is more than half the frame");
}

/// A grid past the device's storage-binding limit (330^3 f32 = 144 MB; lavapipe binds at
/// most 128 MiB) either renders or fails with an error naming the limit, in both renderers:
/// never a panic, a driver crash or a garbage image.
#[test]
fn grids_past_the_device_limits_run_or_fail_clearly() {
    let gpu = Gpu::new().unwrap();
    let n = 330;
    let mut grid = rendernet::voxel::VoxelGrid::zeros([n; 3]).unwrap();
    for z in n / 4..3 * n / 4 {
        for y in n / 4..3 * n / 4 {
            for x in n / 3..2 * n / 3 {
                grid.set(z, y, x, 1.0);
            }
        }
    }
    let (view, light) = (View::default(), Light::default());
    let check = |what: &str, r: rendernet::Result<reference::Image>| match r {
        Ok(img) => {
            assert!(img.data.iter().all(|v| v.is_finite()), "{what}: non-finite pixels");
            assert!(img.data.iter().any(|&v| v > 0.1), "{what}: blank image");
            eprintln!("{what}: rendered");
        }
        Err(e) => {
            let msg = e.to_string();
            eprintln!("{what}: {msg}");
            assert!(msg.contains("max_") || msg.contains("limit"), "{what}: the error does not name a limit: {msg}");
        }
    };
    let mut net = Renderer::new(&gpu, Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", 64).unwrap();
    check("network", net.render(&gpu, &grid, &view, &light));
    let opts = reference::Options { supersample: 1, ..reference::Options::default() };
    check("reference", reference::RayMarcher::new(&gpu).with_options(opts).render(&gpu, &grid, &view, &light, Shader::Phong, 64));
}

/// A network trained on another shader's dataset (ambient occlusion: one image head, no
/// light) renders through `render --shader ao --weights`, with the reference's AO beside it;
/// without --weights `--shader ao` takes the shipped tiny AO weights (and claims no Phong
/// score), and `eval` scores them, refusing a `--shader` the dataset does not hold. A shader
/// with no shipped weights is refused by name, listing the shipped ones; the shipped toon
/// weights render without --weights.
#[test]
fn weights_of_another_shader_render_with_its_head() {
    let dir = std::env::temp_dir().join(format!("rendernet-ao-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (data, ckpt, png) = (dir.join("data"), dir.join("ao.ckpt"), dir.join("ao.png"));
    let d = data.to_str().unwrap();
    rendernet(&["dataset", "--shader", "ao", "--count", "2", "--views", "1", "--res", "16", "--image", "128", "--seed", "5", "--out", d]);
    rendernet(&["train", "--data", d, "--out", ckpt.to_str().unwrap(), "--steps", "2", "--crop", "16", "--eval-samples", "1"]);
    let w = ckpt.with_extension("weights.safetensors");
    let out = rendernet(&["render", "--shader", "ao", "--weights", w.to_str().unwrap(), "--size", "64", "--compare", "--out", png.to_str().unwrap()]);
    assert!(out.contains("object PSNR") && out.contains("mask IoU"), "{out}");
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (128, 64), "network and reference side by side");
    let out = rendernet(&["render", "--shader", "ao", "--size", "64", "--out", png.to_str().unwrap()]);
    assert!(out.contains("embedded tiny-ao weights") && !out.contains("PSNR"), "{out}");
    let out = rendernet(&["eval", "--shader", "ao", "--data", d, "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert!(j["object_psnr_mean"].as_f64().is_some_and(|v| v > j["black_image_object_psnr"].as_f64().unwrap()), "{out}");
    let refused = Command::new(env!("CARGO_BIN_EXE_rendernet")).args(["eval", "--shader", "phong", "--data", d]).output().unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("--shader phong") && err.contains("holds ao images"), "{err}");
    // `train --init`: the Phong network's trunk under a fresh AO head.
    let phong = dir.join("phong.safetensors");
    std::fs::write(&phong, TINY_PHONG_WEIGHTS).unwrap();
    let init_ckpt = dir.join("init.ckpt");
    let out = rendernet(&["train", "--data", d, "--out", init_ckpt.to_str().unwrap(), "--init", phong.to_str().unwrap(), "--steps", "1", "--crop", "16", "--eval-samples", "1"]);
    assert!(out.contains("tensors taken, 2 initialised fresh (head.image.weight, head.image.bias)"), "{out}");
    let refused = Command::new(env!("CARGO_BIN_EXE_rendernet")).args(["train", "--data", d, "--out", "x.ckpt", "--init", "a", "--resume", "b"]).output().unwrap();
    assert!(!refused.status.success() && String::from_utf8_lossy(&refused.stderr).contains("--init"));
    let refused = Command::new(env!("CARGO_BIN_EXE_rendernet")).args(["render", "--shader", "depth", "--out", png.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("--shader depth") && err.contains("ao (tiny)") && err.contains("contour (tiny)") && err.contains("--weights"), "{err}");
    // Toon weights are shipped too: an RGB image head, no light input.
    let out = rendernet(&["render", "--shader", "toon", "--size", "64", "--out", png.to_str().unwrap()]);
    assert!(out.contains("embedded tiny-toon weights") && !out.contains("PSNR"), "{out}");
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(img.pixels().any(|p| p.0[0] > 128), "the toon render is black");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `frontier --json`: every model scored and timed beside the reference renderer's time and
/// the same-run FMA ceiling, the chart written; a malformed --model is refused by name.
#[test]
fn frontier_scores_and_times_every_model() {
    let dir = std::env::temp_dir().join(format!("rendernet-frontier-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (data, w, png) = (dir.join("data"), dir.join("w.safetensors"), dir.join("f.png"));
    rendernet(&["dataset", "--count", "2", "--views", "1", "--res", "16", "--image", "128", "--seed", "9", "--out", data.to_str().unwrap()]);
    std::fs::write(&w, TINY_PHONG_WEIGHTS).unwrap();
    let model = format!("copy=tiny:{}", w.display());
    // One EC training step on whole frames: the baseline's trainer path and its chart group.
    let ec = dir.join("ec.ckpt");
    rendernet(&["train", "--preset", "ec", "--data", data.to_str().unwrap(), "--out", ec.to_str().unwrap(), "--steps", "1", "--eval-samples", "1"]);
    let ec_model = format!("ec=ec:{}", ec.with_extension("weights.safetensors").display());
    let out = rendernet(&["frontier", "--data", data.to_str().unwrap(), "--samples", "1", "--repeat", "1", "--model", &model, "--model", &ec_model, "--out", png.to_str().unwrap(), "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    let models = j["models"].as_array().unwrap();
    assert_eq!(models.len(), 5, "the shipped nano, tiny and base, the copy and EC: {out}");
    assert_eq!((models[1]["arch"].as_str(), models[1]["train_images"].as_u64()), (Some("RenderNet"), Some(76000)), "{out}");
    assert_eq!((models[2]["arch"].as_str(), models[2]["train_images"].as_u64()), (Some("RenderNet"), Some(78000)), "{out}");
    assert_eq!((models[4]["arch"].as_str(), models[4]["train_images"].as_u64()), (Some("EC baselines"), Some(1)), "{out}");
    assert!(models[4]["train_seconds"].as_f64().is_some_and(|v| v >= 0.0), "{out}");
    // EC renders whole frames only: its cropped time is its whole-frame time.
    assert_eq!(models[4]["forward_ms_cropped"], models[4]["forward_ms"], "{out}");
    assert!(models[1]["forward_ms_cropped"].as_f64().is_some_and(|v| v > 0.0), "{out}");
    for m in models {
        assert!(m["object_psnr"].as_f64().is_some_and(|v| v.is_finite() && v > 0.0), "{m}");
        assert!(m["forward_ms"].as_f64().is_some_and(|v| v > 0.0), "{m}");
    }
    assert_eq!(models[1]["object_psnr"], models[3]["object_psnr"], "the same weights score the same");
    assert!(j["reference"]["forward_ms"].as_f64().is_some_and(|v| v > 0.0) && j["fma_ceiling_gflops"].as_f64().is_some_and(|v| v > 0.0), "{out}");
    assert!(png.exists());
    let bad = Command::new(env!("CARGO_BIN_EXE_rendernet")).args(["frontier", "--data", data.to_str().unwrap(), "--model", "nano", "--out", png.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("--model nano") && err.contains("LABEL=PRESET:WEIGHTS"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A training step records the same dispatches every time, so after the first one it must
/// create no GPU buffer, texture or bind group (the executor's memo hands back last step's),
/// and the reuse must not change a single bit: an executor that makes everything fresh (and
/// zeroed) every step ends with identical weights, so no kernel reads scratch it never wrote.
#[test]
fn training_steps_after_the_first_create_no_gpu_objects() {
    use rendernet::graph::Executor;
    use rendernet::nn::camera::{light_values, pose_for_view};
    use rendernet::ops::adam::Adam;
    let gpu = Gpu::new().unwrap();
    let p = Preset::nano();
    let (n, hw) = (2, [16, 12]);
    let net = RenderNet::build(&p, Head::Phong(phong_of(&Light::default())), n, hw, true).unwrap();
    let size = |v| net.graph.info(v).shape.iter().product::<usize>();
    let ramp = |len: usize, k: usize| (0..len).map(|i| ((i * k) % 17) as f32 / 16.0).collect::<Vec<f32>>();
    let grid: Vec<f32> = ramp(size(net.grid), 7).iter().map(|&v| if v > 0.6 { 1.0 } else { 0.0 }).collect();
    let pose: Vec<f32> = (0..n).flat_map(|i| pose_for_view(&View { azimuth: 30.0 + 50.0 * i as f64, ..View::default() }, p.input, p.cam, Some([24, 26, 16, 12]))).collect();
    let light: Vec<f32> = (0..n).flat_map(|_| light_values(&Light::default())).collect();
    let train = |steps: usize, reuse: bool| {
        let mut ex = Executor::new(&gpu, net.graph.clone(), 5).unwrap();
        ex.reuse_gpu_objects(reuse);
        ex.feed(&gpu, net.grid, &grid).unwrap();
        ex.feed(&gpu, net.pose, &pose).unwrap();
        ex.feed(&gpu, net.light.unwrap(), &light).unwrap();
        for (k, (_, v)) in net.targets.iter().enumerate() {
            ex.feed(&gpu, *v, &ramp(size(*v), 3 + k)).unwrap();
        }
        let stats: Vec<_> = (0..steps).map(|_| ex.train_step(&gpu, net.loss.unwrap(), &Adam::new(1e-3)).unwrap()).collect();
        let weights: Vec<Vec<f32>> = net.graph.params().into_iter().map(|v| ex.read(&gpu, v).unwrap()).collect();
        (stats, weights)
    };
    let (stats, weights) = train(3, true);
    assert!(stats[0].created > 0, "the first step must create its scratch and bind groups: {:?}", stats[0]);
    for (k, s) in stats.iter().enumerate().skip(1) {
        assert_eq!(s.created, 0, "step {} created GPU objects: {s:?}", k + 1);
        assert_eq!((s.dispatches, s.submits), (stats[0].dispatches, 1), "step {}: {s:?}", k + 1);
    }
    assert!(stats[0].scratch_bytes > 0, "{:?}", stats[0]);
    let (fresh_stats, fresh) = train(3, false);
    assert!(fresh_stats[2].created > 0, "{:?}", fresh_stats[2]);
    assert!(weights == fresh, "reusing scratch and bind groups changed the result");

}

/// `Executor::profile` times every op of a run in schedule order: each forward node, then
/// the backward of the nodes on the loss's path (loss first), then Adam; it changes no result
/// and no dispatch count, and turning it off leaves no times behind.
#[test]
fn profiled_runs_time_every_op_in_schedule_order() {
    use rendernet::graph::{Executor, profile::by_kind};
    use rendernet::ops::adam::Adam;
    let gpu = Gpu::new().unwrap();
    if !gpu.has_timestamps() {
        eprintln!("skipped: {} has no timestamps inside compute passes", gpu.info.name);
        return;
    }
    let net = RenderNet::build(&Preset::nano(), Head::Phong(phong_of(&Light::default())), 1, [16, 16], true).unwrap();
    let mut ex = Executor::new(&gpu, net.graph.clone(), 5).unwrap();
    ex.keep(net.image);
    ex.train_step(&gpu, net.loss.unwrap(), &Adam::new(1e-3)).unwrap();
    let unprofiled = ex.train_step(&gpu, net.loss.unwrap(), &Adam::new(1e-3)).unwrap().dispatches;
    ex.forward(&gpu).unwrap();
    let plain = ex.read(&gpu, net.image).unwrap();
    ex.profile(&gpu, true).unwrap();
    ex.forward(&gpu).unwrap();
    assert_eq!(ex.read(&gpu, net.image).unwrap(), plain, "profiling changed the image");
    let names: Vec<String> = ex.op_times().iter().map(|t| t.name.clone()).collect();
    let forward: Vec<String> = net.graph.nodes().iter().map(|n| format!("{} forward", n.name)).collect();
    assert_eq!(names, forward);
    let kinds: Vec<&str> = ex.op_times().iter().map(|t| t.kind.as_str()).collect();
    assert_eq!(kinds, net.graph.nodes().iter().map(|n| n.op.name()).collect::<Vec<_>>());
    let stats = ex.train_step(&gpu, net.loss.unwrap(), &Adam::new(1e-3)).unwrap();
    // The profiler's own empty dispatches (after each timestamp) are nobody's work.
    assert_eq!(stats.dispatches, unprofiled, "profiling changed the step's dispatch count");
    let t = ex.op_times();
    // Every dispatch of the step is counted against one op, and every op dispatches but the
    // heads' channel ranges, views of the joint head's output in the forward (16x16 planes),
    // and the heads' weights and biases, views of the parameters (graph/flat.rs) both ways.
    // Only the weight packings ahead of the step (one dispatch where the convs run on
    // textures, ops/conv_pack_jobs.rs) are outside every op.
    let outside = stats.dispatches.checked_sub(t.iter().map(|t| t.dispatches).sum::<u64>()).expect("more dispatches counted against ops than made");
    assert_eq!(outside, u64::from(on_textures(&gpu)), "dispatches outside the ops: {t:?}");
    let view = |t: &&rendernet::graph::profile::OpTime| t.kind == "narrow" && t.name.ends_with(" forward") || t.kind == "concat_axis0";
    assert!(t.iter().filter(|t| !view(t)).all(|t| t.dispatches > 0), "{t:?}");
    assert!(t.iter().filter(view).all(|t| t.dispatches == 0), "{t:?}");
    assert!(t.iter().all(|t| t.ns.is_finite() && t.ns >= 0.0), "{t:?}");
    assert_eq!(t[..forward.len()].iter().map(|t| t.name.clone()).collect::<Vec<_>>(), forward);
    let backward: Vec<&str> = t[forward.len()..t.len() - 1].iter().map(|t| t.name.as_str()).collect();
    assert_eq!(backward.first(), Some(&"loss backward"), "{backward:?}");
    assert_eq!(backward.last(), Some(&"enc3d.conv1 backward"), "{backward:?}");
    assert!(backward.iter().all(|n| n.ends_with(" backward")), "{backward:?}");
    assert_eq!(t.last().unwrap().name, "adam");
    let total: f64 = t.iter().map(|t| t.ns).sum();
    let kinds = by_kind(t);
    assert_eq!(kinds.iter().map(|k| k.2).sum::<usize>(), t.len());
    assert_eq!(kinds.iter().map(|k| k.3).sum::<u64>() + outside, stats.dispatches);
    assert!((kinds.iter().map(|k| k.1).sum::<f64>() - total).abs() <= 1e-6 * total.max(1.0));
    assert!(kinds.windows(2).all(|w| w[0].1 >= w[1].1), "kinds not sorted slowest first");
    ex.profile(&gpu, false).unwrap();
    ex.forward(&gpu).unwrap();
    assert!(ex.op_times().is_empty());
}

/// Whether the convs run on the texture kernels here (a CPU adapter where they measured
/// faster), as the first layer's shape shows.
fn on_textures(gpu: &Gpu) -> bool {
    use rendernet::ops::conv::{Conv, ConvKernel, Padding};
    Conv::conv3d([5, 5, 5], [2, 2, 2], Padding::Same).fuses_prelu(ConvKernel::Auto, gpu, &[1, 1, 9, 10, 11], &[8, 1, 5, 5, 5]).unwrap()
}

/// The EC baselines: whole 128 px frames from a 32^3 grid, pose and light; a camera-grid
/// crop is refused by name (their fully-connected layers see the whole frame); an image head
/// takes no light; both fit the < 5 MB budget for shipped weights.
#[test]
fn ec_baselines_build_whole_frames_only() {
    let head = Head::Phong(phong_of(&Light::default()));
    for p in [Preset::ec(), Preset::ec_deep()] {
        let net = RenderNet::build(&p, head, 2, [p.cam, p.cam], true).unwrap();
        assert_eq!(net.graph.info(net.image).shape, [2, 3, 128, 128], "{}", p.name);
        assert!(net.light.is_some() && net.maps.is_none());
        assert_eq!(net.targets.iter().map(|t| t.0.as_str()).collect::<Vec<_>>(), ["phong"]);
        let params: usize = net.graph.params().iter().map(|&v| net.graph.info(v).shape.iter().product::<usize>()).sum();
        assert!(params * 4 < 5_000_000, "{}: {params} parameters", p.name);
        let e = RenderNet::build(&p, head, 1, [32, 32], false).err().expect("crop refused").to_string();
        assert!(e.contains("whole 128x128 frames"), "{e}");
        let ao = RenderNet::build(&p, Head::Image(1), 1, [p.cam, p.cam], false).unwrap();
        assert!(ao.light.is_none());
        assert_eq!(ao.graph.info(ao.image).shape, [1, 1, 128, 128]);
    }
    let deep = RenderNet::build(&Preset::ec_deep(), head, 1, [64, 64], false).unwrap();
    assert!(deep.graph.value("pose.fc.weight").is_some() && deep.graph.value("dec.0.res1.conv2.weight").is_some());
    let ec = RenderNet::build(&Preset::ec(), head, 1, [64, 64], false).unwrap();
    assert!(ec.graph.value("pose.fc.weight").is_none() && ec.graph.value("dec.0.conv.weight").is_some());
}

/// EC and EC-deep at toy sizes: the image depends on the pose (its features reach the
/// decoder), and Adam on one sample lowers the loss, so every layer's gradient is wired.
#[test]
fn ec_baselines_see_the_pose_and_learn() {
    use rendernet::graph::{Executor, Graph};
    use rendernet::nn::ec::{EcSizes, build_on, pose_features};
    use rendernet::ops::adam::Adam;
    let gpu = Gpu::new().unwrap();
    let toy = EcSizes { enc: [2, 3, 4, 4], latent: 5, embed: 0, fc: 12, start: 2, dec: vec![6, 4, 3], deep: false };
    for s in [toy.clone(), EcSizes { embed: 4, deep: true, ..toy }] {
        let mut g = Graph::new();
        let grid = g.input("grid", &[1, 1, 16, 16, 16]).unwrap();
        let net = build_on(g, grid, &s, 16, Head::Phong(phong_of(&Light::default())), true).unwrap();
        assert_eq!(net.graph.info(net.image).shape, [1, 3, 8, 8]);
        let mut ex = Executor::new(&gpu, net.graph.clone(), 7).unwrap();
        ex.keep(net.image);
        let occ: Vec<f32> = (0..16 * 16 * 16).map(|i| ((i * 37 % 11) < 4) as u8 as f32).collect();
        ex.feed(&gpu, net.grid, &occ).unwrap();
        ex.feed(&gpu, net.light.unwrap(), &[0.3, 0.5, 0.8, 1.0, 1.0, 1.0]).unwrap();
        let target: Vec<f32> = (0..3 * 64).map(|i| if (i * 5) % 7 < 3 { 0.05 } else { 0.95 }).collect();
        ex.feed(&gpu, net.targets[0].1, &target).unwrap();
        let mut image_at = |az: f32| {
            ex.feed(&gpu, net.pose, &pose_features([1.0, az, -0.8, 0.0, 0.0, 0.0])).unwrap();
            ex.forward(&gpu).unwrap();
            ex.read(&gpu, net.image).unwrap()
        };
        let (a, b) = (image_at(0.3), image_at(-2.5));
        let moved = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
        assert!(moved > 1e-5, "deep={}: the pose does not reach the image ({moved})", s.deep);
        let loss = net.loss.unwrap();
        let first = ex.train_step(&gpu, loss, &Adam::new(1e-2)).unwrap().loss.unwrap();
        let mut last = first;
        for _ in 0..40 {
            last = ex.train_step(&gpu, loss, &Adam::new(1e-2)).unwrap().loss.unwrap();
        }
        assert!(last < 0.8 * first, "deep={}: loss {first} -> {last} after 40 steps", s.deep);
    }
}

/// A coloured network started from grey weights (`train --init`): the first conv's
/// occupancy channel and the albedo head take the grey tensors (colour channels zero, albedo
/// replicated into R, G and B), so on a white grid it renders exactly what the grey network
/// renders.
#[test]
fn a_colour_network_widened_from_grey_weights_renders_as_the_grey_one() {
    use rendernet::graph::Executor;
    use rendernet::nn::camera::{input_values_with, light_values, pose_for_view};
    let gpu = Gpu::new().unwrap();
    let head = Head::Phong(phong_of(&Light::default()));
    let grid = rendernet::voxel::bunny().resample_to(32).unwrap();
    let view = View::default();
    let image = |p: Preset| {
        let net = RenderNet::build(&p, head, 1, [20, 24], false).unwrap();
        let mut ex = Executor::new(&gpu, net.graph.clone(), 1).unwrap();
        let r = ex.load_params_matching(&gpu, TINY_PHONG_WEIGHTS, "tiny-phong").unwrap();
        ex.feed(&gpu, net.grid, &input_values_with(&grid, p.in_channels())).unwrap();
        ex.feed(&gpu, net.pose, &pose_for_view(&view, p.input, p.cam, Some([22, 20, 20, 24]))).unwrap();
        ex.feed(&gpu, net.light.unwrap(), &light_values(&Light::default())).unwrap();
        ex.keep(net.image);
        ex.forward(&gpu).unwrap();
        (r, ex.read(&gpu, net.image).unwrap())
    };
    let (grey_report, grey) = image(Preset::tiny());
    assert!(grey_report.widened.is_empty() && grey_report.fresh.is_empty(), "{grey_report:?}");
    let (report, colour) = image(Preset::tiny().with_colour());
    assert_eq!(report.widened, ["enc3d.conv1.weight", "head.albedo.weight", "head.albedo.bias"]);
    // The colour path starts at zero, so it changes nothing until trained.
    assert_eq!(report.fresh, ["colour.up.0.weight", "colour.up.0.bias"], "{report:?}");
    assert!(grey.iter().any(|&v| v > 0.1), "the grey network drew nothing");
    let worst = grey.iter().zip(&colour).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    // Same sums in the same order (the grey input's padded channels were zero too).
    assert!(worst <= 1e-5, "widened colour network differs from the grey one by {worst}");
}

/// Coloured voxels: a colour preset takes 4 input channels and predicts an RGB albedo, and
/// the colour reaches it: trained on the same cube painted red and painted blue, the
/// predicted albedo is redder for the red cube and bluer for the blue one. Weights with a
/// 4-channel first conv are recognised as colour weights.
#[test]
fn coloured_voxels_reach_the_albedo_head() {
    use rendernet::data::Sample;
    use rendernet::graph::Executor;
    use rendernet::ops::adam::Adam;
    use rendernet::train::batch::Batch;
    use rendernet::voxel::VoxelGrid;
    let gpu = Gpu::new().unwrap();
    let toy = Preset { name: "toy", input: 16, cam: 16, c3: [4, 4], res3d: 0, proj: 8, c2: 8, res2d: 0, up: vec![6], ..Preset::tiny() }.with_colour();
    let (n, side) = (16usize, 16usize);
    let occ: Vec<f32> = (0..n * n * n).map(|i| [i / (n * n), (i / n) % n, i % n].iter().all(|&x| (3..13).contains(&x)) as u8 as f32).collect();
    let painted = |rgb: [f32; 3]| VoxelGrid::new([n; 3], occ.clone()).unwrap().with_colour(rgb.iter().flat_map(|&c| vec![c; n * n * n]).collect()).unwrap();
    let (view, light) = (View { azimuth: 35.0, elevation: 60.0, radius: 1.8 }, Light::default());
    let reference = reference::RayMarcher::new(&gpu);
    let sample = |grid: VoxelGrid| {
        let mut images = std::collections::BTreeMap::new();
        for (name, shader) in [("phong", Shader::Phong), ("normal", Shader::Normal), ("albedo", Shader::Albedo), ("mask", Shader::Mask)] {
            let mut img = reference.render(&gpu, &grid, &view, &light, shader, side as u32).unwrap();
            if shader == Shader::Mask {
                img.channels = 1;
                img.data.truncate(side * side);
            }
            images.insert(name.to_string(), img);
        }
        Sample { grid, view, light, shape_id: 0, images }
    };
    let (red, blue) = (sample(painted([0.9, 0.15, 0.1])), sample(painted([0.1, 0.2, 0.9])));
    let net = RenderNet::build(&toy, Head::Phong(phong_of(&light)), 2, [16, 16], true).unwrap();
    assert_eq!(net.graph.info(net.grid).shape, [2, 4, 16, 16, 16]);
    let albedo = net.maps.unwrap()[1];
    assert_eq!(net.graph.info(albedo).shape, [2, 3, 16, 16]);
    let names: Vec<String> = net.targets.iter().map(|(n, _)| n.clone()).collect();
    let mut b = Batch::default();
    for s in [&red, &blue] {
        b.push(&toy, s, [0, 0, 16, 16], &names).unwrap();
    }
    let mut ex = Executor::new(&gpu, net.graph.clone(), 3).unwrap();
    ex.keep(albedo);
    ex.feed(&gpu, net.grid, &b.grid).unwrap();
    ex.feed(&gpu, net.pose, &b.pose).unwrap();
    ex.feed(&gpu, net.light.unwrap(), &b.light).unwrap();
    for (name, v) in &b.targets {
        ex.feed(&gpu, net.targets.iter().find(|(n, _)| n == name).unwrap().1, v).unwrap();
    }
    for _ in 0..150 {
        ex.train_step(&gpu, net.loss.unwrap(), &Adam::new(1e-2)).unwrap();
    }
    ex.forward(&gpu).unwrap();
    let a = ex.read(&gpu, albedo).unwrap();
    // Mean of each albedo channel over the cube's pixels (the mask), per sample.
    let mask = &red.images["mask"].data;
    let px = side * side;
    let mean = |k: usize, c: usize| {
        let on: Vec<usize> = (0..px).filter(|&i| mask[i] > 0.5).collect();
        on.iter().map(|&i| a[(k * 3 + c) * px + i]).sum::<f32>() / on.len() as f32
    };
    let (red_r, red_b, blue_r, blue_b) = (mean(0, 0), mean(0, 2), mean(1, 0), mean(1, 2));
    eprintln!("albedo: red cube r {red_r:.3} b {red_b:.3}; blue cube r {blue_r:.3} b {blue_b:.3}");
    assert!(red_r - blue_r > 0.2 && blue_b - red_b > 0.2, "red cube r {red_r} b {red_b}; blue cube r {blue_r} b {blue_b}");
    let file = std::env::temp_dir().join(format!("rendernet-colour-{}.safetensors", std::process::id()));
    ex.save_params(&gpu, &file).unwrap();
    let bytes = std::fs::read(&file).unwrap();
    let _ = std::fs::remove_file(&file);
    assert!(rendernet::nn::render::weights_take_colour(&bytes, "toy").unwrap());
    assert!(!rendernet::nn::render::weights_take_colour(TINY_PHONG_WEIGHTS, "tiny").unwrap());
}

/// The coloured path from the command line: `dataset --colour`, `train` (which switches the
/// preset to colour), `eval` on the coloured test split, and `render` of a painted `.vox`
/// with those weights (recognised as colour weights), beside the reference.
#[test]
fn coloured_dataset_trains_evaluates_and_renders_a_vox() {
    let dir = std::env::temp_dir().join(format!("rendernet-colour-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (data, ckpt, vox, png) = (dir.join("data"), dir.join("c.ckpt"), dir.join("chair.vox"), dir.join("c.png"));
    let d = data.to_str().unwrap();
    rendernet(&["dataset", "--colour", "--count", "2", "--views", "1", "--res", "16", "--image", "128", "--seed", "4", "--out", d]);
    rendernet(&["train", "--data", d, "--out", ckpt.to_str().unwrap(), "--steps", "2", "--crop", "16", "--eval-samples", "1"]);
    let w = ckpt.with_extension("weights.safetensors");
    let bytes = std::fs::read(&w).unwrap();
    assert!(rendernet::nn::render::weights_take_colour(&bytes, "c").unwrap(), "train did not switch to the colour preset");
    let out = rendernet(&["eval", "--weights", w.to_str().unwrap(), "--data", d, "--json"]);
    assert!(out.contains("object_psnr_mean"), "{out}");
    let shape = rendernet::voxel::Family::Chair.generate(5);
    rendernet::voxel::vox::write(&shape.to_coloured_grid(24, 5).unwrap(), &vox).unwrap();
    let out = rendernet(&["render", "--voxels", vox.to_str().unwrap(), "--weights", w.to_str().unwrap(), "--size", "64", "--compare", "--out", png.to_str().unwrap()]);
    assert!(out.contains("object PSNR"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}
