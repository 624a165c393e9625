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
