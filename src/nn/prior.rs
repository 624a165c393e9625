//! The 3D shape autoencoder the paper trains as a shape prior for inverse rendering
//! (appendix, "3D shape autoencoder"): strided 3D convs, a fully-connected layer to a
//! latent code squashed by a sigmoid, a fully-connected layer back to a small grid, and 3D
//! transposed convs up to the input resolution, ELU between layers and a sigmoid at the end.
//! Inverse rendering searches the code and renders the decoded grid (MAP with the decoder
//! as the prior). Sizes are scaled to the 32^3 grids trained here (the paper: 64^3, 200
//! latents, 64-512 channels).

use super::rendernet::Builder;
use crate::error::{Error, Result};
use crate::graph::{Graph, Op, Value};
use crate::ops::conv::{Conv, Padding};
use crate::ops::conv_transpose::ConvTranspose;
use crate::ops::loss::Loss;

/// The shipped shape prior ([`PriorPreset::small`]) trained on procedural chairs, with its
/// code statistics (see `weights/README.md`).
pub static PRIOR_CHAIRS_WEIGHTS: &[u8] = include_bytes!("../../weights/prior-chairs.safetensors");

/// Sizes of a shape autoencoder.
#[derive(Clone, Debug, PartialEq)]
pub struct PriorPreset {
    /// Name, for messages and files.
    pub name: &'static str,
    /// Grid side (a multiple of 16: four stride-2 convs, the decoder starts at `res / 8`).
    pub res: usize,
    /// Channels of the four encoder convs (kernels 5, 5, 2, 2, stride 2 each, as the paper).
    pub enc: [usize; 4],
    /// Latent code length.
    pub latent: usize,
    /// Channels of the decoder's starting grid and of its three stride-2 transposed convs.
    pub dec: [usize; 4],
}

impl PriorPreset {
    /// The size trained here: 32^3 grids, a 64-number code.
    pub fn small() -> PriorPreset {
        PriorPreset { name: "prior-small", res: 32, enc: [8, 16, 32, 64], latent: 64, dec: [32, 16, 8, 8] }
    }
}

/// A built autoencoder and the values a caller feeds and reads.
pub struct ShapePrior {
    /// The graph.
    pub graph: Graph,
    /// Input occupancy `[N, 1, R, R, R]` (values in 0..1) in RenderNet's input layout
    /// (`nn::camera::input_values`), also the reconstruction target.
    pub grid: Value,
    /// The latent code `[N, L, 1, 1]` (after the sigmoid).
    pub code: Value,
    /// Reconstructed occupancy probabilities `[N, 1, R, R, R]`.
    pub recon: Value,
    /// BCE of the reconstruction against the input, when built with a loss.
    pub loss: Option<Value>,
}

impl ShapePrior {
    /// The autoencoder for batch `n`; with `with_loss`, BCE(recon, grid).
    pub fn build(p: &PriorPreset, n: usize, with_loss: bool) -> Result<ShapePrior> {
        if p.res % 16 != 0 || p.res == 0 {
            return Err(Error::Invalid(format!("prior grid side {} must be a positive multiple of 16", p.res)));
        }
        let mut g = Graph::new();
        let mut b = Builder { g: &mut g };
        let r = p.res;
        let grid = b.g.input("grid", &[n, 1, r, r, r])?;
        let mut x = grid;
        for (i, (&c, k)) in p.enc.iter().zip([5, 5, 2, 2]).enumerate() {
            x = b.conv(&format!("enc.conv{i}"), x, c, Conv::conv3d([k; 3], [2; 3], Padding::Same))?;
            x = b.g.apply(&format!("enc.act{i}"), Op::Elu(1.0), &[x])?;
        }
        let flat = p.enc[3] * (r / 16).pow(3);
        x = b.g.apply("enc.flat", Op::Reshape(vec![n, flat, 1, 1]), &[x])?;
        x = b.dense("enc.fc", x, p.latent)?;
        let code = b.g.apply("code", Op::Sigmoid, &[x])?;
        let recon = decoder(&mut b, p, code)?;
        let loss = if with_loss { Some(g.apply("loss", Op::Loss(Loss::Bce), &[recon, grid])?) } else { None };
        Ok(ShapePrior { graph: g, grid, code, recon, loss })
    }
}

