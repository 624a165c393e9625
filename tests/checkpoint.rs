//! `kill -9` at any moment of training leaves the last good checkpoint loadable.
//!
//! What it catches: a checkpoint written in place (`File::create(path)` then `write_all`, no
//! temporary file and rename) is truncated the moment the write starts, so a kill during the
//! write leaves a short file that neither `--resume` nor `render --weights` can read. Checked
//! by making `save_safetensors` write in place: round 1, the first kill at a write's start,
//! then failed with "header too small".

use rendernet::graph::params::load_safetensors;
use rendernet::rng::SplitMix64;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn rendernet() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rendernet"))
}

/// A training run, killed with SIGKILL when dropped (a failed assertion leaves no orphan).
struct Run(Child);

impl Drop for Run {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Name, length and modification time of the checkpoint `net.ckpt` and of every file named
/// after it (temporary files of writes; the weights, log and curve beside it are `net.*`
/// files of other names): a change means a checkpoint write has begun or ended.
fn snapshot(dir: &Path) -> Vec<(String, u64, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let e = e.ok()?;
            let name = e.file_name().into_string().ok()?;
            let m = e.metadata().ok()?;
            name.contains("net.ckpt").then(|| (name, m.len(), m.modified().unwrap()))
        })
        .collect();
    v.sort();
    v
}

/// The entries of a snapshot other than the checkpoint itself: unfinished writes.
fn temporaries(s: &[(String, u64, std::time::SystemTime)]) -> Vec<&(String, u64, std::time::SystemTime)> {
    s.iter().filter(|e| e.0 != "net.ckpt").collect()
}

/// The checkpoint's step, after checking that every tensor reads back as finite f32.
fn load_step(ckpt: &Path, what: &str) -> u64 {
    let (tensors, meta) = load_safetensors(ckpt).unwrap_or_else(|e| panic!("{what}: the checkpoint does not load: {e}"));
    assert!(tensors.keys().any(|k| k.starts_with("adam.m.")), "{what}: no optimiser state in {tensors:?}");
    meta.get("step").and_then(|s| s.parse().ok()).unwrap_or_else(|| panic!("{what}: no step in {meta:?}"))
}

/// Trains on a tiny dataset with a checkpoint every step, killing the process with SIGKILL
/// at random moments and, every other round, the moment a checkpoint write begins; each
/// round resumes from what the last kill left. After every kill the checkpoint must load
/// (stale temporary files beside it or not), and at the end `render --weights` must draw it.
#[test]
fn sigkill_during_training_leaves_a_loadable_checkpoint() {
    let dir = std::env::temp_dir().join(format!("rendernet-ckpt-kill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // `dataset` creates the folder.
    let (data, ckpt) = (dir.join("data"), dir.join("net.ckpt"));
    let st = rendernet()
        .args(["dataset", "--count", "2", "--views", "2", "--res", "16", "--image", "128", "--seed", "3", "--out"])
        .arg(&data)
        .status()
        .unwrap();
    assert!(st.success());
    let seed = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos() as u64;
    let mut rng = SplitMix64(seed);
    let (mut mid_write, mut last_step) = (0, 0);
    for round in 0..10 {
        let what = format!("round {round} (seed {seed})");
        let log = dir.join("stderr.txt");
        let mut cmd = rendernet();
        cmd.args(["train", "--steps", "1000", "--eval-every", "1", "--eval-samples", "1", "--data"]).arg(&data).arg("--out").arg(&ckpt);
        if ckpt.exists() {
            cmd.arg("--resume").arg(&ckpt);
        }
        let mut run = Run(cmd.stdout(Stdio::null()).stderr(std::fs::File::create(&log).unwrap()).spawn().unwrap());
        let before = snapshot(&dir);
        let t0 = Instant::now();
        // Odd rounds watch for a write starting (a temporary file, or the checkpoint
        // changing); even rounds wait a random time: start-up, a step, or a write.
        let delay = Duration::from_secs_f32(rng.range(0.3, 4.0));
        loop {
            if let Some(status) = run.0.try_wait().unwrap() {
                panic!("{what}: training stopped by itself ({status}): {}", std::fs::read_to_string(&log).unwrap());
            }
            let writing = snapshot(&dir) != before;
            if (round % 2 == 1 && writing) || (round % 2 == 0 && t0.elapsed() >= delay) {
                break;
            }
            assert!(t0.elapsed() < Duration::from_secs(120), "{what}: no checkpoint write within 120 s");
            std::thread::sleep(Duration::from_micros(100));
        }
        drop(run);
        // A temporary file created or rewritten by this run: the kill cut a write short.
        let after = snapshot(&dir);
        if temporaries(&after).iter().any(|t| !temporaries(&before).contains(t)) {
            mid_write += 1;
        }
        if ckpt.exists() {
            let step = load_step(&ckpt, &what);
            assert!(step >= last_step, "{what}: step went back from {last_step} to {step}");
            last_step = step;
        }
    }
    eprintln!("{mid_write} of 10 kills cut a checkpoint write short; last checkpoint at step {last_step} (seed {seed})");
    // Killing at the first sign of a write must have caught one in progress at least once,
    // or the rounds above proved nothing about writes.
    assert!(mid_write > 0, "no kill landed during a checkpoint write (seed {seed})");
    assert!(last_step > 0, "no checkpoint was ever completed (seed {seed})");
    let png = dir.join("render.png");
    let out = rendernet().args(["render", "--size", "32", "--weights"]).arg(&ckpt).arg("--out").arg(&png).output().unwrap();
    assert!(out.status.success(), "render --weights {}: {}", ckpt.display(), String::from_utf8_lossy(&out.stderr));
    assert!(png.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
