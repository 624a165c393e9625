//! Triangle meshes: the type, a few analytic constructors (used by the procedural shapes and
//! tests) and hand-written OBJ and OFF loaders (PLY lives in [`super::ply`]).
//!
//! The loaders are deliberately small: they keep positions and faces only, fan-triangulate
//! polygons, and report the file and line of the first problem instead of panicking.

use super::{MAX_TRIANGLES, MAX_VERTICES, VoxelError, read_file};
use glam::{Mat3, Vec3};
use std::path::Path;

/// An indexed triangle mesh. World axes map to grid axes as described in [`super`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as indices into `positions` (counter-clockwise seen from outside for
    /// constructed meshes; loaded meshes keep the file's order).
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex RGB in `[0, 1]` (OBJ `v x y z r g b`, PLY `red`/`green`/`blue`), one per
    /// position, or empty when the file has none; [`crate::voxel::voxelize`] carries it into
    /// the grid's colour.
    pub colours: Vec<[f32; 3]>,
}

impl Mesh {
    /// Loads an `.obj`, `.off` or `.ply` file, chosen by extension (case-insensitive).
    pub fn load(path: impl AsRef<Path>) -> Result<Mesh, VoxelError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let (name, bytes) = read_file(path)?;
        match ext.as_str() {
            "obj" => Mesh::parse_obj(&String::from_utf8_lossy(&bytes), &name),
            "off" => Mesh::parse_off(&String::from_utf8_lossy(&bytes), &name),
            "ply" => Mesh::parse_ply_bytes(&bytes, &name),
            _ => Err(VoxelError::malformed(
                &name,
                None,
                "unknown mesh format (expected .obj, .off or .ply)",
            )),
        }
    }

    /// Parses PLY bytes (ascii or binary); see [`super::ply`].
    pub fn parse_ply_bytes(bytes: &[u8], name: &str) -> Result<Mesh, VoxelError> {
        super::ply::parse_ply(bytes, name)
    }

    /// Parses Wavefront OBJ text: `v x y z` and `f` lines with `a`, `a/b`, `a//c`, `a/b/c`
    /// references, 1-based or negative (relative) indices; all other statements are ignored.
    pub fn parse_obj(text: &str, name: &str) -> Result<Mesh, VoxelError> {
        let mut mesh = Mesh::default();
        let mut poly = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("");
            let mut tok = line.split_whitespace();
            let lineno = Some(i + 1);
            match tok.next() {
                Some("v") => {
                    let p = parse_xyz(&mut tok, name, lineno)?;
                    mesh.push_vertex(p, name, lineno)?;
                    // The common `v x y z r g b` extension (the last three numbers; a lone
                    // fourth is w).
                    let rgb: Vec<&str> = tok.collect();
                    if rgb.len() >= 3 {
                        let c = parse_xyz(rgb[rgb.len() - 3..].iter().copied(), name, lineno)?;
                        mesh.set_last_colour(Some(c), name, lineno)?;
                    } else {
                        mesh.set_last_colour(None, name, lineno)?;
                    }
                }
                Some("f") => {
                    poly.clear();
                    let n = mesh.positions.len();
                    for r in tok {
                        let first = r.split('/').next().unwrap_or("");
                        let idx: i64 = first.parse().map_err(|_| {
                            VoxelError::malformed(
                                name,
                                lineno,
                                format!("bad face vertex reference {r:?}"),
                            )
                        })?;
                        let resolved = if idx < 0 { n as i64 + idx } else { idx - 1 };
                        if idx == 0 || resolved < 0 || resolved >= n as i64 {
                            return Err(VoxelError::malformed(
                                name,
                                lineno,
                                format!("face index {idx} out of range ({n} vertices)"),
                            ));
                        }
                        poly.push(resolved as u32);
                    }
                    mesh.push_polygon(&poly, name, lineno)?;
                }
                _ => {}
            }
        }
        Ok(mesh)
    }

    /// Parses ASCII OFF (also COFF/NOFF headers: extra per-vertex or per-face values are
    /// ignored). Counts may follow `OFF` on the same line.
    pub fn parse_off(text: &str, name: &str) -> Result<Mesh, VoxelError> {
        // Non-empty lines with comments removed, keeping 1-based line numbers for errors.
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
            .filter(|(_, l)| !l.is_empty());
        let (l0, header) = lines
            .next()
            .ok_or_else(|| VoxelError::malformed(name, None, "empty file"))?;
        let mut htok = header.split_whitespace();
        let magic = htok.next().unwrap_or("");
        if !magic.ends_with("OFF") || magic.len() > 5 {
            return Err(VoxelError::malformed(
                name,
                Some(l0),
                format!("expected 'OFF' header, found {magic:?}"),
            ));
        }
        let rest: Vec<&str> = htok.collect();
        let (lc, counts) = if rest.is_empty() {
            let (l, c) = lines.next().ok_or_else(|| {
                VoxelError::malformed(name, Some(l0), "missing vertex/face counts")
            })?;
            (l, c.split_whitespace().collect::<Vec<_>>())
        } else {
            (l0, rest)
        };
        let count = |k: usize| -> Result<usize, VoxelError> {
            counts.get(k).and_then(|s| s.parse().ok()).ok_or_else(|| {
                VoxelError::malformed(
                    name,
                    Some(lc),
                    "bad counts line (expected 'vertices faces edges')",
                )
            })
        };
        let (nv, nf) = (count(0)?, count(1)?);
        VoxelError::check_limit(name, "vertices", nv as u128, MAX_VERTICES as u128)?;
        VoxelError::check_limit(name, "faces", nf as u128, MAX_TRIANGLES as u128)?;

        let mut mesh = Mesh::default();
        let mut last = lc;
        for k in 0..nv + nf {
            let Some((l, line)) = lines.next() else {
                let what = if k < nv {
                    format!("{nv} vertices, found {k}")
                } else {
                    format!("{nf} faces, found {}", k - nv)
                };
                return Err(VoxelError::malformed(
                    name,
                    Some(last),
                    format!("file ends early: expected {what}"),
                ));
            };
            last = l;
            let mut tok = line.split_whitespace();
            if k < nv {
                mesh.push_vertex(parse_xyz(tok, name, Some(l))?, name, Some(l))?;
                continue;
            }
            let bad = |m: String| VoxelError::malformed(name, Some(l), m);
            let n: usize = tok
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| bad("bad face line".into()))?;
            let poly: Vec<u32> = tok
                .take(n)
                .map(|s| match s.parse::<u32>() {
                    Ok(i) if (i as usize) < nv => Ok(i),
                    _ => Err(bad(format!(
                        "face index {s:?} out of range ({nv} vertices)"
                    ))),
                })
                .collect::<Result<_, _>>()?;
            if poly.len() != n {
                return Err(bad(format!(
                    "face declares {n} vertices but lists {}",
                    poly.len()
                )));
            }
            mesh.push_polygon(&poly, name, Some(l))?;
        }
        Ok(mesh)
    }

    /// Adds a vertex, enforcing finiteness and the vertex limit.
    pub(crate) fn push_vertex(
        &mut self,
        p: [f32; 3],
        name: &str,
        line: Option<usize>,
    ) -> Result<(), VoxelError> {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(VoxelError::malformed(
                name,
                line,
                format!("vertex {p:?} is not finite"),
            ));
        }
        VoxelError::check_limit(
            name,
            "vertices",
            self.positions.len() as u128 + 1,
            MAX_VERTICES as u128,
        )?;
        self.positions.push(p);
        Ok(())
    }

    /// Gives the last pushed vertex its colour (`None`: white once any vertex has one), keeping
    /// `colours` empty until the first coloured vertex and then one per position.
    pub(crate) fn set_last_colour(&mut self, rgb: Option<[f32; 3]>, name: &str, line: Option<usize>) -> Result<(), VoxelError> {
        if let Some(c) = rgb {
            if !c.iter().all(|v| (0.0..=1.0).contains(v)) {
                return Err(VoxelError::malformed(name, line, format!("vertex colour {c:?} is outside [0, 1]")));
            }
        }
        if rgb.is_none() && self.colours.is_empty() {
            return Ok(());
        }
        self.colours.resize(self.positions.len() - 1, [1.0; 3]);
        self.colours.push(rgb.unwrap_or([1.0; 3]));
        Ok(())
    }

    /// Fan-triangulates a polygon of already range-checked indices.
    pub(crate) fn push_polygon(
        &mut self,
        poly: &[u32],
        name: &str,
        line: Option<usize>,
    ) -> Result<(), VoxelError> {
        if poly.len() < 3 {
            return Err(VoxelError::malformed(
                name,
                line,
                format!("face has {} vertices, need at least 3", poly.len()),
            ));
        }
        VoxelError::check_limit(
            name,
            "triangles",
            (self.triangles.len() + poly.len() - 2) as u128,
            MAX_TRIANGLES as u128,
        )?;
        for k in 1..poly.len() - 1 {
            self.triangles.push([poly[0], poly[k], poly[k + 1]]);
        }
        Ok(())
    }

    /// Checks indices, finiteness and limits of a mesh built by hand; `name` labels errors.
    pub fn validate(&self, name: &str) -> Result<(), VoxelError> {
        VoxelError::check_limit(
            name,
            "vertices",
            self.positions.len() as u128,
            MAX_VERTICES as u128,
        )?;
        VoxelError::check_limit(
            name,
            "triangles",
            self.triangles.len() as u128,
            MAX_TRIANGLES as u128,
        )?;
        if let Some(p) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(VoxelError::invalid(
                name,
                format!("vertex {p} is not finite"),
            ));
        }
        let n = self.positions.len();
        if !self.colours.is_empty() && self.colours.len() != n {
            return Err(VoxelError::invalid(name, format!("{} vertex colours for {n} vertices", self.colours.len())));
        }
        if let Some(c) = self.colours.iter().position(|c| !c.iter().all(|v| (0.0..=1.0).contains(v))) {
            return Err(VoxelError::invalid(name, format!("vertex colour {c} {:?} is outside [0, 1]", self.colours[c])));
        }
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= n))
        {
            return Err(VoxelError::invalid(
                name,
                format!(
                    "triangle {t} {:?} indexes past {n} vertices",
                    self.triangles[t]
                ),
            ));
        }
        Ok(())
    }

    /// Axis-aligned bounds `(min, max)`, or `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.positions.iter().map(|&p| Vec3::from(p));
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }

    /// Signed enclosed volume (divergence theorem); positive for closed, outward-wound meshes.
    pub fn signed_volume(&self) -> f64 {
        let p = |i: u32| Vec3::from(self.positions[i as usize]).as_dvec3();
        self.triangles
            .iter()
            .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))) / 6.0)
            .sum()
    }

    /// Appends another mesh (as a separate part: no vertices are merged). Colours stay one
    /// per vertex: white for the side that had none, when the other had some.
    pub fn append(&mut self, other: &Mesh) {
        let base = self.positions.len() as u32;
        if !self.colours.is_empty() || !other.colours.is_empty() {
            self.colours.resize(self.positions.len(), [1.0; 3]);
            self.colours.extend((0..other.positions.len()).map(|i| other.colours.get(i).copied().unwrap_or([1.0; 3])));
        }
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
    }

    /// A closed box: `rot` maps box-local axes to world, `half` are the half extents.
    pub fn cuboid(center: Vec3, half: Vec3, rot: Mat3) -> Mesh {
        let positions = (0..8)
            .map(|k| {
                let s = Vec3::new(sign(k & 1), sign(k & 2), sign(k & 4));
                (center + rot * (s * half)).to_array()
            })
            .collect();
        // Corner k has bit0 = +x, bit1 = +y, bit2 = +z; two triangles per face, outward CCW.
        let quads = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh {
            positions,
            triangles,
            colours: Vec::new(),
        }
    }

    /// A closed cone frustum (cylinder when `ra == rb`) from `a` to `b` with `segments` sides.
    pub fn frustum(a: Vec3, b: Vec3, ra: f32, rb: f32, segments: u32) -> Mesh {
        let seg = segments.max(3);
        let axis = (b - a).normalize_or(Vec3::Y);
        let (u, v) = axis.any_orthonormal_pair();
        let mut positions = vec![a.to_array(), b.to_array()];
        for k in 0..seg {
            let t = k as f32 / seg as f32 * std::f32::consts::TAU;
            let dir = u * t.cos() + v * t.sin();
            positions.push((a + dir * ra).to_array());
            positions.push((b + dir * rb).to_array());
        }
        let mut triangles = Vec::new();
        for k in 0..seg {
            let (a0, b0) = (2 + 2 * k, 3 + 2 * k);
            let (a1, b1) = (2 + 2 * ((k + 1) % seg), 3 + 2 * ((k + 1) % seg));
            triangles.extend([[0, a1, a0], [1, b0, b1], [a0, a1, b1], [a0, b1, b0]]);
        }
        Mesh {
            positions,
            triangles,
            colours: Vec::new(),
        }
    }

    /// A closed UV sphere with `segments` longitudes and `rings` latitude bands.
    pub fn uv_sphere(center: Vec3, radius: f32, segments: u32, rings: u32) -> Mesh {
        let (seg, rings) = (segments.max(3), rings.max(2));
        let mut positions = vec![
            (center + Vec3::Y * radius).to_array(),
            (center - Vec3::Y * radius).to_array(),
        ];
        for r in 1..rings {
            let phi = r as f32 / rings as f32 * std::f32::consts::PI;
            for s in 0..seg {
                let th = s as f32 / seg as f32 * std::f32::consts::TAU;
                let d = Vec3::new(phi.sin() * th.cos(), phi.cos(), phi.sin() * th.sin());
                positions.push((center + d * radius).to_array());
            }
        }
        let at = |r: u32, s: u32| 2 + (r - 1) * seg + s % seg;
        let mut triangles = Vec::new();
        for s in 0..seg {
            triangles.push([0, at(1, s + 1), at(1, s)]);
            triangles.push([1, at(rings - 1, s), at(rings - 1, s + 1)]);
            for r in 1..rings - 1 {
                let (p, q, pn, qn) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                triangles.extend([[p, q, qn], [p, qn, pn]]);
            }
        }
        Mesh {
            positions,
            triangles,
            colours: Vec::new(),
        }
    }
}

fn sign(bit: usize) -> f32 {
    if bit != 0 { 1.0 } else { -1.0 }
}

/// Parses the first three numbers of a vertex line (extra values such as w or colour ignored).
pub(crate) fn parse_xyz<'a>(
    mut tok: impl Iterator<Item = &'a str>,
    name: &str,
    line: Option<usize>,
) -> Result<[f32; 3], VoxelError> {
    let mut p = [0.0f32; 3];
    for c in &mut p {
        let s = tok
            .next()
            .ok_or_else(|| VoxelError::malformed(name, line, "vertex needs 3 coordinates"))?;
        *c = s
            .parse()
            .map_err(|_| VoxelError::malformed(name, line, format!("bad coordinate {s:?}")))?;
    }
    Ok(p)
}
