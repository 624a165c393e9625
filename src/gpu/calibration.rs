//! Choices a device measures once per machine (which kernel family is faster, say) and keeps
//! in `$XDG_CACHE_HOME/rendernet/calibration.txt` (`~/.cache/...`), one `key=value` line each,
//! keyed by the choice's name, the adapter, the driver and the CPU: on lavapipe the answer
//! depends on all of them.

use super::Gpu;
use std::path::{Path, PathBuf};

fn cache_file() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("rendernet").join("calibration.txt"))
}

impl Gpu {
    /// The cached answer of the yes/no choice `name` on this device and CPU, or `measure`'s,
    /// which is then cached (best effort, written atomically: a cache that cannot be written
    /// costs a re-measure next time).
    pub(crate) fn calibrated_choice(&self, name: &str, measure: impl FnOnce() -> bool) -> bool {
        let i = &self.info;
        let cpu = crate::bench::cpu_model().unwrap_or_default();
        let key = format!("{name} {} | {} | {} | {cpu}", i.name, i.driver, i.driver_info).replace(['\n', '='], " ");
        cached(cache_file().as_deref(), &key, measure)
    }
}

/// The answer cached under `key` in the file `path`, or `measure`'s, then written there.
fn cached(path: Option<&Path>, key: &str, measure: impl FnOnce() -> bool) -> bool {
    let read = || path.and_then(|p| std::fs::read_to_string(p).ok()).unwrap_or_default();
    if let Some(v) = read().lines().find_map(|l| l.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v == "yes")) {
        return v;
    }
    let v = measure();
    if let Some(p) = path {
        // Read after measuring: a measurement can itself calibrate something (the operands'
        // runs pack, and the packings' own choice is measured then), and its line must stay.
        let mut lines: Vec<String> = read().lines().filter(|l| l.split_once('=').is_none_or(|(k, _)| k != key)).map(String::from).collect();
        lines.push(format!("{key}={}", if v { "yes" } else { "no" }));
        let tmp = p.with_extension("tmp");
        if p.parent().is_some_and(|d| std::fs::create_dir_all(d).is_ok()) && std::fs::write(&tmp, lines.join("\n") + "\n").is_ok() {
            let _ = std::fs::rename(&tmp, p);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A choice measured while another is being measured keeps its line when the outer one
    /// writes its own; both answers are read back without measuring again.
    #[test]
    fn a_calibration_inside_a_calibration_keeps_both() {
        let dir = std::env::temp_dir().join(format!("rendernet-calibration-{}", std::process::id()));
        let path = dir.join("calibration.txt");
        let _ = std::fs::remove_file(&path);
        let outer = cached(Some(&path), "outer", || !cached(Some(&path), "inner", || true));
        assert!(!outer);
        assert!(cached(Some(&path), "inner", || panic!("inner measured again")));
        assert!(!cached(Some(&path), "outer", || panic!("outer measured again")));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
