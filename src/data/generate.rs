//! The dataset generator behind `rendernet dataset`: shapes, random views and lights from a
//! seeded SplitMix64, targets from the reference renderer, written as sharded safetensors.
//!
//! Determinism: shape `i`'s seed is `SplitMix64(seed, stream i)`'s first output, and its views
//! and lights come from a generator seeded by that value alone, so the bytes depend only on
//! the options (not on batching or timing). Sampling ranges are the paper's (section 4):
//! camera azimuth uniform in [0, 360), elevation (polar) uniform in [10, 170), radius uniform
//! in [3, 6.3); light azimuth uniform in [0, 360) and elevation in [20, 160) relative to the
//! camera, white, for Phong datasets; the networks of other shaders take no light, so their
//! targets are lit by the default light (toon depends on it).

use super::{
    COLOURS, GRIDS, LIGHTS, LightParams, MANIFEST, Manifest, SHAPE_IDS, SHARD_SIZE, Split, SplitInfo, VIEWS,
    image_outputs,
};
use crate::error::{Error, Result};
use crate::gpu::{Gpu, Tensor};
use crate::reference::{GpuGrid, Light, Options, RayMarcher, Shader, View};
use crate::rng::SplitMix64;
use crate::voxel::{Family, Mesh, VoxelGrid, VoxelizeOptions, voxelize};
use safetensors::{Dtype, tensor::TensorView};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Stream separating per-shape seeds from everything else drawn from the user's seed.
const SHAPE_STREAM: u64 = 0x5348_4150; // "SHAP"
/// Stream of a shape's views and lights.
const VIEW_STREAM: u64 = 0x5649_4557; // "VIEW"
/// Views recorded into one submit (bounds the G-buffers alive at once).
const VIEWS_PER_SUBMIT: usize = 16;

/// Where the shapes come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shapes {
    /// Procedural chairs (the training distribution standing in for ShapeNet chairs).
    Chairs,
    /// Meshes (.obj, .off, .ply) under a directory, in file-name order (see `datasets/`).
    Real,
    /// The four furniture and CSG families in turn ([`Family::ALL`]): chair, table, sofa,
    /// primitive, chair, ...
    Mixed,
    /// The four of `Mixed` and the curved creatures in turn: chair, table, sofa, primitive,
    /// creature, chair, ...
    Varied,
}

impl Shapes {
    /// Parses `chairs`, `real`, `mixed` or `varied`.
    pub fn parse(s: &str) -> Option<Shapes> {
        match s {
            "chairs" => Some(Shapes::Chairs),
            "real" => Some(Shapes::Real),
            "mixed" => Some(Shapes::Mixed),
            "varied" => Some(Shapes::Varied),
            _ => None,
        }
    }

    /// The name [`Shapes::parse`] accepts.
    pub fn name(self) -> &'static str {
        match self {
            Shapes::Chairs => "chairs",
            Shapes::Real => "real",
            Shapes::Mixed => "mixed",
            Shapes::Varied => "varied",
        }
    }
}

/// Everything that determines a dataset's bytes.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    /// Shape source.
    pub shapes: Shapes,
    /// Reference shader of the targets.
    pub shader: Shader,
    /// Number of shapes `N`.
    pub count: usize,
    /// Views per shape `V` (so `N * V` samples).
    pub views: usize,
    /// Input grid side `R`.
    pub res: usize,
    /// Side of the grid the targets are rendered from (the smooth iso-surface of a finer
    /// grid); usually `2 * res`.
    pub truth_res: usize,
    /// Image side `S`.
    pub image: usize,
    /// Sub-voxels per axis of the input grids: 1 (the default) gives binary occupancy, as
    /// binvox files are; `k > 1` samples `k^3` points per voxel, so surface voxels hold the
    /// fraction inside (as `render` voxelises a mesh: [`VoxelizeOptions::smooth`]).
    pub input_supersample: usize,
    /// Seed of everything random.
    pub seed: u64,
    /// Fraction of shapes held out: the last `ceil(test_fraction * count)` go to test.
    pub test_fraction: f64,
    /// Camera radius range `[lo, hi)`; the paper's `(3.0, 6.3)` by default ([`PAPER_RADII`]),
    /// `(r, r)` for a fixed distance (evaluation at one framing).
    pub radius: (f64, f64),
    /// Sub-pixels per axis of the targets (anti-aliasing).
    pub supersample: u32,
    /// Ambient-occlusion rays per pixel, a perfect square (stratified directions); fewer
    /// make AO targets cheaper to render and coarser.
    pub ao_rays: u32,
    /// Directory of meshes for [`Shapes::Real`].
    pub real_dir: PathBuf,
    /// Paint the procedural shapes ([`Shape::to_coloured_grid`]): the input grids carry RGB
    /// and Phong targets an RGB albedo map.
    ///
    /// [`Shape::to_coloured_grid`]: crate::voxel::Shape::to_coloured_grid
    pub colour: bool,
}

