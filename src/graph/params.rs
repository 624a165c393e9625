//! Parameter initialisation and safetensors I/O: weights files (parameters only, PyTorch
//! layouts and the graph's value names) and checkpoints (parameters, Adam moments under
//! `adam.m.<name>` / `adam.v.<name>`, and the step in the metadata). Files are written
//! atomically: a temporary file in the same folder, fsync, rename, so a crash leaves either
//! the old file or the new one, never a torn one.

use super::exec::Executor;
use crate::error::{Error, Result};
use crate::gpu::Gpu;
use crate::rng::SplitMix64;
use safetensors::{Dtype, SafeTensors, tensor::TensorView};
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

/// How a parameter starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Init {
    /// Glorot/Xavier uniform, as the original code: U(±sqrt(6 / (fan_in + fan_out))) with
    /// fans from an OI... or IO... weight shape (symmetric, so transposed layouts agree).
    Xavier,
    /// He/Kaiming uniform for ReLU-like layers: U(±sqrt(6 / fan_in)).
    He,
    /// Every element this value (biases 0.001 and PReLU slopes 0 in the original code).
    Constant(f32),
    /// For a stride-2 4x4 transposed conv `[I, O, 4, 4]`: a Xavier 3x3 kernel convolved with
    /// a 2x2 box. Such a layer starts out as nearest-neighbour upsampling followed by that
    /// 3x3 conv, so its four output phases sum the same weights and a flat input gives a flat
    /// output: no checkerboard at initialisation (Odena et al. 2016, "Deconvolution and
    /// checkerboard artifacts"). Other shapes fall back to [`Init::Xavier`].
    XavierUpsample,
}

impl Init {
    /// Initial values for `shape`, a pure function of (seed, salt).
    pub fn values(&self, shape: &[usize], seed: u64, salt: u64) -> Vec<f32> {
        let n: usize = shape.iter().product();
        let receptive: usize = shape.iter().skip(2).product();
        let fan_out = shape[0] * receptive;
        let fan_in = shape.get(1).copied().unwrap_or(1) * receptive;
        let limit = match self {
            Init::Constant(c) => return vec![*c; n],
            Init::XavierUpsample if shape.len() == 4 && shape[2..] == [4, 4] => {
                return upsample_kernels(shape[0], shape[1], seed, salt);
            }
            Init::Xavier | Init::XavierUpsample => (6.0 / (fan_in + fan_out) as f64).sqrt(),
            Init::He => (6.0 / fan_in as f64).sqrt(),
        };
        let mut rng = SplitMix64::keyed(seed, salt);
        (0..n).map(|_| ((2.0 * rng.next_f64() - 1.0) * limit) as f32).collect()
    }
}

/// `[ci, co, 4, 4]` kernels, each a Xavier 3x3 kernel convolved with a 2x2 box (see
/// [`Init::XavierUpsample`] and [`super::resize_conv`]).
fn upsample_kernels(ci: usize, co: usize, seed: u64, salt: u64) -> Vec<f32> {
    Init::Xavier.values(&[ci, co, 3, 3], seed, salt).chunks(9).flat_map(super::resize_conv::expand).collect()
}

/// A named f32 tensor read from or written to a file.
pub type Named = (String, Vec<usize>, Vec<f32>);