/// The decoder on `code` (`[N, L, 1, 1]`, in 0..1): occupancy probabilities `[N, 1, R, R, R]`
/// in RenderNet's input layout. Its parameters are named `dec.*`.
pub(crate) fn decoder(b: &mut Builder, p: &PriorPreset, code: Value) -> Result<Value> {
    grid_decoder(b, "dec", p.res, p.dec, 1, code, "recon")
}

/// A code `[N, L, 1, 1]` decoded into a grid `[N, out, res, res, res]` with values in 0..1
/// (the appendix's decoder: a fully-connected layer to a `res / 8` grid of `dec[0]` channels,
/// three stride-2 3D transposed convs of `dec[1..]` channels, a 3^3 conv to `out` channels,
/// ELU between layers and a sigmoid at the end). Parameters are named `{prefix}.*`; the
/// output value is named `output`. Shared by the shape prior and the texture decoder.
pub(crate) fn grid_decoder(b: &mut Builder, prefix: &str, res: usize, dec: [usize; 4], out: usize, code: Value, output: &str) -> Result<Value> {
    if res % 8 != 0 || res == 0 {
        return Err(Error::Invalid(format!("a decoded grid's side ({res}) must be a positive multiple of 8")));
    }
    let n = b.g.info(code).shape[0];
    let s = res / 8;
    let mut x = b.dense(&format!("{prefix}.fc"), code, dec[0] * s * s * s)?;
    x = b.g.apply(&format!("{prefix}.fc.act"), Op::Elu(1.0), &[x])?;
    x = b.g.apply(&format!("{prefix}.grid"), Op::Reshape(vec![n, dec[0], s, s, s]), &[x])?;
    for (i, &c) in dec[1..].iter().enumerate() {
        x = b.conv_transpose(&format!("{prefix}.up{i}"), x, c, ConvTranspose::conv3d([4; 3], [2; 3], Padding::Same))?;
        x = b.g.apply(&format!("{prefix}.act{i}"), Op::Elu(1.0), &[x])?;
    }
    x = b.conv(&format!("{prefix}.out"), x, out, Conv::conv3d([3; 3], [1; 3], Padding::Same))?;
    b.g.apply(output, Op::Sigmoid, &[x])
}

/// The prior's decoder in front of RenderNet: a latent code input `code` `[N, L, 1, 1]`
/// decoded into the grid RenderNet renders, for shape recovery by gradient descent on the
/// code (the paper's MAP with the decoder as prior). Load RenderNet's weights and the
/// prior's `dec.*` weights with [`crate::graph::Executor::load_params_parts`].
pub fn decoder_with_renderer(p: &PriorPreset, rp: &crate::nn::rendernet::Preset, head: crate::nn::rendernet::Head, n: usize, cam_hw: [usize; 2]) -> Result<(crate::nn::rendernet::RenderNet, Value)> {
    if p.res != rp.input {
        return Err(Error::Invalid(format!("the prior decodes {}^3 grids; preset '{}' reads {}^3", p.res, rp.name, rp.input)));
    }
    let mut g = Graph::new();
    let code = g.input("code", &[n, p.latent, 1, 1])?;
    let grid = decoder(&mut Builder { g: &mut g }, p, code)?;
    Ok((crate::nn::rendernet::RenderNet::build_on(g, grid, rp, head, cam_hw, false)?, code))
}

/// Intersection over union of two occupancy grids thresholded at 0.5 (1 when both are empty).
pub fn iou(a: &[f32], b: &[f32]) -> f64 {
    let (mut inter, mut uni) = (0usize, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        let (p, q) = (x > 0.5, y > 0.5);
        inter += (p && q) as usize;
        uni += (p || q) as usize;
    }
    if uni == 0 { 1.0 } else { inter as f64 / uni as f64 }
}