/// The reference renderer's options for a dataset's targets: `supersample` sub-pixels per
/// axis, `ao_rays` ambient-occlusion rays per pixel (a perfect square in 1..=256).
pub fn target_options(supersample: u32, ao_rays: u32) -> Result<Options> {
    let ao_sqrt = (ao_rays as f64).sqrt().round() as u32;
    if ao_sqrt * ao_sqrt != ao_rays || !(1..=256).contains(&ao_rays) {
        return Err(Error::Invalid(format!("--ao-rays {ao_rays}: must be a perfect square in 1..=256 (4, 16, 64, ...)")));
    }
    Ok(Options { supersample, ao_dirs_sqrt: ao_sqrt, ..Options::default() })
}

/// What [`generate`] wrote.
#[derive(Clone, Debug)]
pub struct Summary {
    /// The manifest as written.
    pub manifest: Manifest,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// The paper's camera radii (Section 4), the default of [`GenerateOptions::radius`].
pub const PAPER_RADII: (f64, f64) = (3.0, 6.3);

/// Seed of shape `i`.
pub fn shape_seed(seed: u64, i: usize) -> u64 {
    SplitMix64::new(seed ^ SHAPE_STREAM, i as u64).next_u64()
}

/// The `views` random `(view, light)` pairs of the shape with seed `shape_seed`, as stored:
/// f32 values, so what is rendered is exactly what the shard records.
/// The radius is drawn from `radius` (one draw whatever the range, so a fixed radius leaves
/// every other value as the paper's range would have drawn it).
pub fn sample_poses(shape_seed: u64, views: usize, radius: (f64, f64)) -> Vec<([f32; 3], [f32; 5])> {
    let mut rng = SplitMix64::new(shape_seed, VIEW_STREAM);
    (0..views)
        .map(|_| {
            let v = [
                rng.range(0.0, 360.0),
                rng.range(10.0, 170.0),
                rng.range(radius.0 as f32, radius.1 as f32),
            ];
            let l = [rng.range(0.0, 360.0), rng.range(20.0, 160.0), 1.0, 1.0, 1.0];
            (v, l)
        })
        .collect()
}

/// Mesh files under `dir` (.obj, .off, .ply), sorted by name.
pub fn real_meshes(dir: &Path) -> Result<Vec<PathBuf>> {
    let io = |e| Error::Io {
        path: dir.display().to_string(),
        source: e,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase();
            matches!(ext.as_str(), "obj" | "off" | "ply")
        })
        .collect();
    files.sort();
    Ok(files)
}

fn verr(e: crate::voxel::VoxelError) -> Error {
    Error::Invalid(e.to_string())
}

/// The procedural family of shape `i` (`None` for real meshes).
fn family_of(shapes: Shapes, i: usize) -> Option<Family> {
    match shapes {
        Shapes::Chairs => Some(Family::Chair),
        Shapes::Mixed => Some(Family::ALL[i % Family::ALL.len()]),
        Shapes::Varied => Some(Family::VARIED[i % Family::VARIED.len()]),
        Shapes::Real => None,
    }
}

