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
    let grid = voxel::safetensors_io::from_bytes(&bunny, "bunny64").unwrap();
    let (view, light) = (View { azimuth: 40.0, elevation: 75.0, radius: 3.6 }, Light { azimuth: 20.0, elevation: 70.0, ..Light::default() });
    let target = reference::RayMarcher::new(&gpu).render(&gpu, &grid, &view, &light, Shader::Phong, 128).unwrap();
    let inv = Inverter::new(Preset::tiny(), TINY_PHONG_WEIGHTS, "embedded", Light::default());
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
    assert_eq!(j["curve"].as_array().map(Vec::len), Some(4), "{text}");
    let png = image::open(&out).unwrap();
    assert_eq!((png.width(), png.height()), (256, 128));
    let _ = std::fs::remove_dir_all(&dir);
}
