//! Checks on `--out` image paths, made before any work so a bad name fails in milliseconds
//! rather than after a render; the write itself is `reference::write_png` (atomic).

use rendernet::reference::png_path_problem;
use rendernet::{Error, Result};
use std::path::Path;

/// Errors, naming `--out`, unless `path` is a `.png` name in a folder that exists.
pub fn check_png_out(path: &Path) -> Result<()> {
    let bad = |m: String| Err(Error::Invalid(format!("--out {}: {m}", path.display())));
    if let Some(m) = png_path_problem(path) {
        return bad(m);
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return bad(format!("the folder {} does not exist", dir.display()));
    }
    Ok(())
}
