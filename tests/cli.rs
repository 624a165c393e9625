//! The `rendernet` binary as a user meets it: `info` works, and with no matching adapter it
//! fails with an actionable message instead of a panic.

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