/// Writes tensors and metadata to `path` atomically.
pub fn save_safetensors(path: &Path, tensors: &[Named], metadata: HashMap<String, String>) -> Result<()> {
    let io = |e: std::io::Error| Error::Io { path: path.display().to_string(), source: e };
    let bytes: Vec<Vec<u8>> = tensors.iter().map(|t| bytemuck::cast_slice(&t.2).to_vec()).collect();
    let views = tensors
        .iter()
        .zip(&bytes)
        .map(|(t, b)| TensorView::new(Dtype::F32, t.1.clone(), b).map(|v| (t.0.clone(), v)))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
    let meta = if metadata.is_empty() { None } else { Some(metadata) };
    let data = safetensors::serialize(views, meta).map_err(|e| Error::Invalid(format!("{}: {e}", path.display())))?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = dir.join(format!(".{}.tmp", path.file_name().and_then(|n| n.to_str()).unwrap_or("out")));
    {
        let mut f = std::fs::File::create(&tmp).map_err(io)?;
        f.write_all(&data).map_err(io)?;
        f.sync_all().map_err(io)?;
    }
    std::fs::rename(&tmp, path).map_err(io)?;
    // Make the rename itself durable.
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Reads every tensor of a safetensors file as f32 (other dtypes are an error naming the
/// tensor), with the file's metadata.
pub fn load_safetensors(path: &Path) -> Result<(BTreeMap<String, (Vec<usize>, Vec<f32>)>, HashMap<String, String>)> {
    let data = std::fs::read(path).map_err(|e| Error::Io { path: path.display().to_string(), source: e })?;
    parse_safetensors(&data, &path.display().to_string())
}

/// [`load_safetensors`] on bytes already in memory (embedded weights); `p` names them in errors.
/// Every tensor that is not finite F32 is listed in one error.
pub fn parse_safetensors(data: &[u8], p: &str) -> Result<(BTreeMap<String, (Vec<usize>, Vec<f32>)>, HashMap<String, String>)> {
    let (out, bad, meta) = decode(data, p)?;
    if !bad.is_empty() {
        let list: Vec<String> = bad.iter().map(|(name, why)| format!("tensor '{name}' {why}")).collect();
        return Err(Error::Invalid(format!("{p}: {}", list.join("; "))));
    }
    Ok((out, meta))
}

/// Tensors decoded as f32, what is wrong with each other tensor (its dtype is not F32, or a
/// value is not finite), and the metadata; only an unreadable file is an error, so callers
/// can report every problem at once.
#[allow(clippy::type_complexity)]
fn decode(data: &[u8], p: &str) -> Result<(BTreeMap<String, (Vec<usize>, Vec<f32>)>, BTreeMap<String, String>, HashMap<String, String>)> {
    let st = SafeTensors::deserialize(data).map_err(|e| Error::Invalid(format!("{p}: not a valid safetensors file: {e}")))?;
    let (_, meta) = SafeTensors::read_metadata(data).map_err(|e| Error::Invalid(format!("{p}: {e}")))?;
    let (mut out, mut bad) = (BTreeMap::new(), BTreeMap::new());
    for (name, view) in st.tensors() {
        if view.dtype() != Dtype::F32 {
            bad.insert(name, format!("is {:?}, expected F32", view.dtype()));
            continue;
        }
        let vals: Vec<f32> = view.data().chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        if let Some(i) = vals.iter().position(|v| !v.is_finite()) {
            bad.insert(name, format!("holds {} at index {i}", vals[i]));
            continue;
        }
        out.insert(name, (view.shape().to_vec(), vals));
    }
    Ok((out, bad, meta.metadata().clone().unwrap_or_default()))
}

/// Whether `name` is optimizer state in a checkpoint (see [`Executor::save_checkpoint`]).
/// Tensors a file may hold beside the parameters: a checkpoint's Adam moments, and the code
/// statistics a shape prior keeps with its weights (`nn::prior::CodeStats`).
fn is_state(name: &str) -> bool {
    name.starts_with("adam.m.") || name.starts_with("adam.v.") || name.starts_with(crate::nn::prior::STATS_PREFIX)
}

impl Executor {
    fn param_tensors(&self, gpu: &Gpu) -> Result<Vec<Named>> {
        self.graph()
            .params()
            .into_iter()
            .map(|v| {
                let info = self.graph().info(v);
                Ok((info.name.clone(), info.shape.clone(), self.read(gpu, v)?))
            })
            .collect()
    }

    /// Saves the parameters (the shippable weights) to `path`, with [`Executor::notes`] as
    /// metadata.
    pub fn save_params(&self, gpu: &Gpu, path: &Path) -> Result<()> {
        save_safetensors(path, &self.param_tensors(gpu)?, self.notes.clone())
    }

    /// Loads parameters from `path`: a weights file, or a checkpoint whose Adam moments are
    /// ignored (its parameters are the same tensors the weights file beside it holds). Every
    /// parameter must be present, F32, finite and of its shape; all missing, unexpected,
    /// mis-shaped and mis-typed tensors are reported together.
    pub fn load_params(&mut self, gpu: &Gpu, path: &Path) -> Result<()> {
        let data = std::fs::read(path).map_err(|e| Error::Io { path: path.display().to_string(), source: e })?;
        self.load_params_bytes(gpu, &data, &path.display().to_string())
    }

    /// [`Executor::load_params`] on safetensors bytes (e.g. weights embedded in the binary).
    pub fn load_params_bytes(&mut self, gpu: &Gpu, bytes: &[u8], name: &str) -> Result<()> {
        self.load_params_parts(gpu, &[(bytes, name, "")])
    }

    /// Loads the parameters of a graph made of several trained models from their files:
    /// each `(bytes, name, prefix)` gives the tensors whose names start with `prefix` (""
    /// for all), e.g. RenderNet's weights and a shape prior's `dec.` decoder. Together they
    /// must hold every parameter exactly once, as [`Executor::load_params_bytes`] checks.
    pub fn load_params_parts(&mut self, gpu: &Gpu, parts: &[(&[u8], &str, &str)]) -> Result<()> {
        let (mut file, mut bad) = (BTreeMap::new(), BTreeMap::new());
        for &(bytes, name, prefix) in parts {
            let (f, b, _) = decode(bytes, name)?;
            // A checkpoint passed where weights are expected: its parameters serve as they
            // are; the optimizer state is of no use outside training, so it is not "unexpected"
            // (nor are a prior's code statistics).
            let keep = |k: &String| !is_state(k) && k.starts_with(prefix);
            for (k, v) in f.into_iter().filter(|(k, _)| keep(k)) {
                if file.insert(k.clone(), v).is_some() {
                    return Err(Error::Invalid(format!("{name}: '{k}' is also in an earlier file")));
                }
            }
            bad.extend(b.into_iter().filter(|(k, _)| keep(k)));
        }
        let label = parts.iter().map(|p| p.1).collect::<Vec<_>>().join(" + ");
        self.take_params(gpu, Path::new(&label), &mut file, &bad)
    }

    /// Starts from another model's weights where they fit: every parameter whose name and
    /// shape match a tensor of `bytes` takes its values (a checkpoint's Adam state is
    /// ignored); the rest keep their initialisation. For fine-tuning one trunk under new heads
    /// (a Phong network's layers under a contour head). A grey model's tensors also seed a
    /// coloured model's wider ones (see [`widen`]), so a colour network starts out rendering
    /// exactly what the grey one did. An error when nothing matches (another preset's weights).
    pub fn load_params_matching(&mut self, gpu: &Gpu, bytes: &[u8], name: &str) -> Result<InitReport> {
        let (file, _, _) = decode(bytes, name)?;
        let mut r = InitReport::default();
        for v in self.graph().params() {
            let info = self.graph().info(v).clone();
            match file.get(&info.name).filter(|_| !is_state(&info.name)) {
                Some((shape, vals)) if *shape == info.shape => {
                    self.feed(gpu, v, vals)?;
                    r.loaded.push(info.name);
                }
                Some((shape, vals)) => match widen(shape, vals, &info.shape) {
                    Some(w) => {
                        self.feed(gpu, v, &w)?;
                        r.widened.push(info.name);
                    }
                    None => r.fresh.push(info.name),
                },
                None => r.fresh.push(info.name),
            }
        }
        if r.loaded.is_empty() && r.widened.is_empty() {
            return Err(Error::Invalid(format!("{name}: no tensor matches the model's parameters by name and shape (another preset's weights?)")));
        }
        Ok(r)
    }

    /// Feeds every parameter from `file`, which must hold exactly the parameters (a name in
    /// `bad` is present but unusable, for the reason given), or lists every problem.
    fn take_params(
        &mut self,
        gpu: &Gpu,
        path: &Path,
        file: &mut BTreeMap<String, (Vec<usize>, Vec<f32>)>,
        bad: &BTreeMap<String, String>,
    ) -> Result<()> {
        let mut problems = Vec::new();
        let mut ok = Vec::new();
        for v in self.graph().params() {
            let info = self.graph().info(v);
            match file.remove(&info.name) {
                None => match bad.get(&info.name) {
                    Some(why) => problems.push(format!("'{}' {why}", info.name)),
                    None => problems.push(format!("missing '{}' {:?}", info.name, info.shape)),
                },
                Some((shape, _)) if shape != info.shape => {
                    problems.push(format!("'{}' has shape {shape:?}, the model needs {:?}", info.name, info.shape))
                }
                Some((_, vals)) => ok.push((v, vals)),
            }
        }
        let is_param = |k: &str| self.graph().params().into_iter().any(|v| self.graph().info(v).name == k);
        problems.extend(file.keys().chain(bad.keys().filter(|k| !is_param(k))).map(|k| format!("unexpected '{k}'")));
        if !problems.is_empty() {
            return Err(Error::Invalid(format!("{}: does not match the model: {}", path.display(), problems.join("; "))));
        }
        for (v, vals) in ok {
            self.feed(gpu, v, &vals)?;
        }
        Ok(())
    }

    /// Saves parameters, Adam moments, the step and the seed to `path`, atomically.
    pub fn save_checkpoint(&self, gpu: &Gpu, path: &Path) -> Result<()> {
        let mut tensors = self.param_tensors(gpu)?;
        for v in self.graph().params() {
            if let Some((m, s)) = &self.adam_state[v.0] {
                let info = self.graph().info(v);
                tensors.push((format!("adam.m.{}", info.name), info.shape.clone(), m.to_vec(gpu)?));
                tensors.push((format!("adam.v.{}", info.name), info.shape.clone(), s.to_vec(gpu)?));
            }
        }
        let mut meta = self.notes.clone();
        meta.extend([("step".to_string(), self.step.to_string()), ("seed".to_string(), self.seed.to_string())]);
        save_safetensors(path, &tensors, meta)
    }

    /// Restores a checkpoint written by [`Executor::save_checkpoint`] for this graph, so that
    /// training continues exactly as if it had not stopped.
    pub fn load_checkpoint(&mut self, gpu: &Gpu, path: &Path) -> Result<()> {
        let (mut file, meta) = load_safetensors(path)?;
        let field = |k: &str| -> Result<u64> {
            meta.get(k)
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| Error::Invalid(format!("{}: checkpoint metadata lacks a numeric '{k}'", path.display())))
        };
        let (step, seed) = (field("step")?, field("seed")?);
        let mut moments = BTreeMap::new();
        file.retain(|k, v| {
            if k.starts_with("adam.") {
                moments.insert(k.clone(), v.clone());
                false
            } else {
                true
            }
        });
        self.take_params(gpu, path, &mut file, &BTreeMap::new())?;
        for v in self.graph().params() {
            let info = self.graph().info(v).clone();
            let (m, s) = (moments.remove(&format!("adam.m.{}", info.name)), moments.remove(&format!("adam.v.{}", info.name)));
            self.adam_state[v.0] = match (m, s) {
                (Some((ms, m)), Some((vs, s))) if ms == info.shape && vs == info.shape => {
                    let (tm, ts) = self.moments_of(gpu, v)?;
                    tm.write(gpu, &m)?;
                    ts.write(gpu, &s)?;
                    Some((tm, ts))
                }
                (None, None) => {
                    // Fresh moments: zero what an earlier run of this executor left there.
                    let (tm, ts) = self.moments_of(gpu, v)?;
                    let zeros = vec![0.0; tm.numel()];
                    tm.write(gpu, &zeros)?;
                    ts.write(gpu, &zeros)?;
                    None
                }
                _ => return Err(Error::Invalid(format!("{}: Adam moments of '{}' are incomplete or mis-shaped", path.display(), info.name))),
            };
        }
        if let Some(k) = moments.keys().next() {
            return Err(Error::Invalid(format!("{}: unexpected '{k}'", path.display())));
        }
        self.step = step;
        self.seed = seed;
        Ok(())
    }
}

/// What [`Executor::load_params_matching`] did with each parameter.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InitReport {
    /// Taken as they were (same name and shape).
    pub loaded: Vec<String>,
    /// Taken from a grey model's narrower tensor of the same name (see [`widen`]).
    pub widened: Vec<String>,
    /// Left as initialised (absent, or a shape no rule maps).
    pub fresh: Vec<String>,
}

