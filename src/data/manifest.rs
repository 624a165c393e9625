//! `manifest.json`: what a dataset holds and how it was made, written last so a directory
//! with a manifest is complete.

use super::{FORMAT, SHARD_SIZE, Split};
use crate::error::{Error, Result};
use crate::reference::{Light, Shader};
use serde_json::{Value, json};

/// The material constants every sample's light shares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightParams {
    /// Ambient term.
    pub ambient: f32,
    /// Diffuse weight.
    pub kd: f32,
    /// Specular weight.
    pub ks: f32,
    /// Specular exponent.
    pub shininess: f32,
}

impl From<&Light> for LightParams {
    fn from(l: &Light) -> Self {
        LightParams {
            ambient: l.ambient,
            kd: l.kd,
            ks: l.ks,
            shininess: l.shininess,
        }
    }
}

/// Sample count and shard files of one split.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SplitInfo {
    /// Samples in the split.
    pub count: usize,
    /// Shard file names, relative to the dataset directory, in order.
    pub shards: Vec<String>,
}

/// The parsed `manifest.json`.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// `chairs`, `real` or `mixed`.
    pub shapes: String,
    /// Reference shader name ([`Shader::name`]).
    pub shader: String,
    /// Input grid side `R`.
    pub res: usize,
    /// Side of the grid the targets were rendered from.
    pub truth_res: usize,
    /// Sub-voxels per axis of the input grids (extra key; 1, binary occupancy, when absent).
    pub input_supersample: usize,
    /// Image side `S`.
    pub image: usize,
    /// Views per shape.
    pub views: usize,
    /// Generator seed.
    pub seed: u64,
    /// Material constants.
    pub light: LightParams,
    /// Training split.
    pub train: SplitInfo,
    /// Test split.
    pub test: SplitInfo,
    /// Sub-pixels per axis of the targets (extra key; 1 when absent).
    pub supersample: u32,
    /// Ambient-occlusion rays per pixel of the targets (extra key; 64 when absent).
    pub ao_rays: u32,
    /// Fraction of shapes held out for test (extra key, informational).
    pub test_fraction: f64,
    /// Camera radius range (extra key; the paper's 3..6.3 when absent).
    pub radius: (f64, f64),
    /// Coloured voxels (extra key; false when absent): shards carry `colours` and Phong
    /// datasets an RGB albedo map.
    pub colour: bool,
}

impl Manifest {
    /// The shader as an enum.
    pub fn shader_kind(&self) -> Result<Shader> {
        Shader::parse(&self.shader)
            .ok_or_else(|| Error::Invalid(format!("manifest: unknown shader `{}`", self.shader)))
    }

    /// The JSON text written to disk.
    pub fn to_json(&self) -> String {
        let split = |s: &SplitInfo| json!({"count": s.count, "shards": s.shards});
        let v = json!({
            "format": FORMAT,
            "shapes": self.shapes,
            "shader": self.shader,
            "res": self.res,
            "truth_res": self.truth_res,
            "input_supersample": self.input_supersample,
            "image": self.image,
            "views": self.views,
            "seed": self.seed,
            "light": {"ambient": self.light.ambient, "kd": self.light.kd, "ks": self.light.ks, "shininess": self.light.shininess},
            "train": split(&self.train),
            "test": split(&self.test),
            "supersample": self.supersample,
            "ao_rays": self.ao_rays,
            "test_fraction": self.test_fraction,
            "radius": [self.radius.0, self.radius.1],
            "colour": self.colour,
        });
        serde_json::to_string_pretty(&v).expect("a JSON value always serialises") + "\n"
    }

