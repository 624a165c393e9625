//! The trained network a command uses: shared by `render`, `invert`, `eval-invert`,
//! `eval-shape`, `eval-texture` and `stress`.

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
    /// Network size the weights belong to: nano, tiny, small, base or paper, or the baselines
    /// ec and ec-deep (no weights are shipped for small, paper and the baselines: pass
    /// --weights). Default: the preset a --weights file records (`train` writes it), else
    /// the command's own (render: the most accurate shipped for the shader and grid, base for
    /// grey Phong; invert, eval-invert, stress: tiny, 4x less work per render).
    #[arg(long)]
    pub preset: Option<String>,
    /// Pick the shipped Phong model instead of --preset: fast (nano), balanced (tiny) or best
    /// (base, the most accurate); their measured speed and accuracy are in the README.
    #[arg(long, value_enum, conflicts_with_all = ["weights", "target_psnr"])]
    pub quality: Option<Quality>,
    /// Pick the fastest shipped Phong model whose held-out object PSNR (README table) is at
    /// least this many dB; an error names the best there is when none reaches it.
    #[arg(long, value_name = "DB", conflicts_with = "weights", allow_negative_numbers = true)]
    pub target_psnr: Option<f64>,
}

/// The default preset of the commands that render many images per call (invert, eval-invert,
/// eval-shape, stress): the middle rung, a quarter of base's work per image.
pub const MANY_RENDERS: &str = "tiny";

/// A network's preset and weights, resolved from the flags.
pub struct Loaded {
    /// The preset the weights belong to (before [`Preset::for_weights`] reads their grid side).
    pub preset: Preset,
    /// The safetensors bytes.
    pub bytes: Vec<u8>,
    /// The file, or "embedded P-S weights", for messages.
    pub name: String,
}

/// `--quality`: a rung of the shipped speed/accuracy ladder.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum Quality {
    /// The fastest shipped model.
    Fast,
    /// The middle of the ladder (tiny; the default of invert and stress).
    Balanced,
    /// The most accurate shipped model.
    Best,
}

impl WeightsArgs {
    /// The preset --preset, --quality or --target-psnr names, if any.
    fn named(&self) -> Result<Option<&str>> {
        Ok(match (self.quality, self.target_psnr) {
            (Some(Quality::Fast), _) => Some(SHIPPED[0].preset),
            (Some(Quality::Balanced), _) => Some(SHIPPED[SHIPPED.len() / 2].preset),
            (Some(Quality::Best), _) => Some(SHIPPED[SHIPPED.len() - 1].preset),
            (None, Some(db)) => Some(shipped_for_psnr(db)?.preset),
            (None, None) => self.preset.as_deref(),
        })
    }

    /// The preset and weights for a network trained on `shader`, reading a grid with colour
    /// or not: the --weights file, or the shipped weights of the preset (a coloured grid gets
    /// the preset's colour weights where some are shipped: grey ones would ignore its colour).
    /// The preset is the one named by the flags, else the one a --weights file records, else
    /// `default`.
    pub fn resolve(&self, shader: Shader, coloured: bool, default: &str) -> Result<Loaded> {
        let named = self.named()?;
        if let Some(p) = &self.weights {
            let bytes = std::fs::read(p).map_err(|e| Error::Io { path: p.display().to_string(), source: e })?;
            let name = p.display().to_string();
            let preset = match named {
                Some(n) => Preset::by_name(n)?,
                None => match recorded_preset(&bytes, &name)? {
                    Some(r) => Preset::by_name(&r).map_err(|e| Error::Invalid(format!("{name}: metadata 'preset': {e}; pass --preset")))?,
                    None => Preset::by_name(default)?,
                },
            };
            return Ok(Loaded { preset, bytes, name });
        }
        let preset = Preset::by_name(named.unwrap_or(default))?;
        if coloured && let Some(w) = shipped_weights(&preset.clone().with_colour(), shader) {
            let name = format!("embedded {}-{}-colour weights", preset.name, shader.name());
            return Ok(Loaded { preset, bytes: w.to_vec(), name });
        }
        let Some(w) = shipped_weights(&preset, shader) else {
            let shipped = shipped_shaders().iter().map(|(s, names)| format!("{} ({})", s.name(), names.join(", "))).collect::<Vec<_>>().join(", ");
            return Err(Error::Invalid(format!(
                "--shader {} --preset {}: no weights are shipped for it (shipped: {shipped}); pass --weights FILE \
                 (make one with `rendernet dataset --shader {0} ...` then `rendernet train --preset {1}`)",
                shader.name(),
                preset.name
            )));
        };
        let name = format!("embedded {}-{} weights", preset.name, shader.name());
        Ok(Loaded { preset, bytes: w.to_vec(), name })
    }
}

/// The preset name a weights file's metadata records (`train` writes `preset`), if any.
fn recorded_preset(bytes: &[u8], name: &str) -> Result<Option<String>> {
    let (_, meta) = safetensors::SafeTensors::read_metadata(bytes).map_err(|e| Error::Invalid(format!("{name}: not a safetensors file: {e}")))?;
    Ok(meta.metadata().as_ref().and_then(|m| m.get("preset").cloned()))
}
