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
    /// nor --shape it renders the built-in default, the Stanford bunny at 64^3.
    Truth(cli::truth::TruthArgs),
    /// Generate a deterministic, sharded training/test set (input grids, poses, lights and
    /// reference-rendered targets) with a manifest; see datasets/README.md.
    Dataset(cli::dataset::DatasetArgs),
    /// Render a voxel grid (binvox, safetensors or a mesh; any size) with trained RenderNet
    /// to a PNG. With no arguments: the built-in shape with the embedded weights.
    Render(cli::render::RenderArgs),
    /// Train RenderNet on a dataset (patch training, Adam, checkpoints, resume, curve PNG).
    /// On a real GPU the same command trains `--preset paper`.
    Train(cli::train::TrainArgs),
    /// Mean held-out PSNR (95% interval) and per-shape PSNR of trained weights.
    Eval(cli::eval::EvalArgs),
    /// Redraw a training run's curve (loss and held-out PSNR against step) from its
    /// `<out>.log.csv`.
    Curve(cli::train::CurveArgs),
    /// Train the 3D shape autoencoder used as a shape prior by inverse rendering.
    TrainPrior(cli::prior::TrainPriorArgs),
    /// Train the texture decoder (a code of 9 numbers -> an RGB grid over the object cube) on
    /// the procedural paints of `dataset --colour`, for recovering texture by inverse rendering.
    TrainTexture(cli::prior::TrainTextureArgs),
    /// Recover held-out shapes from one or more images through the shape prior (pose and
    /// light known; MAP on the prior's code, multi-start) and report their voxel IoU beside
    /// the best start's and the prior's mean shape's.
    EvalShape(cli::shape::EvalShapeArgs),
    /// Recover the paints of painted shapes from one or more images through the texture
    /// decoder and the colour network (camera and light known; multi-start on the texture
    /// code), scored from a view no input image had against the true paint.
    EvalTexture(cli::texture::EvalTextureArgs),
    /// Recover the camera pose and the light from one image of a known shape, by gradient
    /// descent through the frozen network (coarse silhouette search, then Adam on the best
    /// starts); with --prior, the shape too (alternating with a search on the shape prior's
    /// code). Without --image, the target is rendered from the scene flags and the errors
    /// of the recovered pose, light (and shape) are reported.
    Invert(cli::invert::InvertArgs),
    /// Invert held-out samples of a Phong dataset (shape known) and report camera and light
    /// direction errors in degrees (median, share within 5 and 10 degrees) and time per image.
    EvalInvert(cli::invert::EvalInvertArgs),
    /// Sweep corrupted (voxel dropout, salt, value noise), coarse, two-object and extreme-view
    /// versions of a scene through RenderNet and the reference renderer, each scored against
    /// the reference image of the clean scene; tables or JSON, and a contact sheet PNG.
    Stress(cli::stress::StressArgs),
    /// Speed against accuracy: score each model (the shipped one and any --model) on a
    /// dataset's held-out split, time its forward on this adapter beside the reference
    /// renderer's, and chart object and full-frame PSNR against forward milliseconds and
    /// training hours (PNG; table or JSON), RenderNet presets and EC baselines alike.
    Frontier(cli::frontier::FrontierArgs),
    /// Time the conv, transposed-conv, projection (reference and tiled) and resampling kernels
    /// on shapes from the RenderNet presets: median ms and GFLOP/s per pass, GPU timestamps
    /// when the adapter has them.
    Bench(cli::bench::BenchArgs),
}

fn main() -> ExitCode {
    // `rendernet ... | head` should end quietly like any Unix tool, not panic in println!.
    // SAFETY: restoring the default disposition of one signal before any thread starts.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // Mesa prints a warning per device open without it; any writable folder will do.
        // SAFETY: single-threaded here, before any other thread (wgpu's) exists.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let cli = Cli::parse();
    let r = match cli.cmd {
        Cmd::Info => cli::info::run(),
        Cmd::Truth(a) => cli::truth::run(a),
        Cmd::Dataset(a) => cli::dataset::run(a),
        Cmd::Train(a) => cli::train::run(a),
        Cmd::Render(a) => cli::render::run(a),
        Cmd::Eval(a) => cli::eval::run(a),
        Cmd::Curve(a) => cli::train::run_curve(a),
        Cmd::TrainPrior(a) => cli::prior::run(a),
        Cmd::TrainTexture(a) => cli::prior::run_texture(a),
        Cmd::EvalShape(a) => cli::shape::run(a),
        Cmd::EvalTexture(a) => cli::texture::run(a),
        Cmd::Bench(a) => cli::bench::run(a),
        Cmd::Invert(a) => cli::invert::run(a),
        Cmd::Stress(a) => cli::stress::run(a),
        Cmd::Frontier(a) => cli::frontier::run(a),
        Cmd::EvalInvert(a) => cli::invert::run_eval(a),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