    /// Parses and checks manifest text; `file` names it in errors, with the offending field.
    pub fn parse(text: &str, file: &str) -> Result<Manifest> {
        let bad =
            |field: &str, msg: &str| Error::Invalid(format!("{file}: field `{field}`: {msg}"));
        let v: Value = serde_json::from_str(text)
            .map_err(|e| Error::Invalid(format!("{file}: not valid JSON: {e}")))?;
        let get = |k: &str| v.get(k).ok_or_else(|| bad(k, "missing"));
        let string = |k: &str| {
            get(k)?
                .as_str()
                .map(str::to_string)
                .ok_or_else(|| bad(k, "expected a string"))
        };
        let uint = |k: &str| {
            get(k)?
                .as_u64()
                .ok_or_else(|| bad(k, "expected a non-negative integer"))
        };
        let size = |k: &str, max: u64| match uint(k)? {
            n if (1..=max).contains(&n) => Ok(n as usize),
            n => Err(bad(k, &format!("{n} is outside 1..={max}"))),
        };
        let format = string("format")?;
        if format != FORMAT {
            return Err(bad("format", &format!("`{format}`, expected `{FORMAT}`")));
        }
        let lv = get("light")?;
        let lf = |k: &str| {
            let f = format!("light.{k}");
            lv.get(k)
                .ok_or_else(|| bad(&f, "missing"))?
                .as_f64()
                .map(|x| x as f32)
                .ok_or_else(|| bad(&f, "expected a number"))
        };
        let light = LightParams {
            ambient: lf("ambient")?,
            kd: lf("kd")?,
            ks: lf("ks")?,
            shininess: lf("shininess")?,
        };
        let views = size("views", 1 << 20)?;
        let split = |s: Split| -> Result<SplitInfo> {
            let name = s.name();
            let sv = get(name)?;
            let count = sv.get("count").and_then(Value::as_u64).ok_or_else(|| {
                bad(
                    &format!("{name}.count"),
                    "missing or not a non-negative integer",
                )
            })? as usize;
            let shards: Vec<String> = sv
                .get("shards")
                .and_then(Value::as_array)
                .and_then(|a| a.iter().map(|x| x.as_str().map(str::to_string)).collect())
                .ok_or_else(|| {
                    bad(
                        &format!("{name}.shards"),
                        "missing or not an array of strings",
                    )
                })?;
            if shards.len() != count.div_ceil(SHARD_SIZE) {
                let msg = format!(
                    "{} shards for {count} samples, expected {}",
                    shards.len(),
                    count.div_ceil(SHARD_SIZE)
                );
                return Err(bad(&format!("{name}.shards"), &msg));
            }
            if let Some(s) = shards
                .iter()
                .find(|s| s.contains('/') || s.contains('\\') || s.starts_with('.'))
            {
                return Err(bad(
                    &format!("{name}.shards"),
                    &format!("`{s}` must be a plain file name"),
                ));
            }
            if !count.is_multiple_of(views) {
                return Err(bad(
                    &format!("{name}.count"),
                    &format!("{count} is not a multiple of views = {views}"),
                ));
            }
            Ok(SplitInfo { count, shards })
        };
        let m = Manifest {
            shapes: string("shapes")?,
            shader: string("shader")?,
            res: size("res", 1024)?,
            truth_res: size("truth_res", 1024)?,
            input_supersample: v.get("input_supersample").and_then(Value::as_u64).unwrap_or(1).max(1) as usize,
            image: size("image", 8192)?,
            views,
            seed: uint("seed")?,
            light,
            train: split(Split::Train)?,
            test: split(Split::Test)?,
            supersample: v.get("supersample").and_then(Value::as_u64).unwrap_or(1) as u32,
            ao_rays: v.get("ao_rays").and_then(Value::as_u64).unwrap_or(64) as u32,
            test_fraction: v
                .get("test_fraction")
                .and_then(Value::as_f64)
                .unwrap_or(0.0),
            radius: match v.get("radius").and_then(Value::as_array).map(|a| a.iter().map(Value::as_f64).collect::<Vec<_>>()) {
                None => crate::data::generate::PAPER_RADII,
                Some(r) => match r[..] {
                    [Some(lo), Some(hi)] if lo > 0.0 && lo <= hi => (lo, hi),
                    _ => return Err(bad("radius", "expected [min, max] with 0 < min <= max")),
                },
            },
            colour: match v.get("colour") {
                None => false,
                Some(c) => c.as_bool().ok_or_else(|| bad("colour", "expected true or false"))?,
            },
        };
        m.shader_kind()
            .map_err(|_| bad("shader", &format!("unknown shader `{}`", m.shader)))?;
        Ok(m)
    }
}
