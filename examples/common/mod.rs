//! What every example shares: PNG output names checked at parse time, and a `main` that
//! prints errors as sentences (Display) and exits non-zero.

#![allow(dead_code)] // each example uses the part it needs

use rendernet::reference::png_path_problem;
use std::path::PathBuf;
use std::process::ExitCode;

/// Clap value parser: rejects a non-PNG output name before any rendering.
pub fn png_out(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    png_path_problem(&p).map_or(Ok(p), Err)
}

/// Runs `run` and turns its error into `error: <message>` and a failure exit code.
pub fn exit_with(result: Result<(), Box<dyn std::error::Error>>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
