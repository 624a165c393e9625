//! Renders a procedural chair with every reference shader, the way a dependent crate would
//! use the library, and writes one PNG per shader.
//!
//! `cargo run --example contact_sheet -- [OUT_DIR] [SEED]`

use rendernet::reference::{Light, Renderer, Shader, View};
use rendernet::voxel::shapes;
use rendernet::Gpu;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let out = std::path::PathBuf::from(args.next().unwrap_or_else(|| "contact-sheet".into()));
    let seed: u64 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(0);
    std::fs::create_dir_all(&out)?;
    let gpu = Gpu::new()?;
    let grid = shapes::chair(seed).to_grid(64)?;
    let renderer = Renderer::new(&gpu);
    for shader in Shader::ALL {
        let img = renderer.render(&gpu, &grid, &View::default(), &Light::default(), shader, 128)?;
        let path = out.join(format!("chair{seed}-{}.png", shader.name()));
        img.save_png(&path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