/// The input grid (`res`) and the truth grid (`truth_res`) of shape `i`.
fn shape_grids(
    o: &GenerateOptions,
    meshes: &[PathBuf],
    i: usize,
) -> Result<(VoxelGrid, VoxelGrid)> {
    let family = match family_of(o.shapes, i) {
        Some(f) => f,
        None => {
            // The input stays binary like the procedural inputs (`Shape::to_grid`); the truth
            // grid is anti-aliased so the targets show the mesh, not voxel stair-steps.
            let mut mesh = Mesh::load(&meshes[i]).map_err(verr)?;
            mesh.colours.clear(); // grey datasets stay grey (--colour refuses real meshes)
            let input = VoxelizeOptions {
                resolution: o.res,
                supersample: o.input_supersample,
                ..Default::default()
            };
            return Ok((
                voxelize(&mesh, &input).map_err(verr)?,
                voxelize(&mesh, &VoxelizeOptions::smooth(o.truth_res)).map_err(verr)?,
            ));
        }
    };
    let seed = shape_seed(o.seed, i);
    let shape = family.generate(seed);
    if o.colour {
        return Ok((shape.to_coloured_grid(o.res, seed).map_err(verr)?, shape.to_coloured_grid(o.truth_res, seed).map_err(verr)?));
    }
    let input = if o.input_supersample > 1 { shape.to_grid_supersampled(o.res, o.input_supersample) } else { shape.to_grid(o.res) };
    Ok((
        input.map_err(verr)?,
        shape.to_grid(o.truth_res).map_err(verr)?,
    ))
}

/// Samples of one shard being filled.
#[derive(Default)]
struct ShardBuf {
    len: usize,
    grids: Vec<u8>,
    colours: Vec<u8>,
    views: Vec<f32>,
    lights: Vec<f32>,
    shape_ids: Vec<f32>,
    images: Vec<Vec<u8>>,
}

fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

fn le(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Writes `bytes` to `dir/name` via a temporary file and a rename, so a reader never sees a
/// partial file.
fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<()> {
    let tmp = dir.join(format!(".{name}.tmp"));
    let path = dir.join(name);
    let io = |p: &Path| {
        let p = p.display().to_string();
        move |e| Error::Io { path: p, source: e }
    };
    std::fs::write(&tmp, bytes).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &path).map_err(io(&path))
}

/// The generator's state while it runs.
struct Writer<'a> {
    gpu: &'a Gpu,
    renderer: RayMarcher,
    meshes: Vec<PathBuf>,
    o: &'a GenerateOptions,
    dir: &'a Path,
    outputs: Vec<(&'static str, Shader, usize)>,
    buf: ShardBuf,
    /// Samples rendered so far, for the progress callback.
    done: usize,
}