/// `vals` of shape `from` grown to `to` where a grey model's tensor maps onto a coloured
/// model's: one input channel to several along axis 1 (`[O, 1, k..] -> [O, C, k..]`: the
/// first channel, occupancy in both models, keeps the weights, the colour channels start at
/// zero), or one output channel to several along axis 0 (`[1, ..] -> [C, ..]`, biases
/// included: replicated, so a grey albedo becomes the same value in R, G and B). `None` for
/// any other difference.
pub fn widen(from: &[usize], vals: &[f32], to: &[usize]) -> Option<Vec<f32>> {
    if from.len() != to.len() || from.is_empty() || vals.len() != from.iter().product::<usize>() {
        return None;
    }
    let differs: Vec<usize> = (0..from.len()).filter(|&a| from[a] != to[a]).collect();
    match differs[..] {
        [0] if from[0] == 1 => Some(vals.repeat(to[0])),
        [1] if from[1] == 1 => {
            let inner: usize = from[2..].iter().product();
            let mut out = vec![0.0; to.iter().product()];
            for o in 0..from[0] {
                let dst = o * to[1] * inner;
                out[dst..dst + inner].copy_from_slice(&vals[o * inner..(o + 1) * inner]);
            }
            Some(out)
        }
        _ => None,
    }
}

#[cfg(test)]
mod widen_tests {
    use super::widen;

    #[test]
    fn grey_tensors_widen_to_colour_ones() {
        // [O=2, I=1, k=3] -> [2, 3, 3]: channel 0 keeps the weights, the others are zero.
        let w = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let got = widen(&[2, 1, 3], &w, &[2, 3, 3]).unwrap();
        assert_eq!(got, [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 4.0, 5.0, 6.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        // [1, I=2, k=1] -> [3, 2, 1]: replicated per output channel; a bias [1] -> [3].
        assert_eq!(widen(&[1, 2, 1], &[7.0, 8.0], &[3, 2, 1]).unwrap(), [7.0, 8.0, 7.0, 8.0, 7.0, 8.0]);
        assert_eq!(widen(&[1], &[0.5], &[3]).unwrap(), [0.5, 0.5, 0.5]);
        // Anything else is not a grey -> colour map.
        assert_eq!(widen(&[2, 2, 3], &[0.0; 12], &[2, 4, 3]), None);
        assert_eq!(widen(&[1, 1, 3], &[0.0; 3], &[2, 2, 3]), None);
        assert_eq!(widen(&[2, 1], &[0.0; 2], &[2, 1, 1]), None);
    }
}
