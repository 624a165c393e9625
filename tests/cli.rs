//! The `rendernet` binary as a user meets it: `info` works, and with no matching adapter it
//! fails with an actionable message instead of a panic; `render --compare` and `eval` print
//! every score beside an all-black image's.

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
    assert!(stderr.contains("apt-get install -y mesa-vulkan-drivers"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// `bench --json` carries, per row, the kernel's speed and its fraction of the FMA ceiling
/// measured in the same run, with the adapter and CPU; the ceiling is positive and the
/// fraction is the ratio of the two (a row computed against another number would fail).
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
        assert!(g > 0.0 && (f - g / ceiling).abs() < 1e-9 * g.max(1.0), "{r}");
        assert!(["fast", "texture"].contains(&r["kernel"].as_str().unwrap()), "{r}");
    }
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