impl Writer<'_> {
    fn flush(&mut self, split: Split, info: &mut SplitInfo) -> Result<()> {
        if self.buf.len == 0 {
            return Ok(());
        }
        let b = std::mem::take(&mut self.buf);
        let (n, r, s) = (b.len, self.o.res, self.o.image);
        let (views, lights, ids) = (le(&b.views), le(&b.lights), le(&b.shape_ids));
        let err = |e: safetensors::SafeTensorError| {
            Error::Invalid(format!("encoding a {} shard: {e}", split.name()))
        };
        let mut t = vec![
            (
                GRIDS,
                TensorView::new(Dtype::U8, vec![n, r, r, r], &b.grids).map_err(err)?,
            ),
            (
                VIEWS,
                TensorView::new(Dtype::F32, vec![n, 3], &views).map_err(err)?,
            ),
            (
                LIGHTS,
                TensorView::new(Dtype::F32, vec![n, 5], &lights).map_err(err)?,
            ),
            (
                SHAPE_IDS,
                TensorView::new(Dtype::F32, vec![n], &ids).map_err(err)?,
            ),
        ];
        if self.o.colour {
            t.push((COLOURS, TensorView::new(Dtype::U8, vec![n, 3, r, r, r], &b.colours).map_err(err)?));
        }
        for ((name, _, c), data) in self.outputs.iter().zip(&b.images) {
            t.push((
                name,
                TensorView::new(Dtype::U8, vec![n, *c, s, s], data).map_err(err)?,
            ));
        }
        let bytes = safetensors::serialize(t, None).map_err(err)?;
        let name = split.shard_name(info.shards.len());
        write_atomic(self.dir, &name, &bytes)?;
        info.shards.push(name);
        Ok(())
    }

    /// Renders every view of shape `i` and appends the samples, flushing full shards.
    fn shape(
        &mut self,
        i: usize,
        split: Split,
        info: &mut SplitInfo,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<()> {
        let (o, gpu) = (self.o, self.gpu);
        let (input, truth) = shape_grids(o, &self.meshes, i)?;
        let grid_u8: Vec<u8> = input.occupancy().iter().map(|&v| to_u8(v)).collect();
        let colour_u8: Vec<u8> = input.colour().unwrap_or_default().iter().map(|&v| to_u8(v)).collect();
        let g = GpuGrid::upload(gpu, &truth)?;
        let mut poses = sample_poses(shape_seed(o.seed, i), o.views, o.radius);
        // Only the Phong network takes the light: every other shader's network renders one
        // fixed light (the default, relative to the camera), so toon targets are lit by it.
        if o.shader != Shader::Phong {
            let d = Light::default();
            poses.iter_mut().for_each(|(_, l)| *l = [d.azimuth as f32, d.elevation as f32, 1.0, 1.0, 1.0]);
        }
        let light_params = Light::default();
        for chunk in poses.chunks(VIEWS_PER_SUBMIT) {
            let outs: Vec<Vec<Tensor>> = chunk
                .iter()
                .map(|_| {
                    self.outputs
                        .iter()
                        .map(|&(_, sh, _)| Tensor::zeros(gpu, &[sh.channels(), o.image, o.image]))
                        .collect()
                })
                .collect::<Result<_>>()?;
            let lights: Vec<Light> = chunk
                .iter()
                .map(|(_, l)| Light {
                    azimuth: l[0] as f64,
                    elevation: l[1] as f64,
                    colour: [l[2], l[3], l[4]],
                    ..light_params
                })
                .collect();
            gpu.run(|pass| {
                for (((v, _), light), ts) in chunk.iter().zip(&lights).zip(&outs) {
                    let view = View {
                        azimuth: v[0] as f64,
                        elevation: v[1] as f64,
                        radius: v[2] as f64,
                    };
                    let pairs: Vec<(Shader, &Tensor)> =
                        self.outputs.iter().map(|o| o.1).zip(ts).collect();
                    self.renderer
                        .record_many(gpu, pass, &g, &view, light, &pairs)?;
                }
                Ok(())
            })?;
            for ((v, l), ts) in chunk.iter().zip(&outs) {
                if self.buf.len == 0 {
                    self.buf.images = vec![Vec::new(); self.outputs.len()];
                }
                self.buf.len += 1;
                self.buf.grids.extend_from_slice(&grid_u8);
                self.buf.colours.extend_from_slice(&colour_u8);
                self.buf.views.extend_from_slice(v);
                self.buf.lights.extend_from_slice(l);
                self.buf.shape_ids.push(i as f32);
                for ((_, _, c), (t, img)) in
                    self.outputs.iter().zip(ts.iter().zip(&mut self.buf.images))
                {
                    // Grey outputs rendered as RGB (albedo) keep channel 0 only.
                    let data = t.to_vec(gpu)?;
                    img.extend(data[..c * o.image * o.image].iter().map(|&x| to_u8(x)));
                }
                self.done += 1;
                progress(self.done, o.count * o.views);
                if self.buf.len == SHARD_SIZE {
                    self.flush(split, info)?;
                }
            }
        }
        Ok(())
    }
}

/// Checks options before any work.
fn validate(o: &GenerateOptions) -> Result<()> {
    let bad = |m: String| Err(Error::Invalid(format!("dataset: {m}")));
    if o.count == 0 || o.views == 0 {
        return bad(format!(
            "count ({}) and views ({}) must be at least 1",
            o.count, o.views
        ));
    }
    if !(1..=1024).contains(&o.res)
        || !(1..=1024).contains(&o.truth_res)
        || !(1..=8192).contains(&o.image)
    {
        return bad(format!(
            "res {} and truth_res {} must be in 1..=1024, image {} in 1..=8192",
            o.res, o.truth_res, o.image
        ));
    }
    if o.colour && o.shapes == Shapes::Real {
        return bad("--colour paints procedural shapes; --shapes real meshes carry no paint (use chairs or mixed)".into());
    }
    let (lo, hi) = o.radius;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
        return bad(format!("radius range {lo}..{hi} must be positive, finite and ordered"));
    }
    if !(0.0..=1.0).contains(&o.test_fraction) {
        return bad(format!(
            "test fraction {} is outside [0, 1]",
            o.test_fraction
        ));
    }
    Ok(())
}

