//! Mutation fuzzing of every parser that reads user files: binvox, OBJ, OFF, PLY (ASCII and
//! both binary byte orders), MagicaVoxel .vox, safetensors grids and weights, and dataset
//! manifests. The property: any byte string gives `Ok` or `Err`, never a panic, an abort
//! from a huge allocation, or a hang.
//!
//! Inputs are seeds from `tests/fuzz-corpus/` (kept in the repository) mutated by stacked
//! random edits: bit flips, interesting bytes and integers, inserted, deleted, duplicated or
//! truncated ranges, splices from other seeds, and (for text) numbers swapped for extreme
//! ones. It is not coverage-guided (that needs a nightly toolchain), so the edits aim at
//! what parsers trip on: counts, sizes, offsets and numbers.
//!
//! Budget: `RENDERNET_FUZZ_SECS` seconds per format (default 3), from the fixed seed
//! `RENDERNET_FUZZ_SEED` (default 1), so a failure reproduces. A failing input is written to
//! `target/fuzz-failures/` and its path printed.

use rendernet::rng::SplitMix64;
use rendernet::voxel::{Binvox, Mesh, safetensors_io, vox};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// One parser under test: it sees the bytes and says whether it accepted them.
type Parser = fn(&[u8]) -> bool;

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-corpus")
}

fn seeds(ext: &[&str]) -> Vec<Vec<u8>> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(corpus())
        .expect("tests/fuzz-corpus")
        .map(|e| e.unwrap().path())
        .filter(|p| ext.iter().any(|x| p.to_string_lossy().ends_with(x)))
        .map(|p| (p.display().to_string(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no seed files ending in {ext:?} in tests/fuzz-corpus");
    v.into_iter().map(|(_, b)| b).collect()
}

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Values parsers mishandle: zero, signs, lengths at type limits, NaN/Inf in text.
const INTERESTING_U32: [u32; 10] = [0, 1, 2, 0x7f, 0xff, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 65536, 1 << 30];
const INTERESTING_TEXT: [&str; 12] =
    ["0", "-1", "4294967296", "18446744073709551616", "1e309", "nan", "inf", "-0", "99999999", "1.5", "", "2147483648"];

/// One random edit of `b` (never grows it past 64 KiB).
fn mutate(b: &mut Vec<u8>, r: &mut SplitMix64, others: &[Vec<u8>]) {
    let pick = |r: &mut SplitMix64, n: usize| (r.next_u64() % n.max(1) as u64) as usize;
    match r.next_u64() % 9 {
        0 if !b.is_empty() => {
            let i = pick(r, b.len());
            b[i] ^= 1 << (r.next_u64() % 8);
        }
        1 if !b.is_empty() => {
            let i = pick(r, b.len());
            b[i] = [0u8, 0xff, 0x7f, 0x80, b'\n', b' ', b'-', b'9', b'.'][pick(r, 9)];
        }
        2 if b.len() >= 4 => {
            // A little- or big-endian integer over 4 bytes: counts, sizes and offsets.
            let i = pick(r, b.len() - 3);
            let v = INTERESTING_U32[pick(r, INTERESTING_U32.len())];
            let bytes = if r.next_u64() % 2 == 0 { v.to_le_bytes() } else { v.to_be_bytes() };
            b[i..i + 4].copy_from_slice(&bytes);
        }
        3 if !b.is_empty() => {
            let (i, n) = (pick(r, b.len()), 1 + pick(r, 16));
            b.drain(i..(i + n).min(b.len()));
        }
        4 if b.len() < 65536 && !b.is_empty() => {
            let (i, n) = (pick(r, b.len()), 1 + pick(r, 32));
            let chunk: Vec<u8> = b[i..(i + n).min(b.len())].to_vec();
            let at = pick(r, b.len() + 1);
            b.splice(at..at, chunk);
        }
        5 => {
            let at = pick(r, b.len() + 1);
            b.truncate(at);
        }
        6 if !others.is_empty() && b.len() < 65536 => {
            let o = &others[pick(r, others.len())];
            let (at, from) = (pick(r, b.len() + 1), pick(r, o.len()));
            b.truncate(at);
            b.extend_from_slice(&o[from..]);
        }
        7 => {
            // Replace a run of digits (text formats' counts and coordinates).
            let starts: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_digit())).collect();
            if !starts.is_empty() {
                let s = starts[pick(r, starts.len())];
                let e = (s..b.len()).find(|&i| !b[i].is_ascii_digit()).unwrap_or(b.len());
                let t = INTERESTING_TEXT[pick(r, INTERESTING_TEXT.len())];
                b.splice(s..e, t.bytes());
            }
        }
        _ => {
            if b.len() < 65536 {
                let at = pick(r, b.len() + 1);
                let n = 1 + pick(r, 8);
                let junk: Vec<u8> = (0..n).map(|_| r.next_u64() as u8).collect();
                b.splice(at..at, junk);
            }
        }
    }
}

