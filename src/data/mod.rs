//! Training and test sets: the on-disk format `rendernet-dataset-1`, its reader, and (in
//! [`generate`]) the generator behind `rendernet dataset`.
//!
//! # Format
//! A directory holding `manifest.json` and safetensors shards of up to [`SHARD_SIZE`] samples,
//! `train-00000.safetensors`, ..., `test-00000.safetensors`, .... Each shard of `K` samples has
//! - `grids` U8 `[K, R, R, R]`: the network's input occupancy times 255, rounded;
//! - `views` F32 `[K, 3]`: camera azimuth (deg), elevation (deg), radius ([`View`]);
//! - `lights` F32 `[K, 5]`: light azimuth (deg), elevation (deg), r, g, b ([`Light`]; the
//!   material constants are the manifest's `light`);
//! - `shape_ids` F32 `[K]`: the shape's index `i` (train and test never share one);
//! - `colours` U8 `[K, 3, R, R, R]`, only in coloured datasets (manifest `colour: true`): the
//!   input grid's RGB times 255 (the colour of empty voxels is 0 and means nothing);
//! - images U8 `[K, C, S, S]` (value times 255, rounded): for shader `phong` the tensors
//!   `phong` (3), `normal` (3), `albedo` (1, grey; 3 in coloured datasets) and `mask` (1);
//!   for any other shader one tensor `image` with that shader's channels.
//!
//! Samples are stored shape-major (all views of shape 0, then shape 1, ...), so sample `j` of
//! a split lives in shard `j / SHARD_SIZE` at row `j % SHARD_SIZE`.

pub mod generate;
mod manifest;

pub use generate::{GenerateOptions, Shapes, Summary, generate};
pub use manifest::{LightParams, Manifest, SplitInfo};

use crate::error::{Error, Result};
use crate::reference::{Image, Light, Shader, View};
use crate::voxel::VoxelGrid;
use safetensors::Dtype;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The manifest's `format` value.
pub const FORMAT: &str = "rendernet-dataset-1";
/// Most samples in one shard.
pub const SHARD_SIZE: usize = 256;
/// Manifest file name inside a dataset directory.
pub const MANIFEST: &str = "manifest.json";
/// Input grids tensor.
pub const GRIDS: &str = "grids";
/// Input grid colours tensor (coloured datasets only).
pub const COLOURS: &str = "colours";
/// Camera poses tensor.
pub const VIEWS: &str = "views";
/// Lights tensor.
pub const LIGHTS: &str = "lights";
/// Shape index tensor.
pub const SHAPE_IDS: &str = "shape_ids";
/// Largest safetensors header accepted (ours are a few hundred bytes).
const MAX_HEADER: u64 = 1 << 20;

/// Which half of a dataset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Split {
    /// Training samples.
    Train,
    /// Held-out samples, from shapes training never sees.
    Test,
}

impl Split {
    /// `train` or `test`, as in file names and the manifest.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Test => "test",
        }
    }

    /// The shard file name of index `k`, e.g. `train-00003.safetensors`.
    pub fn shard_name(self, k: usize) -> String {
        format!("{}-{k:05}.safetensors", self.name())
    }
}

/// The image tensors a dataset of `shader` stores: `(tensor name, shader rendered, channels)`.
/// Phong datasets also carry the normal map, albedo and mask, which a shading network or its
/// losses may want; albedo is stored grey (channel 0) unless the grids are coloured.
pub fn image_outputs(shader: Shader, colour: bool) -> Vec<(&'static str, Shader, usize)> {
    match shader {
        Shader::Phong => vec![
            ("phong", Shader::Phong, 3),
            ("normal", Shader::Normal, 3),
            ("albedo", Shader::Albedo, if colour { 3 } else { 1 }),
            ("mask", Shader::Mask, 1),
        ],
        s => vec![("image", s, s.channels())],
    }
}

/// One sample as the model consumes it.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Input occupancy `R^3`, values `u8 / 255`.
    pub grid: VoxelGrid,
    /// Camera pose.
    pub view: View,
    /// Light, with the manifest's material constants.
    pub light: Light,
    /// Index of the shape this view shows.
    pub shape_id: u32,
    /// Target images by tensor name (see [`image_outputs`]), values `u8 / 255`.
    pub images: BTreeMap<String, Image>,
}

