//! The trained network a command uses: shared by `render`, `invert`, `eval-invert` and
//! `stress`.

use clap::Args;
use rendernet::nn::render::shipped_phong_weights;
use rendernet::nn::rendernet::Preset;
use rendernet::reference::Shader;
use rendernet::{Error, Result};
use std::path::PathBuf;

/// `--weights` and `--preset`.
#[derive(Args, Debug)]
pub struct WeightsArgs {
    /// Weights: a safetensors file from `rendernet train` (<out>.weights.safetensors, or the
    /// checkpoint <out> itself, whose Adam state is ignored); default: the embedded Phong
    /// weights of --preset (tiny or nano).
    #[arg(long)]
    pub weights: Option<PathBuf>,
    /// Network size the weights belong to: tiny (default), nano (faster, less accurate),
    /// small, base or paper (no weights are shipped for the last three: pass --weights).
    #[arg(long, default_value = "tiny")]
    pub preset: String,
}

impl WeightsArgs {
    /// The preset `--preset` names.
    pub fn preset(&self) -> Result<Preset> {
        Preset::by_name(&self.preset)
    }

    /// The weights' bytes and a name for messages (Phong weights).
    pub fn load(&self) -> Result<(Vec<u8>, String)> {
        self.load_for(Shader::Phong)
    }

    /// The weights' bytes and a name for messages, for a network trained on `shader`: the
    /// file given, or the embedded weights of the preset and shader where some are shipped.
    pub fn load_for(&self, shader: Shader) -> Result<(Vec<u8>, String)> {
        if let Some(p) = &self.weights {
            return Ok((std::fs::read(p).map_err(|e| Error::Io { path: p.display().to_string(), source: e })?, p.display().to_string()));
        }
        let preset = self.preset()?;
        match (shader, shipped_phong_weights(&preset)) {
            (Shader::Phong, Some(w)) => Ok((w.to_vec(), format!("embedded {}-phong weights", preset.name))),
            (Shader::Phong, None) => Err(Error::Invalid(format!(
                "--preset {}: no weights are shipped for it; pass --weights FILE (make one with `rendernet train --preset {0}`)",
                preset.name
            ))),
            (s, _) => Err(Error::Invalid(format!(
                "--shader {}: no weights are shipped for it yet; pass --weights FILE (make one with \
                 `rendernet dataset --shader {0} ...` then `rendernet train`)",
                s.name()
            ))),
        }
    }
}