/// The distribution of a trained prior's codes over its training shapes, kept in the prior's
/// weights file (tensors `stats.code_mean` `[L]`, `stats.code_std` `[L]`, `stats.codes`
/// `[K, L]`; loaders of the parameters skip `stats.*`): the Gaussian the appendix's MAP
/// search puts on the code, and `K` training shapes' codes to start the search from.
#[derive(Clone, Debug, PartialEq)]
pub struct CodeStats {
    /// Mean code.
    pub mean: Vec<f32>,
    /// Standard deviation of each code entry.
    pub std: Vec<f32>,
    /// Codes of training shapes, `K * L` values, one code after another.
    pub codes: Vec<f32>,
}

/// The prefix of the stats tensors in a prior's weights file.
pub const STATS_PREFIX: &str = "stats.";

impl CodeStats {
    /// Mean and spread of `codes` (`K * latent` values), keeping them all.
    pub fn of(codes: Vec<f32>, latent: usize) -> Result<CodeStats> {
        let k = codes.len() / latent.max(1);
        if latent == 0 || k == 0 || !codes.len().is_multiple_of(latent) {
            return Err(Error::Invalid(format!("code statistics need whole codes of {latent} entries; got {} values", codes.len())));
        }
        let at = |i: usize, j: usize| codes[i * latent + j] as f64;
        let mean: Vec<f64> = (0..latent).map(|j| (0..k).map(|i| at(i, j)).sum::<f64>() / k as f64).collect();
        let std = (0..latent).map(|j| ((0..k).map(|i| (at(i, j) - mean[j]).powi(2)).sum::<f64>() / k as f64).sqrt() as f32).collect();
        Ok(CodeStats { mean: mean.into_iter().map(|m| m as f32).collect(), std, codes })
    }

    /// Code length.
    pub fn latent(&self) -> usize {
        self.mean.len()
    }

    /// The training codes, one slice per shape.
    pub fn training_codes(&self) -> impl Iterator<Item = &[f32]> {
        self.codes.chunks_exact(self.latent())
    }

    /// The stats as named tensors for a weights file.
    pub fn tensors(&self) -> Vec<crate::graph::params::Named> {
        let l = self.latent();
        vec![
            (format!("{STATS_PREFIX}code_mean"), vec![l], self.mean.clone()),
            (format!("{STATS_PREFIX}code_std"), vec![l], self.std.clone()),
            (format!("{STATS_PREFIX}codes"), vec![self.codes.len() / l, l], self.codes.clone()),
        ]
    }

    /// The stats a weights file holds (`None` for a file without them, e.g. a prior trained
    /// before they were kept); `name` labels the file in errors.
    pub fn from_weights(bytes: &[u8], name: &str) -> Result<Option<CodeStats>> {
        let st = safetensors::SafeTensors::deserialize(bytes).map_err(|e| Error::Invalid(format!("{name}: not a valid safetensors file: {e}")))?;
        let get = |k: &str| -> Result<Option<(Vec<usize>, Vec<f32>)>> {
            let Ok(v) = st.tensor(&format!("{STATS_PREFIX}{k}")) else { return Ok(None) };
            if v.dtype() != safetensors::Dtype::F32 {
                return Err(Error::Invalid(format!("{name}: '{STATS_PREFIX}{k}' is {:?}, expected F32", v.dtype())));
            }
            let vals: Vec<f32> = v.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
            if vals.iter().any(|x| !x.is_finite()) {
                return Err(Error::Invalid(format!("{name}: '{STATS_PREFIX}{k}' holds a value that is not finite")));
            }
            Ok(Some((v.shape().to_vec(), vals)))
        };
        let (Some((ms, mean)), Some((ss, std)), Some((cs, codes))) = (get("code_mean")?, get("code_std")?, get("codes")?) else {
            return Ok(None);
        };
        let l = mean.len();
        if ms.len() != 1 || ss != ms || cs.len() != 2 || cs[1] != l || cs[0] == 0 {
            return Err(Error::Invalid(format!("{name}: code stats have shapes {ms:?}, {ss:?}, {cs:?}; expected [L], [L], [K, L] with K >= 1")));
        }
        Ok(Some(CodeStats { mean, std, codes }))
    }
}
