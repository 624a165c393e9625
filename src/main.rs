//! The `rendernet` command line: thin subcommands over the library.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cli;

/// RenderNet on wgpu: render voxel grids with a neural renderer, train it, invert it.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Print the GPU adapter, backend and the limits that matter. Honours WGPU_BACKEND
    /// (vulkan, metal, dx12, gl) and WGPU_ADAPTER_NAME (substring of the adapter name).
    Info,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let r = match cli.cmd {
        Cmd::Info => cli::info::run(),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
