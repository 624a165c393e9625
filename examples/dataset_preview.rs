//! Tiles the first images of a dataset written by `rendernet dataset` into one PNG, one row per
//! sample and one column per image tensor, to eyeball what a model will be trained on.
//!
//! `cargo run --example dataset_preview -- DIR [train|test] [SAMPLES] [OUT.png]`

use rendernet::data::{Dataset, Split};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let dir = args
        .first()
        .ok_or("usage: dataset_preview DIR [train|test] [SAMPLES] [OUT.png]")?;
    let split = if args.get(1).map(String::as_str) == Some("test") {
        Split::Test
    } else {
        Split::Train
    };
    let n: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(8);
    let out = args
        .get(3)
        .cloned()
        .unwrap_or_else(|| "dataset-preview.png".into());
    let ds = Dataset::open(dir)?;
    let view = ds.split(split);
    let n = n.min(view.len());
    let s = ds.manifest.image as u32;
    let mut sheet = None;
    for i in 0..n {
        let sample = view.get(i)?;
        let cols = sample.images.len() as u32;
        let sheet = sheet.get_or_insert_with(|| image::RgbImage::new(s * cols, s * n as u32));
        for (c, img) in sample.images.values().enumerate() {
            image::imageops::replace(
                sheet,
                &img.to_rgb8(),
                (c as u32 * s) as i64,
                (i as u32 * s) as i64,
            );
        }
        println!(
            "{i}: shape {} view {:?} light az {:.0} el {:.0}",
            sample.shape_id, sample.view, sample.light.azimuth, sample.light.elevation
        );
    }
    sheet.ok_or("no samples")?.save(&out)?;
    println!(
        "wrote {out} (columns: {:?})",
        view.get(0)?.images.keys().collect::<Vec<_>>()
    );
    Ok(())
}
