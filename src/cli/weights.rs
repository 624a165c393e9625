//! The trained network a command uses: shared by `render`, `invert`, `eval-invert` and
//! `stress`.

use clap::Args;
use rendernet::nn::render::{SHIPPED, shipped_for_psnr, shipped_shaders, shipped_weights};
use rendernet::nn::rendernet::Preset;
use rendernet::reference::Shader;
use rendernet::{Error, Result};
use std::path::PathBuf;

/// `--weights` and `--preset`.
#[derive(Args, Debug)]
pub struct WeightsArgs {
    /// Weights: a safetensors file from `rendernet train` (<out>.weights.safetensors, or the
    /// checkpoint <out> itself, whose Adam state is ignored); default: the embedded weights of
    /// --preset for the shader (Phong: nano, tiny or base; ao, toon and contour: tiny).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Network size the weights belong to: tiny (default), nano (faster, less accurate),
    /// small, base or paper, or the baselines ec and ec-deep (no weights are shipped for
    /// these: pass --weights).
    #[arg(long, default_value = "tiny")]
    pub preset: String,
    /// Pick the shipped Phong model instead of --preset: fast (nano), balanced (tiny) or best
    /// (base, the most accurate); their measured speed and accuracy are in the README.
    #[arg(long, value_enum, conflicts_with_all = ["weights", "target_psnr"])]
    pub quality: Option<Quality>,
    /// Pick the fastest shipped Phong model whose held-out object PSNR (README table) is at
    /// least this many dB; an error names the best there is when none reaches it.
    #[arg(long, value_name = "DB", conflicts_with = "weights", allow_negative_numbers = true)]
    pub target_psnr: Option<f64>,
}

/// `--quality`: a rung of the shipped speed/accuracy ladder.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum Quality {
    /// The fastest shipped model.
    Fast,
    /// The default: the middle of the ladder.
    Balanced,
    /// The most accurate shipped model.
    Best,
}

impl WeightsArgs {
    /// The preset `--preset` names, or the shipped one `--quality` / `--target-psnr` picks.
    pub fn preset(&self) -> Result<Preset> {
        let picked = match (self.quality, self.target_psnr) {
            (Some(Quality::Fast), _) => SHIPPED[0].preset,
            (Some(Quality::Balanced), _) => SHIPPED[SHIPPED.len() / 2].preset,
            (Some(Quality::Best), _) => SHIPPED[SHIPPED.len() - 1].preset,
            (None, Some(db)) => shipped_for_psnr(db)?.preset,
            (None, None) => &self.preset,
        };
        Preset::by_name(picked)
    }

    /// The weights' bytes and a name for messages (Phong weights).
    pub fn load(&self) -> Result<(Vec<u8>, String)> {
        self.load_for(Shader::Phong)
    }

    /// The weights' bytes and a name for messages, for a network trained on `shader`: the
    /// file given, or the embedded weights of the preset and shader where some are shipped.
    pub fn load_for(&self, shader: Shader) -> Result<(Vec<u8>, String)> {
        self.load_for_grid(shader, false)
    }

    /// [`WeightArgs::load_for`] for a grid that may have colour: without `--weights`, a
    /// coloured grid gets the preset's shipped colour weights where there are some (grey
    /// weights would ignore its colour).
    pub fn load_for_grid(&self, shader: Shader, coloured: bool) -> Result<(Vec<u8>, String)> {
        if let Some(p) = &self.weights {
            return Ok((std::fs::read(p).map_err(|e| Error::Io { path: p.display().to_string(), source: e })?, p.display().to_string()));
        }
        let preset = self.preset()?;
        if coloured && let Some(w) = shipped_weights(&preset.clone().with_colour(), shader) {
            return Ok((w.to_vec(), format!("embedded {}-{}-colour weights", preset.name, shader.name())));
        }
        shipped_weights(&preset, shader).map(|w| (w.to_vec(), format!("embedded {}-{} weights", preset.name, shader.name()))).ok_or_else(|| {
            let shipped = shipped_shaders().iter().map(|(s, names)| format!("{} ({})", s.name(), names.join(", "))).collect::<Vec<_>>().join(", ");
            Error::Invalid(format!(
                "--shader {} --preset {}: no weights are shipped for it (shipped: {shipped}); pass --weights FILE \
                 (make one with `rendernet dataset --shader {0} ...` then `rendernet train --preset {1}`)",
                shader.name(),
                preset.name
            ))
        })
    }
}
