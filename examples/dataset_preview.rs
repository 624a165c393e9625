//! Tiles the first images of a dataset written by `rendernet dataset` into one PNG, one row per
//! sample and one column per image tensor, to eyeball what a model will be trained on.
//!
//! `cargo run --example dataset_preview -- DIR [train|test] [SAMPLES] [OUT.png]`

mod common;

use clap::{Parser, ValueEnum};
use rendernet::data::{Dataset, Split};
use rendernet::reference::write_png;
use std::path::PathBuf;
use std::process::ExitCode;

/// Which split to preview.
#[derive(Clone, Copy, ValueEnum)]
enum Which {
    Train,
    Test,
}

/// Tiles a dataset's first samples into one PNG: a row per sample, a column per image.
#[derive(Parser)]
struct Args {
    /// Dataset directory (from `rendernet dataset`).
    dir: PathBuf,
    /// Split to show.
    #[arg(value_enum, default_value = "train")]
    split: Which,
    /// Samples (rows) to show, at most the split's size.
    #[arg(default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..))]
    samples: u32,
    /// Where to write the PNG.
    #[arg(default_value = "dataset-preview.png", value_parser = common::png_out)]
    out: PathBuf,
}


fn run(a: Args) -> Result<(), Box<dyn std::error::Error>> {
    let ds = Dataset::open(&a.dir)?;
    let view = ds.split(match a.split {
        Which::Train => Split::Train,
        Which::Test => Split::Test,
    });
    let n = (a.samples as usize).min(view.len());
    let s = ds.manifest.image as u32;
    let mut sheet = None;
    for i in 0..n {
        let sample = view.get(i)?;
        let cols = sample.images.len() as u32;
        let sheet = sheet.get_or_insert_with(|| image::RgbImage::new(s * cols, s * n as u32));
        for (c, img) in sample.images.values().enumerate() {
            image::imageops::replace(sheet, &img.to_rgb8(), (c as u32 * s) as i64, (i as u32 * s) as i64);
        }
        println!(
            "{i}: shape {} view {:?} light az {:.0} el {:.0}",
            sample.shape_id, sample.view, sample.light.azimuth, sample.light.elevation
        );
    }
    let sheet = sheet.ok_or(format!("{}: the split has no samples", a.dir.display()))?;
    write_png(&image::DynamicImage::ImageRgb8(sheet), &a.out)?;
    println!("wrote {} (columns: {:?})", a.out.display(), view.get(0)?.images.keys().collect::<Vec<_>>());
    Ok(())
}

fn main() -> ExitCode {
    common::exit_with(run(Args::parse()))
}