/// Runs `parse` on mutants of the seeds for the time budget; panics (failing the test) with
/// the path of the first input that made `parse` panic or take over 5 s.
fn fuzz(format: &str, ext: &[&str], parse: Parser) {
    let seeds = seeds(ext);
    // Every seed must parse: mutants of a rejected seed would explore only error paths.
    for (i, s) in seeds.iter().enumerate() {
        assert!(parse(s), "{format}: seed {i} is rejected");
    }
    let budget = Duration::from_secs_f64(env_or("RENDERNET_FUZZ_SECS", 3.0));
    let mut r = SplitMix64::new(env_or("RENDERNET_FUZZ_SEED", 1), format.len() as u64 * 7919 + ext.len() as u64);
    let (start, mut runs, mut accepted) = (Instant::now(), 0u64, 0u64);
    while start.elapsed() < budget {
        let mut b = seeds[(r.next_u64() % seeds.len() as u64) as usize].clone();
        for _ in 0..1 + r.next_u64() % 6 {
            mutate(&mut b, &mut r, &seeds);
        }
        let t = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| parse(&b)));
        let slow = t.elapsed() > Duration::from_secs(5);
        accepted += u64::from(matches!(outcome, Ok(true)));
        if outcome.is_err() || slow {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-failures");
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join(format!("{format}-{runs}.bin"));
            std::fs::write(&path, &b).unwrap();
            panic!("{format}: input {} {} (run {runs})", path.display(), if slow { "took over 5 s" } else { "panicked" });
        }
        runs += 1;
    }
    eprintln!("{format}: {runs} mutated inputs ({accepted} accepted) in {:.1} s, no panic", start.elapsed().as_secs_f64());
    assert!(runs > 100, "{format}: only {runs} inputs in the budget");
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn binvox_never_panics() {
    fuzz("binvox", &[".binvox"], |b| Binvox::parse(b, "f.binvox").is_ok());
}

#[test]
fn obj_never_panics() {
    fuzz("obj", &[".obj"], |b| Mesh::parse_obj(&text(b), "f.obj").is_ok());
}

#[test]
fn off_never_panics() {
    fuzz("off", &[".off"], |b| Mesh::parse_off(&text(b), "f.off").is_ok());
}

#[test]
fn ply_never_panics() {
    fuzz("ply", &[".ply"], |b| Mesh::parse_ply_bytes(b, "f.ply").is_ok());
}

#[test]
fn vox_never_panics() {
    fuzz("vox", &[".vox"], |b| vox::parse(b, "f.vox").is_ok());
}

#[test]
fn safetensors_grids_never_panic() {
    fuzz("grid", &["grid.safetensors", "grid-u8.safetensors"], |b| safetensors_io::from_bytes(b, "f.safetensors").is_ok());
}

#[test]
fn safetensors_weights_never_panic() {
    fuzz("weights", &["weights.safetensors"], |b| rendernet::graph::params::parse_safetensors(b, "f.safetensors").is_ok());
}

#[test]
fn dataset_manifests_never_panic() {
    fuzz("manifest", &[".json"], |b| rendernet::data::Manifest::parse(&text(b), "manifest.json").is_ok());
}