/// One shard's tensors, decoded.
/// A shard's small per-sample tensors, read whole, and its open file, from which a sample's
/// grid and images are read at their offsets (a shard is ~40 MB; reading it whole for one
/// random sample cost 66 ms, more than a training step).
struct Shard {
    len: usize,
    views: Vec<f32>,
    lights: Vec<f32>,
    shape_ids: Vec<f32>,
    file: Mutex<std::fs::File>,
    name: String,
    /// File offset of each tensor's first byte.
    offsets: BTreeMap<String, u64>,
}

impl Shard {
    /// `len` bytes of tensor `tensor` from byte `start` of its data.
    fn read(&self, tensor: &str, start: usize, len: usize) -> Result<Vec<u8>> {
        use std::io::Seek;
        let at = self.offsets[tensor] + start as u64;
        let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
        let mut buf = vec![0u8; len];
        f.seek(std::io::SeekFrom::Start(at))
            .and_then(|_| f.read_exact(&mut buf))
            .map_err(|e| Error::Io { path: self.name.clone(), source: e })?;
        Ok(buf)
    }
}

/// An opened dataset: manifest and shard headers validated, shards loaded on demand.
pub struct Dataset {
    dir: PathBuf,
    /// The parsed manifest.
    pub manifest: Manifest,
    outputs: Vec<(&'static str, Shader, usize)>,
    /// Shards opened so far (small: see [`Shard`]).
    cache: Mutex<std::collections::HashMap<(Split, usize), Arc<Shard>>>,
}

/// One split of a [`Dataset`].
#[derive(Clone, Copy)]
pub struct SplitView<'a> {
    ds: &'a Dataset,
    split: Split,
}

impl Dataset {
    /// Opens `dir`: parses `manifest.json` and checks every listed shard's header (tensor
    /// names, dtypes, shapes, file length) against it. Errors name the file and the field.
    pub fn open(dir: impl AsRef<Path>) -> Result<Dataset> {
        let dir = dir.as_ref().to_path_buf();
        let mpath = dir.join(MANIFEST);
        let text = std::fs::read_to_string(&mpath).map_err(|e| Error::Io {
            path: mpath.display().to_string(),
            source: e,
        })?;
        let manifest = Manifest::parse(&text, &mpath.display().to_string())?;
        let outputs = image_outputs(manifest.shader_kind()?, manifest.colour);
        let ds = Dataset {
            dir,
            manifest,
            outputs,
            cache: Mutex::new(Default::default()),
        };
        for split in [Split::Train, Split::Test] {
            for k in 0..ds.info(split).shards.len() {
                ds.check_header(split, k)?;
            }
        }
        Ok(ds)
    }