/// Generates the dataset `o` describes into `dir` (created if needed): shards first, each
/// written atomically, then `manifest.json`. Stale shards and manifest from an earlier run in
/// the same directory are removed first, so the directory always describes one run. Calls
/// `progress(done, total)` after every sample.
pub fn generate(gpu: &Gpu, o: &GenerateOptions, dir: &Path, mut progress: impl FnMut(usize, usize)) -> Result<Summary> {
    let t0 = Instant::now();
    validate(o)?;
    let meshes = if o.shapes == Shapes::Real {
        real_meshes(&o.real_dir)?
    } else {
        Vec::new()
    };
    if o.shapes == Shapes::Real && meshes.len() < o.count {
        return Err(Error::Invalid(format!(
            "{}: {} meshes (.obj/.off/.ply) but --count {} asked for; run datasets/fetch_real.sh or lower --count",
            o.real_dir.display(),
            meshes.len(),
            o.count
        )));
    }
    let io = |e| Error::Io {
        path: dir.display().to_string(),
        source: e,
    };
    std::fs::create_dir_all(dir).map_err(io)?;
    for e in std::fs::read_dir(dir).map_err(io)?.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let ours = (name.starts_with("train-") || name.starts_with("test-"))
            && name.ends_with(".safetensors");
        if ours || name == MANIFEST {
            std::fs::remove_file(e.path()).map_err(|err| Error::Io {
                path: e.path().display().to_string(),
                source: err,
            })?;
        }
    }
    let n_test = ((o.test_fraction * o.count as f64).ceil() as usize).min(o.count);
    let n_train = o.count - n_test;
    let renderer = RayMarcher::new(gpu).with_options(target_options(o.supersample, o.ao_rays)?);
    let mut w = Writer {
        gpu,
        renderer,
        meshes,
        o,
        dir,
        outputs: image_outputs(o.shader, o.colour),
        buf: ShardBuf::default(),
        done: 0,
    };
    let (mut train, mut test) = (SplitInfo::default(), SplitInfo::default());
    for (split, range, info) in [
        (Split::Train, 0..n_train, &mut train),
        (Split::Test, n_train..o.count, &mut test),
    ] {
        for i in range.clone() {
            w.shape(i, split, info, &mut progress)?;
        }
        w.flush(split, info)?;
        info.count = range.len() * o.views;
    }
    let manifest = Manifest {
        shapes: o.shapes.name().to_string(),
        shader: o.shader.name().to_string(),
        res: o.res,
        truth_res: o.truth_res,
        input_supersample: o.input_supersample.max(1),
        image: o.image,
        views: o.views,
        seed: o.seed,
        light: LightParams::from(&Light::default()),
        train,
        test,
        supersample: o.supersample,
        ao_rays: o.ao_rays,
        test_fraction: o.test_fraction,
        radius: o.radius,
        colour: o.colour,
    };
    write_atomic(dir, MANIFEST, manifest.to_json().as_bytes())?;
    Ok(Summary {
        manifest,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `varied` is `mixed` with a creature after every four; every name parses back.
    #[test]
    fn varied_cycles_mixed_then_a_creature() {
        for i in 0..10 {
            let want = if i % 5 == 4 { Family::Creature } else { Family::ALL[i % 5] };
            assert_eq!(family_of(Shapes::Varied, i), Some(want), "shape {i}");
            assert_eq!(family_of(Shapes::Mixed, i), Some(Family::ALL[i % 4]), "shape {i}");
        }
        assert_eq!(family_of(Shapes::Real, 3), None);
        for s in [Shapes::Chairs, Shapes::Real, Shapes::Mixed, Shapes::Varied] {
            assert_eq!(Shapes::parse(s.name()), Some(s));
        }
    }
}
