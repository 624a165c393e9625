//! Choices a device measures once per machine (which kernel family is faster, say) and keeps
//! in `$XDG_CACHE_HOME/rendernet/calibration.txt` (`~/.cache/...`), one `key=value` line each,
//! keyed by the choice's name, the adapter, the driver and the CPU: on lavapipe the answer
//! depends on all of them.

use super::Gpu;
use std::path::PathBuf;

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
        let path = cache_file();
        let text = path.as_ref().and_then(|p| std::fs::read_to_string(p).ok()).unwrap_or_default();
        if let Some(v) = text.lines().find_map(|l| l.split_once('=').filter(|(k, _)| *k == key).map(|(_, v)| v == "yes")) {
            return v;
        }
        let v = measure();
        if let Some(p) = path {
            let mut lines: Vec<String> = text.lines().filter(|l| l.split_once('=').is_none_or(|(k, _)| k != key)).map(String::from).collect();
            lines.push(format!("{key}={}", if v { "yes" } else { "no" }));
            let tmp = p.with_extension("tmp");
            if p.parent().is_some_and(|d| std::fs::create_dir_all(d).is_ok()) && std::fs::write(&tmp, lines.join("\n") + "\n").is_ok() {
                let _ = std::fs::rename(&tmp, &p);
            }
        }
        v
    }
}
