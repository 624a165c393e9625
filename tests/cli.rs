//! The `rendernet` binary as a user meets it: `info` works, and with no matching adapter it
//! fails with an actionable message instead of a panic; `render --compare` and `eval` print
//! every score beside an all-black image's; bad flags, output names, weights files and
//! WGPU_BACKEND values fail early with messages that name them.

use std::process::Command;

fn rendernet() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rendernet"))
}

#[test]
fn info_prints_adapter_and_limits() {
    let out = rendernet().arg("info").output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "info failed: {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("adapter:"), "{stdout}");
    assert!(stdout.contains("max_storage_buffer_binding_size"), "{stdout}");
}

#[test]
fn no_adapter_is_a_clear_error_not_a_panic() {
    let out = rendernet()
        .arg("info")
        .env("WGPU_ADAPTER_NAME", "no-such-adapter-anywhere")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.contains("no GPU adapter found"), "{stderr}");
    assert!(stderr.contains("no-such-adapter-anywhere"), "{stderr}");
    // Adapters exist but the name filter rejects them: the advice is about the filter, and
    // about installing lavapipe only where it is not already among the adapters present.
    assert!(stderr.contains("Set WGPU_ADAPTER_NAME"), "{stderr}");
    let present = stderr.split("present but not matching:").nth(1).and_then(|r| r.split("). ").next()).unwrap_or("");
    if present.contains("llvmpipe") {
        assert!(!stderr.contains("apt-get"), "lavapipe is present, yet: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `bench --json` carries, per row, the kernel's speed and its fraction of the FMA ceiling
/// timed between that row's own samples, with the adapter and CPU; the fraction is the ratio
/// of the two (a row computed against another number would fail), and each row's ceiling is
/// within 3x of the run's start ceiling (a ceiling timed wrong by a factor would fail).
#[test]
fn bench_json_reports_speed_against_the_same_run_ceiling() {
    let out = rendernet()
        .args(["bench", "--json", "--filter", "16->3", "--kernel", "texture,fast", "--repeat", "1"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench failed: {stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("bench --json prints JSON");
    let ceiling = v["fma_ceiling_gflops"].as_f64().expect("fma_ceiling_gflops");
    assert!(ceiling > 0.0, "{v}");
    assert!(v["adapter"].as_str().is_some_and(|a| !a.is_empty()), "{v}");
    let rows = v["rows"].as_array().expect("rows");
    // The 16->3 head: 3 passes x 2 kernels.
    assert_eq!(rows.len(), 6, "{v}");
    for r in rows {
        let (g, f) = (r["gflops"].as_f64().unwrap(), r["fraction_of_fma_ceiling"].as_f64().unwrap());
        let rc = r["fma_ceiling_gflops"].as_f64().expect("a row's fma_ceiling_gflops");
        assert!(rc > ceiling / 3.0 && rc < ceiling * 3.0, "row ceiling {rc} against the run's {ceiling}: {r}");
        assert!(g > 0.0 && (f - g / rc).abs() < 1e-9 * g.max(1.0), "{r}");
        assert!(["fast", "texture"].contains(&r["kernel"].as_str().unwrap()), "{r}");
    }
}

/// `bench --pass` keeps that pass's rows alone (here the 16->3 head's weight gradient), and
/// refuses a pass it does not time, naming those it does.
#[test]
fn bench_times_one_pass_alone() {
    let out = rendernet()
        .args(["bench", "--json", "--filter", "16->3", "--pass", "backward_weight", "--kernel", "texture", "--repeat", "1"])
        .output()
        .unwrap();
    assert!(out.status.success(), "bench failed: {}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("bench --json prints JSON");
    let rows: Vec<&str> = v["rows"].as_array().expect("rows").iter().map(|r| r["pass"].as_str().unwrap()).collect();
    assert_eq!(rows, ["backward_weight"], "{v}");
    // The whole-network rows too: the forward's two, not the training steps.
    let out = rendernet().args(["bench", "--json", "--filter", "rendernet", "--pass", "forward", "--repeat", "1"]).output().unwrap();
    assert!(out.status.success(), "bench failed: {}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("bench --json prints JSON");
    let rows: Vec<&str> = v["rows"].as_array().expect("rows").iter().map(|r| r["pass"].as_str().unwrap()).collect();
    assert_eq!(rows, ["forward", "forward"], "{v}");
    let refused = rendernet().args(["bench", "--pass", "sideways"]).output().unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("backward_input") && err.contains("train_step"), "{err}");
    // --profile times whole-network rows only, which a kernel pass leaves out.
    let refused = rendernet().args(["bench", "--pass", "backward_weight", "--profile"]).output().unwrap();
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && err.contains("--pass backward_weight"), "{err}");
}

/// `bench --filter resample`: the resampling's passes per way of reading the grid, the grid
/// gradient (buffer only) left out when `--kernel` asks for textures alone.
#[test]
fn bench_times_the_resampling_both_ways() {
    let rows = |kernels: &str| {
        let out = rendernet().args(["bench", "--json", "--filter", "64x32x32", "--kernel", kernels, "--repeat", "1"]).output().unwrap();
        assert!(out.status.success(), "bench failed: {}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("bench --json prints JSON");
        let rows = v["rows"].as_array().expect("rows").clone();
        assert!(rows.iter().all(|r| r["gflops"].as_f64().is_some_and(|g| g > 0.0)), "{v}");
        // The shape also matches the training-step conv rows; keep the resampling's.
        let rows: Vec<String> = rows.iter().filter(|r| r["op"] == "resample").map(|r| format!("{} {}", r["pass"].as_str().unwrap(), r["kernel"].as_str().unwrap())).collect();
        rows
    };
    let both = ["forward fast", "forward texture", "backward_input fast", "backward_pose fast", "backward_pose texture"];
    assert_eq!(rows("fast,texture"), both);
    assert_eq!(rows("texture"), ["forward texture", "backward_pose texture"]);
}

/// `bench --operands --json`: one row per kind of operand, the plain FMA first with nothing
/// beyond itself, every cost finite and positive, and each row's extra cost counted in
/// ceiling FMAs by one same-run factor, an empty dispatch's cost beside them; with --filter
/// it is refused (it times no kernels).
#[test]
fn bench_operands_prices_each_operand_against_the_fma() {
    let out = rendernet().args(["bench", "--operands", "--json", "--repeat", "1"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench --operands failed: {stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("bench --operands --json prints JSON");
    assert!(v["fma_ceiling_gflops"].as_f64().is_some_and(|c| c > 0.0), "{v}");
    let rows = v["operands"].as_array().expect("operands");
    assert_eq!(rows.len(), 18, "{v}");
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k} in {r}"));
    assert_eq!(rows[0]["operand"], "none (plain FMA)", "{v}");
    assert_eq!(f(&rows[0], "extra_ns"), 0.0, "{v}");
    let per_ns = f(&rows[1], "extra_in_fmas") / f(&rows[1], "extra_ns");
    for r in rows {
        assert!(f(r, "ns_per_vector") > 0.0, "{r}");
        assert!((f(r, "ns_per_vector") - f(&rows[0], "ns_per_vector") - f(r, "extra_ns")).abs() < 1e-9, "{r}");
        assert!((f(r, "extra_in_fmas") - f(r, "extra_ns") * per_ns).abs() < 1e-6 * f(r, "extra_in_fmas").abs().max(1.0), "{r}");
    }
    // An empty dispatch's time, and the same time in ceiling FMAs (2 FLOPs each).
    let (us, fmas) = (v["dispatch_us"].as_f64().expect("dispatch_us"), v["dispatch_in_fmas"].as_f64().expect("dispatch_in_fmas"));
    assert!(us > 0.0 && us < 1e5, "{v}");
    let ceiling = v["fma_ceiling_gflops"].as_f64().unwrap();
    assert!((fmas - us * ceiling * 1e3 / 2.0).abs() < 1e-6 * fmas, "{v}");
    let refused = rendernet().args(["bench", "--operands", "--filter", "conv3d"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && stderr.contains("--operands") && stderr.contains("--filter"), "{stderr}");
}

/// `bench --profile` times the whole-network rows; a filter that leaves them out is refused.
#[test]
fn bench_profile_needs_the_whole_network_rows() {
    let out = rendernet().args(["bench", "--profile", "--filter", "conv3d"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("--profile") && stderr.contains("conv3d"), "{stderr}");
}

#[test]
fn bench_rejects_an_unknown_kernel_by_name() {
    let out = rendernet().args(["bench", "--kernel", "fastest"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("--kernel") && stderr.contains("fastest"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Runs `rendernet args`, asserts success, returns stdout.
fn run_ok(args: &[&str]) -> String {
    let out = rendernet().args(args).output().unwrap();
    let (o, e) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "rendernet {args:?} failed:\n{o}\n{e}");
    o.into_owned()
}

/// The number after `label` in `line`, and the one after the next "all-black ".
fn score(line: &str, label: &str) -> (f64, f64) {
    let num = |s: &str| s.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-')).next().unwrap().parse::<f64>().unwrap();
    let rest = &line[line.find(label).unwrap_or_else(|| panic!("no '{label}' in {line}")) + label.len()..];
    let black = &rest[rest.find("all-black ").unwrap_or_else(|| panic!("no floor after '{label}' in {line}")) + 10..];
    (num(rest), num(black))
}

/// `render --compare` prints the four scores, each beside the all-black floor. The floor's
/// object PSNR is below its full-frame PSNR (the box cuts most of the black background it
/// gets for free) and its IoU is 0; the network draws a silhouette that overlaps the truth's.
#[test]
fn render_compare_prints_every_score_beside_the_black_floor() {
    let png = std::env::temp_dir().join(format!("rendernet-cli-compare-{}.png", std::process::id()));
    let out = run_ok(&["render", "--compare", "--shape", "chair", "--seed", "3", "--resolution", "32", "--size", "64", "--out", png.to_str().unwrap()]);
    let _ = std::fs::remove_file(&png);
    let line = out.lines().find(|l| l.starts_with("against the reference renderer:")).unwrap_or_else(|| panic!("{out}"));
    let (full, full0) = score(line, "full-frame PSNR ");
    let (obj, obj0) = score(line, "object PSNR ");
    let (ssim, ssim0) = score(line, "SSIM ");
    let (iou, iou0) = score(line, "mask IoU ");
    assert!(obj0 < full0 - 1.0 && obj < full, "{line}");
    assert!(iou0 == 0.0 && iou > 0.3 && iou <= 1.0, "{line}");
    assert!(ssim > ssim0 && ssim <= 1.0 && ssim0 > -1.0, "{line}");
}

/// `weights/tiny-phong-varied.safetensors` (a fine-tune of the embedded tiny, not embedded:
/// `--weights` reads it) loads as tiny reading 64^3 grids and draws the default bunny better
/// than the embedded tiny by at least 0.5 dB of object PSNR (at 64 px: measured 19.0 against
/// 17.8 dB), far above the all-black floor (7.6): a corrupted file, other weights of another
/// preset or the embedded tiny's copied in its place fail.
#[test]
fn the_varied_fine_tune_renders_the_bunny_better_than_tiny() {
    let w = concat!(env!("CARGO_MANIFEST_DIR"), "/weights/tiny-phong-varied.safetensors");
    let (_, meta) = rendernet::graph::params::parse_safetensors(&std::fs::read(w).unwrap(), w).unwrap();
    assert_eq!((meta.get("preset").map(String::as_str), meta.get("input").map(String::as_str)), (Some("tiny"), Some("64")), "{meta:?}");
    let png = std::env::temp_dir().join(format!("rendernet-cli-varied-{}.png", std::process::id()));
    let object_psnr = |extra: &[&str]| {
        let mut args = vec!["render", "--compare", "--size", "64", "--out", png.to_str().unwrap()];
        args.extend_from_slice(extra);
        let out = run_ok(&args);
        let line = out.lines().find(|l| l.starts_with("against the reference renderer:")).unwrap_or_else(|| panic!("{out}"));
        score(line, "object PSNR ")
    };
    let (varied, black) = object_psnr(&["--weights", w]);
    let (tiny, _) = object_psnr(&["--preset", "tiny"]);
    let _ = std::fs::remove_file(&png);
    assert!(varied > black + 8.0 && varied > tiny + 0.5, "varied {varied} dB, tiny {tiny}, all-black {black}");
}

/// `eval --json` is valid JSON with the original keys and every score's mean, interval and
/// all-black floor; per-shape entries carry full-frame and object PSNR. The text form lists
/// the four scores. Uses the embedded weights on a two-shape dataset, so it runs in seconds.
#[test]
fn eval_reports_every_score_with_its_black_floor() {
    let dir = std::env::temp_dir().join(format!("rendernet-cli-eval-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (data, weights) = (dir.join("data"), dir.join("tiny.safetensors"));
    std::fs::write(&weights, rendernet::nn::render::TINY_PHONG_WEIGHTS).unwrap();
    let (d, w) = (data.to_str().unwrap(), weights.to_str().unwrap());
    run_ok(&["dataset", "--count", "2", "--views", "2", "--res", "16", "--image", "128", "--seed", "3", "--out", d]);
    let out = run_ok(&["eval", "--weights", w, "--data", d, "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("eval --json is not JSON ({e}): {out}"));
    let num = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("no number '{k}' in {v}"));
    assert_eq!(v["samples"].as_u64(), Some(2), "{v}");
    for k in ["psnr_mean", "psnr_ci95", "object_psnr_mean", "object_psnr_ci95", "ssim_ci95", "iou_ci95", "black_image_ssim"] {
        assert!(num(k).is_finite(), "{k}: {v}");
    }
    // The all-black floor: fewer dB inside the object box than over the frame, IoU 0.
    assert!(num("black_image_object_psnr") < num("black_image_psnr") - 1.0, "{v}");
    assert_eq!(num("black_image_iou"), 0.0, "{v}");
    assert!((0.0..=1.0).contains(&num("iou_mean")) && num("ssim_mean") <= 1.0, "{v}");
    let shapes = v["per_shape"].as_object().expect("per_shape");
    assert!(!shapes.is_empty(), "{v}");
    for s in shapes.values() {
        assert!(s["psnr"].as_f64().is_some() && s["object_psnr"].as_f64().is_some(), "{s}");
    }
    let text = run_ok(&["eval", "--weights", w, "--data", d]);
    for row in ["full-frame PSNR", "object PSNR", "SSIM", "mask IoU"] {
        assert!(text.lines().any(|l| l.contains(row) && l.contains("±") && l.contains("all-black")), "{row}: {text}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `eval --reference-on-input` scores the reference renderer on each sample's input grid:
/// exact (to the targets' u8 rounding, ~59 dB) when the targets were drawn from that very
/// grid (`--truth-res` = `--res`), and far from it when they come from a grid twice as fine.
/// JSON carries it under `reference_on_input`; the text adds a column.
#[test]
fn eval_scores_the_reference_renderer_on_the_input_grid() {
    let dir = std::env::temp_dir().join(format!("rendernet-cli-eval-ref-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let reference = |truth_res: &str| {
        let data = dir.join(format!("data-{truth_res}"));
        let d = data.to_str().unwrap();
        run_ok(&["dataset", "--count", "2", "--views", "2", "--res", "16", "--truth-res", truth_res, "--image", "128", "--seed", "3", "--out", d]);
        let out = run_ok(&["eval", "--data", d, "--json", "--reference-on-input"]);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("not JSON ({e}): {out}"));
        let r = &v["reference_on_input"];
        assert_eq!(r["samples"].as_u64(), Some(2), "{v}");
        (r["psnr_mean"].as_f64().unwrap(), r["object_psnr_mean"].as_f64().unwrap(), d.to_string())
    };
    let (same, same_object, _) = reference("16");
    assert!(same > 50.0 && same_object > 45.0, "reference on the truth's own grid: {same} / {same_object} dB");
    let (finer, finer_object, d) = reference("32");
    assert!(finer < 40.0 && finer_object < same_object - 10.0, "reference on a grid half the truth's side: {finer} / {finer_object} dB");
    let text = run_ok(&["eval", "--data", &d, "--reference-on-input"]);
    assert!(text.lines().any(|l| l.contains("object PSNR") && l.contains("reference on the input grid")), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `eval` on images larger than the network draws scores them as `render` draws them (at the
/// trained side, upscaled: a score, not an error); smaller images are refused by size.
#[test]
fn eval_scores_larger_images_upscaled_and_refuses_smaller_ones() {
    let dir = scratch("eval-sizes");
    let score = |image: &str| {
        let data = dir.join(format!("data-{image}"));
        let d = data.to_str().unwrap().to_string();
        run_ok(&["dataset", "--count", "1", "--views", "1", "--res", "16", "--image", image, "--seed", "3", "--test-fraction", "1", "--out", &d]);
        d
    };
    let out = run_ok(&["eval", "--data", &score("256"), "--preset", "nano", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("not JSON ({e}): {out}"));
    assert!(v["samples"].as_u64() == Some(1) && v["object_psnr_mean"].as_f64().unwrap() > v["black_image_object_psnr"].as_f64().unwrap(), "{v}");
    let e = run_err(&["eval", "--data", &score("64"), "--preset", "nano"], &[]);
    assert!(e.contains("images are 64px") && e.contains("renders 128px"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `rendernet args` with `env` set, asserts it fails without a panic, returns stderr.
fn run_err(args: &[&str], env: &[(&str, &str)]) -> String {
    let out = rendernet().args(args).envs(env.iter().copied()).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "rendernet {args:?} should have failed:\n{}", String::from_utf8_lossy(&out.stdout));
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

/// A fresh folder for one test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("rendernet-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `render` and `truth` share one validation of the scene flags: each bad value fails both,
/// before anything is written, with the flag and its range rather than an internal tensor
/// name ('pose') or a wrong word (inf called NaN); `--radius -1` parses as a number. Fails
/// on the old code, where `render` drew `--elevation 500` and `--radius 100`.
#[test]
fn render_and_truth_reject_bad_scene_flags_alike_naming_the_flag() {
    let dir = scratch("scene");
    let out = dir.join("x.png");
    let cases: [(&[&str], &str); 7] = [
        (&["--elevation", "500"], "--elevation 500: must lie in 0..=180"),
        (&["--radius", "100"], "--radius 100: must lie in 0.05..=6.6 for --size 32"),
        (&["--radius", "0"], "--radius 0: must lie in"),
        (&["--radius", "-1"], "--radius -1: must lie in"),
        (&["--azimuth", "inf"], "--azimuth inf: must be a finite number"),
        (&["--azimuth", "-inf"], "--azimuth -inf: must be a finite number"),
        (&["--light-elevation", "-5"], "--light-elevation -5: must lie in 0..=180"),
    ];
    for cmd in ["render", "truth"] {
        for (flags, want) in cases {
            let mut args = vec![cmd, "--size", "32", "--out", out.to_str().unwrap()];
            args.extend_from_slice(flags);
            let e = run_err(&args, &[]);
            assert!(e.contains(want), "{cmd} {flags:?}: '{want}' not in: {e}");
            assert!(!e.contains("'pose'") && !e.contains("NaN"), "{cmd} {flags:?}: {e}");
            assert!(!out.exists(), "{cmd} {flags:?} wrote {}", out.display());
        }
    }
    // The bound itself is accepted: at 32 px, radius 6.6 leaves the object 8 px wide.
    run_ok(&["truth", "--size", "32", "--radius", "6.6", "--out", out.to_str().unwrap()]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `truth --out-voxels` writes the scene's grid: a painted procedural shape as a `.vox` that
/// reads back as the same occupancy and colours (within the palette's 8 bits), so a
/// MagicaVoxel file of it can be rendered with `render --voxels`; a `.binvox` of a painted grid
/// (no colour there) and an unknown extension are refused by name.
#[test]
fn truth_writes_the_scene_grid_as_voxels() {
    let dir = scratch("voxels");
    let (png, vox) = (dir.join("t.png"), dir.join("chair.vox"));
    let scene = ["truth", "--shape", "chair", "--seed", "9001", "--colour", "--resolution", "16", "--size", "32", "--out", png.to_str().unwrap()];
    run_ok(&[&scene[..], &["--out-voxels", vox.to_str().unwrap()]].concat());
    let got = rendernet::voxel::vox::read(&vox).unwrap();
    let want = rendernet::voxel::Family::Chair.generate(9001).to_coloured_grid(16, 9001).unwrap();
    assert_eq!(got.dims(), want.dims());
    assert_eq!(got.occupancy(), want.occupancy());
    let (gc, wc) = (got.colour().expect("the .vox keeps the colour"), want.colour().unwrap());
    let cells = want.occupancy().len();
    for (i, (g, w)) in gc.iter().zip(wc).enumerate() {
        if want.occupancy()[i % cells] > 0.5 {
            assert!((g - w).abs() <= 0.5 / 255.0 + 1e-6, "colour {i}: {g} vs {w}");
        }
    }
    for (name, want) in [("chair.binvox", "no colour"), ("chair.png", "--out-voxels")] {
        let e = run_err(&[&scene[..], &["--out-voxels", dir.join(name).to_str().unwrap()]].concat(), &[]);
        assert!(e.contains(want) && e.contains(name), "{name}: {e}");
    }
    let grey = dir.join("chair.binvox");
    run_ok(&["truth", "--shape", "chair", "--seed", "9001", "--resolution", "16", "--size", "32", "--out", png.to_str().unwrap(), "--out-voxels", grey.to_str().unwrap()]);
    assert_eq!(rendernet::voxel::binvox::Binvox::read(&grey).unwrap().grid.occupancy(), rendernet::voxel::Family::Chair.generate(9001).to_grid(16).unwrap().occupancy());
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output name the build cannot encode fails before rendering and leaves no file (the old
/// code rendered, then left a 0-byte x.jpg); a successful write leaves no temporary file.
#[test]
fn unsupported_out_extension_fails_first_and_leaves_no_file() {
    let dir = scratch("out");
    for cmd in ["render", "truth"] {
        for name in ["x.jpg", "noext"] {
            let out = dir.join(name);
            let e = run_err(&[cmd, "--size", "32", "--out", out.to_str().unwrap()], &[]);
            assert!(e.contains("--out") && e.contains(".png"), "{cmd} {name}: {e}");
            assert!(!e.contains("rendered"), "{e}");
            assert!(!out.exists(), "{cmd} left {}", out.display());
        }
    }
    let missing = dir.join("no-such-folder").join("x.png");
    let e = run_err(&["truth", "--size", "32", "--out", missing.to_str().unwrap()], &[]);
    assert!(e.contains("--out") && e.contains("does not exist"), "{e}");
    run_ok(&["truth", "--size", "32", "--out", dir.join("ok.png").to_str().unwrap()]);
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert_eq!(left, ["ok.png"], "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A failed PNG write (here: an image the encoder refuses) keeps the file already there and
/// leaves no temporary file, where `image::save` would have truncated it.
#[test]
fn failed_png_write_keeps_the_old_file() {
    let dir = scratch("atomic");
    let path = dir.join("keep.png");
    std::fs::write(&path, b"old").unwrap();
    let empty = image::DynamicImage::new_rgb8(0, 0);
    assert!(rendernet::reference::write_png(&empty, &path).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), b"old");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `render --weights` takes a training checkpoint (its Adam moments ignored) and draws what
/// the weights file beside it draws; the old code listed every `adam.*` tensor as unexpected.
#[test]
fn render_accepts_a_training_checkpoint_as_weights() {
    use rendernet::graph::params::{Named, parse_safetensors, save_safetensors};
    let dir = scratch("ckpt");
    let (weights, ckpt) = (dir.join("w.safetensors"), dir.join("run.ckpt"));
    std::fs::write(&weights, rendernet::nn::render::TINY_PHONG_WEIGHTS).unwrap();
    let (params, mut meta) = parse_safetensors(rendernet::nn::render::TINY_PHONG_WEIGHTS, "tiny").unwrap();
    let mut tensors: Vec<Named> = Vec::new();
    for (name, (shape, vals)) in &params {
        tensors.push((name.clone(), shape.clone(), vals.clone()));
        tensors.push((format!("adam.m.{name}"), shape.clone(), vec![0.5; vals.len()]));
        tensors.push((format!("adam.v.{name}"), shape.clone(), vec![0.25; vals.len()]));
    }
    // The weights' own metadata (their `input` side among it), as `train` writes both.
    meta.extend([("step", "1000"), ("seed", "3")].map(|(k, v)| (k.to_string(), v.to_string())));
    save_safetensors(&ckpt, &tensors, meta).unwrap();
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    run_ok(&["render", "--size", "32", "--weights", ckpt.to_str().unwrap(), "--out", a.to_str().unwrap()]);
    run_ok(&["render", "--size", "32", "--weights", weights.to_str().unwrap(), "--out", b.to_str().unwrap()]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A weights file with a missing, a mis-shaped, a mis-typed (F16) and an unexpected tensor
/// gets all four named in one error; the old code stopped at the F16 tensor.
#[test]
fn weight_loading_reports_every_mismatch_at_once() {
    use safetensors::{Dtype, tensor::TensorView};
    let dir = scratch("mismatch");
    let bad = dir.join("bad.safetensors");
    let (params, _) = rendernet::graph::params::parse_safetensors(rendernet::nn::render::TINY_PHONG_WEIGHTS, "tiny").unwrap();
    let names: Vec<&String> = params.keys().collect();
    let (missing, reshaped, halved) = (names[0].clone(), names[1].clone(), names[2].clone());
    let mut owned: Vec<(String, Dtype, Vec<usize>, Vec<u8>)> = Vec::new();
    for (name, (shape, vals)) in &params {
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        if *name == missing {
            continue;
        } else if *name == reshaped {
            owned.push((name.clone(), Dtype::F32, vec![1, vals.len()], bytes));
        } else if *name == halved {
            owned.push((name.clone(), Dtype::F16, shape.clone(), vec![0; 2 * vals.len()]));
        } else {
            owned.push((name.clone(), Dtype::F32, shape.clone(), bytes));
        }
    }
    owned.push(("extra.weight".into(), Dtype::F32, vec![1], 1f32.to_le_bytes().to_vec()));
    let views: Vec<(String, TensorView)> =
        owned.iter().map(|(n, d, s, b)| (n.clone(), TensorView::new(*d, s.clone(), b).unwrap())).collect();
    std::fs::write(&bad, safetensors::serialize(views, None).unwrap()).unwrap();
    let e = run_err(&["render", "--size", "32", "--weights", bad.to_str().unwrap(), "--out", dir.join("x.png").to_str().unwrap()], &[]);
    for want in [format!("missing '{missing}'"), format!("'{reshaped}' has shape"), format!("'{halved}' is F16"), "unexpected 'extra.weight'".into()] {
        assert!(e.contains(&want), "'{want}' not in: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `train --out X` refuses to replace an existing X unless --resume or --force is given, and
/// says so; with --force it goes on (and here stops at the missing dataset). The old code went
/// straight to training and would have overwritten X at the first checkpoint.
#[test]
fn train_refuses_to_overwrite_a_checkpoint_without_resume_or_force() {
    let dir = scratch("train");
    let ckpt = dir.join("run.ckpt");
    std::fs::write(&ckpt, b"hours of training").unwrap();
    let (c, data) = (ckpt.to_str().unwrap(), dir.join("no-data"));
    let d = data.to_str().unwrap();
    let e = run_err(&["train", "--data", d, "--out", c, "--steps", "1"], &[]);
    assert!(e.contains("--out") && e.contains("exists") && e.contains("--force") && e.contains("--resume"), "{e}");
    let e = run_err(&["train", "--data", d, "--out", c, "--steps", "1", "--force"], &[]);
    assert!(!e.contains("--force") && e.contains("no-data"), "--force should pass the check: {e}");
    assert_eq!(std::fs::read(&ckpt).unwrap(), b"hours of training");
    let _ = std::fs::remove_dir_all(&dir);
}

/// WGPU_BACKEND is checked against the names wgpu defines: an unknown one is named with the
/// accepted list (the old code tried no backend at all and advised installing Mesa).
#[test]
fn unknown_wgpu_backend_is_named_with_the_accepted_ones() {
    let e = run_err(&["info"], &[("WGPU_BACKEND", "foo")]);
    assert!(e.contains("WGPU_BACKEND=foo") && e.contains("unknown backend 'foo'"), "{e}");
    assert!(e.contains("vulkan") && e.contains("gl") && !e.contains("mesa-vulkan-drivers"), "{e}");
}

/// A backend this build lacks on Linux (Metal) is said to be missing from the build, not
/// blamed on a missing Mesa install.
#[cfg(target_os = "linux")]
#[test]
fn backend_missing_from_the_build_is_not_blamed_on_mesa() {
    let e = run_err(&["info"], &[("WGPU_BACKEND", "metal")]);
    assert!(e.contains("no metal backend on linux") && e.contains("vulkan"), "{e}");
    assert!(!e.contains("apt-get"), "{e}");
}

/// `stress --json` runs every sweep on the default scene; the reference renderer on the
/// clean grid reproduces its own truth exactly (99 dB), the network does not but stays well
/// above the all-black floor, and the contact sheet has two rows per sweep.
#[test]
fn stress_runs_every_sweep_and_scores_against_the_clean_scene() {
    let dir = scratch("stress");
    let sheet = dir.join("sheet.png");
    let out = run_ok(&["stress", "--json", "--out", sheet.to_str().unwrap()]);
    let rows: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap();
    for sweep in ["dropout", "salt", "value-noise", "downsample", "two-objects", "view"] {
        assert!(rows.iter().any(|r| r["sweep"] == sweep), "sweep {sweep} missing");
    }
    let at = |sweep: &str, method: &str, level: f64| {
        rows.iter().find(|r| r["sweep"] == sweep && r["method"] == method && r["level"].as_f64() == Some(level)).unwrap()["object_psnr"].as_f64().unwrap()
    };
    assert_eq!(at("dropout", "reference", 0.0), 99.0);
    assert!(at("dropout", "reference", 0.5) < 30.0, "dropout did not change the grid");
    let ours = at("dropout", "rendernet", 0.0);
    assert!((12.0..40.0).contains(&ours), "network object PSNR {ours} on the clean scene");
    let png = image::open(&sheet).unwrap();
    assert_eq!((png.width(), png.height()), (6 * 128, 12 * 128));
    // One chart per sweep beside the sheet (no --charts): <out stem>-<sweep>.png.
    for sweep in ["dropout", "salt", "value-noise", "downsample", "two-objects", "view"] {
        let chart = dir.join(format!("sheet-{sweep}.png"));
        let img = image::open(&chart).unwrap_or_else(|e| panic!("{}: {e}", chart.display()));
        assert_eq!((img.width(), img.height()), (800, 480), "{sweep}");
    }
    // A --charts folder that does not exist fails before any rendering, naming the flag.
    let err = run_err(&["stress", "--out", sheet.to_str().unwrap(), "--charts", dir.join("missing").to_str().unwrap()], &[]);
    assert!(err.contains("--charts"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `curve` redraws a run's chart from its log and names the flag when the log is missing.
#[test]
fn curve_redraws_a_log_and_rejects_a_missing_one() {
    let dir = scratch("curve");
    let log = dir.join("run.log.csv");
    let rows: String = (1..=50).map(|s| format!("{s},{},\n", 1.0 / s as f32)).collect();
    std::fs::write(&log, format!("step,loss,psnr\n{rows}50,,21.5\n")).unwrap();
    let png = dir.join("curve.png");
    let out = run_ok(&["curve", "--log", log.to_str().unwrap(), "--out", png.to_str().unwrap()]);
    assert!(out.contains("50 loss rows, 1 evaluations"), "{out}");
    assert!(image::open(&png).is_ok());
    let err = run_err(&["curve", "--log", dir.join("none.csv").to_str().unwrap(), "--out", png.to_str().unwrap()], &[]);
    assert!(err.contains("--log") && err.contains("no such file"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A corruption level outside 0..=1 is refused by flag name before any data is read.
#[test]
fn train_rejects_an_augmentation_level_by_name() {
    let dir = scratch("augment");
    let out = rendernet()
        .args(["train", "--data", "no-such-dataset", "--out", dir.join("x.ckpt").to_str().unwrap(), "--augment-dropout", "1.5"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--augment-dropout 1.5") && !err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Each shipped preset renders out of the box; a preset without shipped weights asks for
/// --weights by name.
#[test]
fn render_uses_the_shipped_weights_of_the_preset() {
    let dir = scratch("presets");
    let png = dir.join("nano.png");
    let out = run_ok(&["render", "--preset", "nano", "--size", "32", "--out", png.to_str().unwrap()]);
    assert!(out.contains("embedded nano-phong weights") && png.exists(), "{out}");
    let out = rendernet().args(["render", "--preset", "paper", "--out", png.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--preset paper") && err.contains("--weights"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A grid with colour (a painted `--shape`, a `.vox` palette) renders with the shipped colour
/// weights unless `--weights` says otherwise; a grey one keeps the grey weights; `eval` on a
/// coloured dataset finds the colour weights too.
#[test]
fn render_picks_the_colour_weights_for_a_coloured_grid() {
    let dir = scratch("colour-weights");
    let png = dir.join("c.png");
    let p = png.to_str().unwrap();
    let out = run_ok(&["render", "--shape", "chair", "--seed", "9001", "--colour", "--size", "64", "--out", p]);
    assert!(out.contains("embedded base-phong-colour weights") && png.exists(), "{out}");
    let out = run_ok(&["render", "--shape", "chair", "--seed", "9001", "--colour", "--size", "64", "--preset", "tiny", "--out", p]);
    assert!(out.contains("embedded tiny-phong-colour weights"), "{out}");
    let out = run_ok(&["render", "--shape", "chair", "--seed", "9001", "--size", "64", "--out", p]);
    assert!(out.contains("embedded base-phong weights (held-out"), "{out}");
    let data = dir.join("data");
    let d = data.to_str().unwrap();
    run_ok(&["dataset", "--colour", "--count", "1", "--views", "1", "--res", "16", "--image", "128", "--seed", "2", "--test-fraction", "1", "--out", d]);
    let out = run_ok(&["eval", "--data", d, "--json"]);
    assert!(out.contains("object_psnr_mean"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--quality` and `--target-psnr` pick a shipped model by its measured accuracy: the fastest
/// that meets the target; a target none meets names the best there is.
#[test]
fn render_picks_the_fastest_shipped_model_that_meets_the_target() {
    let dir = scratch("quality");
    let png = dir.join("q.png");
    let p = png.to_str().unwrap();
    let picks = [
        (&["--quality", "fast"][..], "nano"),
        (&["--quality", "balanced"], "tiny"),
        (&["--quality", "best"], "base"),
        (&["--target-psnr", "19"], "nano"),
        (&["--target-psnr", "20"], "tiny"),
        (&["--target-psnr", "23"], "base"),
    ];
    for (flags, model) in picks {
        let out = run_ok(&[&["render", "--size", "32", "--out", p][..], flags].concat());
        assert!(out.contains(&format!("embedded {model}-phong weights (held-out object PSNR")), "{flags:?}: {out}");
    }
    let out = rendernet().args(["render", "--target-psnr", "40", "--out", p]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--target-psnr 40") && err.contains("'base'"), "{err}");
    let out = rendernet().args(["render", "--quality", "fast", "--weights", "w.safetensors", "--out", p]).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("--weights"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without --preset, `render` takes the preset a --weights file records (`train` writes it)
/// and, with the shipped weights, the most accurate model there is for the shader and grid;
/// a recorded preset that does not exist is named with where it came from.
#[test]
fn render_defaults_to_the_recorded_or_most_accurate_preset() {
    use rendernet::graph::params::{Named, parse_safetensors, save_safetensors};
    let dir = scratch("default-preset");
    let p = dir.join("d.png");
    let p = p.to_str().unwrap();
    let out = run_ok(&["render", "--size", "32", "--out", p]);
    assert!(out.contains("embedded base-phong weights"), "{out}");
    let out = run_ok(&["render", "--size", "32", "--shader", "ao", "--out", p]);
    assert!(out.contains("embedded tiny-ao weights"), "{out}");
    let (params, meta) = parse_safetensors(rendernet::nn::render::NANO_PHONG_WEIGHTS, "nano").unwrap();
    assert_eq!(meta.get("preset").map(String::as_str), Some("nano"), "the shipped nano weights record their preset");
    let tensors: Vec<Named> = params.into_iter().map(|(n, (shape, v))| (n, shape, v)).collect();
    let nano = dir.join("nano.safetensors");
    save_safetensors(&nano, &tensors, meta.clone()).unwrap();
    let out = run_ok(&["render", "--size", "32", "--weights", nano.to_str().unwrap(), "--out", p]);
    assert!(out.contains("nano.safetensors"), "{out}");
    let odd = dir.join("odd.safetensors");
    let mut bad = meta;
    bad.insert("preset".to_string(), "huge".to_string());
    save_safetensors(&odd, &tensors, bad).unwrap();
    let e = run_err(&["render", "--size", "32", "--weights", odd.to_str().unwrap(), "--out", p], &[]);
    assert!(e.contains("odd.safetensors: metadata 'preset'") && e.contains("'huge'") && e.contains("--preset"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `stress --unseen DIR` adds one clean case per grid or mesh file of DIR (other files are
/// skipped), for both methods; a folder without any is refused by flag name.
#[test]
fn stress_unseen_scores_every_shape_file_of_a_folder() {
    let dir = scratch("unseen");
    let shapes = dir.join("shapes");
    std::fs::create_dir_all(&shapes).unwrap();
    let corpus = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-corpus");
    for f in ["cube.off", "pattern.binvox"] {
        std::fs::copy(corpus.join(f), shapes.join(f)).unwrap();
    }
    std::fs::write(shapes.join("notes.txt"), "not a shape").unwrap();
    let png = dir.join("s.png");
    let out = run_ok(&["stress", "--unseen", shapes.to_str().unwrap(), "--resolution", "32", "--json", "--out", png.to_str().unwrap()]);
    let rows: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    let unseen: Vec<&serde_json::Value> = rows.iter().filter(|r| r["sweep"] == "unseen").collect();
    let labels: Vec<&str> = unseen.iter().map(|r| r["label"].as_str().unwrap()).collect();
    assert_eq!(labels, ["cube", "cube", "pattern", "pattern"], "{out}");
    assert!(unseen.iter().all(|r| r["object_psnr"].as_f64().is_some_and(|v| v > 0.0)), "{out}");
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = rendernet().args(["stress", "--unseen", empty.to_str().unwrap(), "--out", png.to_str().unwrap()]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--unseen") && err.contains("no .binvox"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `train-prior` trains the shape autoencoder on a dataset's grids: it writes the checkpoint
/// and the weights, reports a held-out IoU in 0..1, resumes from its checkpoint, and refuses
/// to overwrite a checkpoint without --resume or --force, and keeps its training codes'
/// statistics in the weights file; `eval-shape` then recovers a held-out shape through it
/// from one and from two views, and through the shipped prior, and reports IoUs in 0..1;
/// more views than the dataset has is an error naming both counts.
#[test]
fn train_prior_trains_resumes_and_reports_iou() {
    let dir = std::env::temp_dir().join(format!("rendernet-cli-prior-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (data, ckpt) = (dir.join("data"), dir.join("prior.ckpt"));
    let (d, c) = (data.to_str().unwrap(), ckpt.to_str().unwrap());
    run_ok(&["dataset", "--count", "2", "--views", "2", "--res", "32", "--image", "128", "--seed", "5", "--out", d]);
    let common = ["--data", d, "--out", c, "--batch", "2", "--eval-every", "2", "--eval-samples", "2"];
    let out = run_ok(&[&["train-prior", "--steps", "2"][..], &common[..]].concat());
    let iou: f64 = out.lines().find_map(|l| l.strip_prefix("final held-out IoU ")).and_then(|r| r.split(';').next()).unwrap_or_else(|| panic!("{out}")).parse().unwrap();
    assert!((0.0..=1.0).contains(&iou), "{out}");
    assert!(ckpt.exists() && ckpt.with_extension("weights.safetensors").exists());
    let again = rendernet().args([&["train-prior", "--steps", "2"][..], &common[..]].concat()).output().unwrap();
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("--resume"));
    let out = run_ok(&[&["train-prior", "--steps", "4", "--resume", c][..], &common[..]].concat());
    assert!(out.contains("step 4/4"), "{out}");
    let w = ckpt.with_extension("weights.safetensors");
    let stats = rendernet::nn::prior::CodeStats::from_weights(&std::fs::read(&w).unwrap(), "prior").unwrap().expect("code statistics kept");
    assert_eq!((stats.latent(), stats.training_codes().count()), (64, 2), "the one training shape's two views");
    let ws = w.to_str().unwrap();
    for args in [&["--prior", ws, "--views", "1"][..], &["--prior", ws, "--views", "2"], &["--views", "1"]] {
        let out = run_ok(&[&["eval-shape", "--data", d, "--samples", "1", "--steps", "2", "--json"][..], args].concat());
        let j: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
        for key in ["iou_mean", "retrieved_iou_mean", "start_iou_mean"] {
            assert!(j[key].as_f64().is_some_and(|v| (0.0..=1.0).contains(&v)), "{key} in {out}");
        }
    }
    // Camera and light searched too (a tiny search is not exposed: the default one, 1 round).
    let out = run_ok(&["eval-shape", "--data", d, "--prior", ws, "--samples", "1", "--steps", "1", "--unknown-pose", "--rounds", "1", "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    for key in ["iou_mean", "pose_error_degrees_median", "light_error_degrees_median"] {
        assert!(j[key].as_f64().is_some_and(f64::is_finite), "{key} in {out}");
    }
    let bad = rendernet().args(["eval-shape", "--data", d, "--prior", ws, "--views", "2", "--unknown-pose"]).output().unwrap();
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("one view per shape"));
    let bad = rendernet().args(["eval-shape", "--data", d, "--prior", ws, "--views", "3"]).output().unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && err.contains("3 views") && err.contains("as few as 2"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `train-texture`: no dataset (the paints are procedural); it reports the held-out texture
/// PSNR, refuses to overwrite, and resumes.
#[test]
fn train_texture_trains_resumes_and_reports_psnr() {
    let dir = std::env::temp_dir().join(format!("rendernet-cli-texture-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ckpt = dir.join("texture.ckpt");
    let c = ckpt.to_str().unwrap();
    let common = ["--out", c, "--batch", "2", "--eval-every", "2", "--eval-samples", "2"];
    let out = run_ok(&[&["train-texture", "--steps", "2"][..], &common[..]].concat());
    let psnr: f64 = out.lines().find_map(|l| l.strip_prefix("final held-out texture PSNR ")).and_then(|r| r.split(';').next()).unwrap_or_else(|| panic!("{out}")).parse().unwrap();
    assert!(psnr.is_finite() && psnr > 3.0, "{out}");
    let again = rendernet().args([&["train-texture", "--steps", "2"][..], &common[..]].concat()).output().unwrap();
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("--resume"));
    let out = run_ok(&[&["train-texture", "--steps", "4", "--resume", c][..], &common[..]].concat());
    assert!(out.contains("step 4/4"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `train --input N` trains reading grids at N^3 and records N in the weights (`input`);
/// `Preset::for_weights` reads it back, a resume keeps it without the flag, and a weights
/// file whose `input` is out of range is an error naming the field and the limit.
#[test]
fn train_input_side_is_recorded_kept_on_resume_and_checked() {
    use rendernet::nn::rendernet::{MAX_INPUT, Preset};
    let dir = scratch("input");
    let (data, ckpt) = (dir.join("data"), dir.join("run.ckpt"));
    let (d, c) = (data.to_str().unwrap(), ckpt.to_str().unwrap());
    run_ok(&["dataset", "--count", "2", "--views", "1", "--res", "16", "--image", "128", "--seed", "5", "--out", d]);
    let common = ["--preset", "nano", "--data", d, "--out", c, "--eval-every", "1", "--eval-samples", "1"];
    let side = |f: &std::path::Path| {
        let bytes = std::fs::read(f).unwrap();
        Preset::nano().for_weights(&bytes, "w").unwrap().input
    };
    run_ok(&[&["train", "--steps", "1", "--input", "24"][..], &common[..]].concat());
    let w = ckpt.with_extension("weights.safetensors");
    assert_eq!((side(&w), side(&ckpt)), (24, 24));
    run_ok(&[&["train", "--steps", "2", "--resume", c][..], &common[..]].concat());
    assert_eq!(side(&w), 24, "a resume without --input keeps the checkpoint's side");
    let e = run_err(&[&["train", "--steps", "1", "--force", "--input", "1"][..], &common[..]].concat(), &[]);
    assert!(e.contains("--input"), "{e}");
    // Weights naming an impossible side: refused by name, not built into a huge graph.
    let (params, _) = rendernet::graph::params::parse_safetensors(&std::fs::read(&w).unwrap(), "w").unwrap();
    let tensors: Vec<_> = params.into_iter().map(|(n, (s, v))| (n, s, v)).collect();
    let bad = dir.join("bad.safetensors");
    let meta = [("input".to_string(), format!("{}", MAX_INPUT + 1))].into();
    rendernet::graph::params::save_safetensors(&bad, &tensors, meta).unwrap();
    let e = run_err(&["render", "--preset", "nano", "--size", "32", "--weights", bad.to_str().unwrap(), "--out", dir.join("x.png").to_str().unwrap()], &[]);
    assert!(e.contains("'input'") && e.contains(&MAX_INPUT.to_string()), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