    /// The directory it was opened from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// One split.
    pub fn split(&self, split: Split) -> SplitView<'_> {
        SplitView { ds: self, split }
    }

    fn info(&self, split: Split) -> &SplitInfo {
        match split {
            Split::Train => &self.manifest.train,
            Split::Test => &self.manifest.test,
        }
    }

    /// `(name, dtype, shape)` of every tensor shard `k` of `split` must hold.
    fn expected(&self, split: Split, k: usize) -> Vec<(String, Dtype, Vec<usize>)> {
        let m = &self.manifest;
        let n = (self.info(split).count - k * SHARD_SIZE).min(SHARD_SIZE);
        let (r, s) = (m.res, m.image);
        let mut v = vec![
            (GRIDS.to_string(), Dtype::U8, vec![n, r, r, r]),
            (VIEWS.to_string(), Dtype::F32, vec![n, 3]),
            (LIGHTS.to_string(), Dtype::F32, vec![n, 5]),
            (SHAPE_IDS.to_string(), Dtype::F32, vec![n]),
        ];
        if m.colour {
            v.push((COLOURS.to_string(), Dtype::U8, vec![n, 3, r, r, r]));
        }
        v.extend(
            self.outputs
                .iter()
                .map(|&(name, _, c)| (name.to_string(), Dtype::U8, vec![n, c, s, s])),
        );
        v
    }

    fn shard_path(&self, split: Split, k: usize) -> PathBuf {
        self.dir.join(&self.info(split).shards[k])
    }

    /// Reads only the header of a shard and checks it (cheap: no tensor data is read);
    /// returns the file offset of each tensor's data.
    fn check_header(&self, split: Split, k: usize) -> Result<BTreeMap<String, u64>> {
        let path = self.shard_path(split, k);
        let name = path.display().to_string();
        let io = |e| Error::Io {
            path: name.clone(),
            source: e,
        };
        let bad = |msg: String| Error::Invalid(format!("{name}: {msg}"));
        let mut f = std::fs::File::open(&path).map_err(io)?;
        let file_len = f.metadata().map_err(io)?.len();
        let mut len8 = [0u8; 8];
        f.read_exact(&mut len8)
            .map_err(|_| bad("truncated: no safetensors header".into()))?;
        let hlen = u64::from_le_bytes(len8);
        if hlen > MAX_HEADER || 8 + hlen > file_len {
            return Err(bad(format!(
                "safetensors header length {hlen} is absurd for a {file_len}-byte file"
            )));
        }
        let mut header = vec![0u8; hlen as usize];
        f.read_exact(&mut header).map_err(io)?;
        let json: serde_json::Value = serde_json::from_slice(&header)
            .map_err(|e| bad(format!("safetensors header is not JSON: {e}")))?;
        let obj = json
            .as_object()
            .ok_or_else(|| bad("safetensors header is not a JSON object".into()))?;
        let mut data_end = 0u64;
        let mut offsets = BTreeMap::new();
        let mut spans = Vec::new();
        let expected = self.expected(split, k);
        for (tname, dtype, shape) in &expected {
            let t = obj
                .get(tname)
                .ok_or_else(|| bad(format!("tensor `{tname}` is missing")))?;
            let got_dtype = t.get("dtype").and_then(|d| d.as_str()).unwrap_or("?");
            if got_dtype != format!("{dtype:?}") {
                return Err(bad(format!(
                    "tensor `{tname}` has dtype {got_dtype}, expected {dtype:?}"
                )));
            }
            let got_shape: Option<Vec<usize>> =
                t.get("shape").and_then(|s| s.as_array()).map(|a| {
                    a.iter()
                        .filter_map(|x| x.as_u64().map(|x| x as usize))
                        .collect()
                });
            if got_shape.as_ref() != Some(shape) {
                return Err(bad(format!(
                    "tensor `{tname}` has shape {got_shape:?}, expected {shape:?}"
                )));
            }
            let at = |i: usize| t.get("data_offsets").and_then(|o| o.get(i)).and_then(|e| e.as_u64());
            let (start, end) = (at(0).unwrap_or(u64::MAX), at(1).unwrap_or(u64::MAX));
            let bytes = shape.iter().product::<usize>() as u64 * if *dtype == Dtype::U8 { 1 } else { 4 };
            if end.checked_sub(start) != Some(bytes) {
                return Err(bad(format!("tensor `{tname}` has data_offsets [{start}, {end}], expected {bytes} bytes")));
            }
            data_end = data_end.max(end);
            spans.push((start, end));
            offsets.insert(tname.clone(), 8 + hlen + start);
        }
        if let Some(extra) = obj
            .keys()
            .find(|k| *k != "__metadata__" && !expected.iter().any(|(n, _, _)| n == *k))
        {
            return Err(bad(format!("unexpected tensor `{extra}`")));
        }
        // The tensors must tile the data section: no overlaps, no gaps.
        spans.sort_unstable();
        if spans.first().is_some_and(|s| s.0 != 0) {
            return Err(bad(format!("tensor data starts at byte {} of the data section, not 0", spans[0].0)));
        }
        if let Some(w) = spans.windows(2).find(|w| w[0].1 != w[1].0) {
            return Err(bad(format!("tensor data overlaps or leaves a gap at bytes {}..{}", w[0].1.min(w[1].0), w[0].1.max(w[1].0))));
        }
        if 8 + hlen + data_end != file_len {
            return Err(bad(format!(
                "file is {file_len} bytes but its header describes {}",
                8 + hlen.saturating_add(data_end)
            )));
        }
        Ok(offsets)
    }

    /// Loads (or takes from the cache) shard `k` of `split`.
    fn shard(&self, split: Split, k: usize) -> Result<Arc<Shard>> {
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = cache.get(&(split, k)) {
            return Ok(s.clone());
        }
        let shard = Arc::new(self.open_shard(split, k)?);
        cache.insert((split, k), shard.clone());
        Ok(shard)
    }

    fn open_shard(&self, split: Split, k: usize) -> Result<Shard> {
        let path = self.shard_path(split, k);
        let name = path.display().to_string();
        // Checked again: the file may have changed since `open`.
        let offsets = self.check_header(split, k)?;
        let file = std::fs::File::open(&path).map_err(|e| Error::Io { path: name.clone(), source: e })?;
        let n = (self.info(split).count - k * SHARD_SIZE).min(SHARD_SIZE);
        let mut shard = Shard { len: n, views: Vec::new(), lights: Vec::new(), shape_ids: Vec::new(), file: Mutex::new(file), name, offsets };
        let f32s = |b: Vec<u8>| b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect::<Vec<f32>>();
        shard.views = f32s(shard.read(VIEWS, 0, n * 3 * 4)?);
        shard.lights = f32s(shard.read(LIGHTS, 0, n * 5 * 4)?);
        shard.shape_ids = f32s(shard.read(SHAPE_IDS, 0, n * 4)?);
        Ok(shard)
    }
}

