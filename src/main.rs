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
    /// Render one ground-truth image with the reference renderer (the images RenderNet learns
    /// to imitate): a voxel file, a mesh (voxelised), or a procedural shape, seen from an
    /// orthographic camera at the given pose and shaded by --shader. With neither --voxels
    /// nor --shape it renders the built-in default, procedural chair seed 0 at 64^3.
    Truth(cli::truth::TruthArgs),
    /// Time the conv, transposed-conv and projection kernels (reference and tiled) on shapes
    /// from the RenderNet presets: median ms and GFLOP/s per pass, GPU timestamps when the
    /// adapter has them.
    Bench(cli::bench::BenchArgs),
}

fn main() -> ExitCode {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa prints a warning per device open without it; any writable folder will do.
        // SAFETY: single-threaded here, before any other thread (wgpu's) exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let r = match cli.cmd {
        Cmd::Info => cli::info::run(),
        Cmd::Truth(a) => cli::truth::run(a),
        Cmd::Bench(a) => cli::bench::run(a),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