impl SplitView<'_> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.ds.info(self.split).count
    }

    /// True when the split has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Indices of `samples` samples spread evenly over the split (0 or more than there are:
    /// all), so an evaluation of a few samples still sees every part of the shape list.
    pub fn spread(&self, samples: usize) -> impl Iterator<Item = usize> + use<> {
        let len = self.len();
        let n = if samples == 0 { len } else { samples.min(len) };
        (0..n).map(move |k| k * len / n)
    }

    /// The shape sample `i` shows, without reading its grid or images.
    pub fn shape_id(&self, i: usize) -> Result<u32> {
        self.check(i)?;
        Ok(self.ds.shard(self.split, i / SHARD_SIZE)?.shape_ids[i % SHARD_SIZE] as u32)
    }

    fn check(&self, i: usize) -> Result<()> {
        if i >= self.len() {
            return Err(Error::Invalid(format!(
                "{}: {} sample {i} out of range (0..{})",
                self.ds.dir.display(),
                self.split.name(),
                self.len()
            )));
        }
        Ok(())
    }

    /// Sample `i` (`0..len`), decoding its shard on first use.
    pub fn get(&self, i: usize) -> Result<Sample> {
        let ds = self.ds;
        self.check(i)?;
        let shard = ds.shard(self.split, i / SHARD_SIZE)?;
        let j = i % SHARD_SIZE;
        debug_assert!(j < shard.len);
        let m = &ds.manifest;
        let unpack = |b: &[u8]| b.iter().map(|&x| x as f32 / 255.0).collect::<Vec<f32>>();
        let r3 = m.res * m.res * m.res;
        let mut grid = VoxelGrid::new([m.res; 3], unpack(&shard.read(GRIDS, j * r3, r3)?))
            .map_err(|e| Error::Invalid(e.to_string()))?;
        if m.colour {
            grid = grid.with_colour(unpack(&shard.read(COLOURS, j * 3 * r3, 3 * r3)?)).map_err(|e| Error::Invalid(e.to_string()))?;
        }
        let v = &shard.views[j * 3..j * 3 + 3];
        let l = &shard.lights[j * 5..j * 5 + 5];
        let view = View {
            azimuth: v[0] as f64,
            elevation: v[1] as f64,
            radius: v[2] as f64,
        };
        let light = Light {
            azimuth: l[0] as f64,
            elevation: l[1] as f64,
            colour: [l[2], l[3], l[4]],
            ambient: m.light.ambient,
            kd: m.light.kd,
            ks: m.light.ks,
            shininess: m.light.shininess,
        };
        let s2 = m.image * m.image;
        let images = ds
            .outputs
            .iter()
            .map(|&(name, _, c)| {
                let data = unpack(&shard.read(name, j * c * s2, c * s2)?);
                Ok((name.to_string(), Image { channels: c, size: m.image, data }))
            })
            .collect::<Result<_>>()?;
        Ok(Sample {
            grid,
            view,
            light,
            shape_id: shard.shape_ids[j] as u32,
            images,
        })
    }
}
