//! The binvox format (Patrick Min's voxeliser; ShapeNet's voxelisations use it).
//!
//! A text header
//! ```text
//! #binvox 1
//! dim A B C
//! translate tx ty tz
//! scale s
//! data
//! ```
//! is followed by run-length pairs of bytes `(value, count)`, value 0 or 1, count 1..=255.
//! The spec's reader walks the voxels as `index = x * (B*C) + z * C + y`, so the file holds a
//! `[x][z][y]` array with `x < A`, `z < B`, `y < C` (y fastest).
//!
//! We map it to our `[D, H, W] = [x, y, z]` (world y up), exactly what `binvox_rw.py`'s
//! `read_as_3d_array` (fix_coords) returns and what RenderNet trained on. So `D = A`, `H = C`,
//! `W = B`, and writing swaps them back; ShapeNet files are cubic, where this is just a
//! transpose of the last two axes.

use super::{VoxelError, VoxelGrid, check_dims, read_file, write_file};
use std::path::Path;

/// Header bytes searched for the `data` line before giving up (real headers are ~60 bytes).
const MAX_HEADER: usize = 4096;

/// A binvox file: the grid plus the header's placement of the unit cube in world space
/// (world = translate + scale * normalised voxel coordinate), kept so round trips are exact.
#[derive(Clone, Debug, PartialEq)]
pub struct Binvox {
    /// Occupancy grid, `[D, H, W] = [x, y, z]`; values >= 0.5 count as occupied when writing.
    pub grid: VoxelGrid,
    /// `translate` header line.
    pub translate: [f32; 3],
    /// `scale` header line.
    pub scale: f32,
}

impl Binvox {
    /// Wraps a grid with the identity placement (translate 0, scale 1).
    pub fn from_grid(grid: VoxelGrid) -> Self {
        Binvox {
            grid,
            translate: [0.0; 3],
            scale: 1.0,
        }
    }

    /// Reads a `.binvox` file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self, VoxelError> {
        let (name, bytes) = read_file(path.as_ref())?;
        Self::parse(&bytes, &name)
    }

    /// Parses binvox bytes; `name` is used in error messages. Trailing bytes after the last
    /// voxel are ignored, since some writers append a newline.
    pub fn parse(bytes: &[u8], name: &str) -> Result<Self, VoxelError> {
        let (header, data_start) = split_header(bytes, name)?;
        let mut dims_abc: Option<[usize; 3]> = None;
        let mut translate = [0.0f32; 3];
        let mut scale = 1.0f32;
        for (i, line) in header.iter().enumerate() {
            let lineno = Some(i + 1);
            let mut tok = line.split_whitespace();
            let key = tok.next().unwrap_or("");
            let args: Vec<&str> = tok.collect();
            let bad = |msg: String| VoxelError::malformed(name, lineno, msg);
            match key {
                _ if i == 0 => {
                    if key != "#binvox" {
                        return Err(bad(format!(
                            "expected '#binvox <version>' header, found {line:?}"
                        )));
                    }
                }
                "dim" => {
                    let v = parse_n::<usize>(&args, 3)
                        .ok_or_else(|| bad(format!("bad dim line {line:?}")))?;
                    dims_abc = Some([v[0], v[1], v[2]]);
                }
                "translate" => {
                    let v = parse_n::<f32>(&args, 3)
                        .ok_or_else(|| bad(format!("bad translate line {line:?}")))?;
                    translate = [v[0], v[1], v[2]];
                }
                "scale" => {
                    scale = parse_n::<f32>(&args, 1)
                        .ok_or_else(|| bad(format!("bad scale line {line:?}")))?[0];
                }
                "" => {}
                _ => return Err(bad(format!("unknown header line {line:?}"))),
            }
        }
        let [a, b, c] = dims_abc
            .ok_or_else(|| VoxelError::malformed(name, None, "header has no 'dim' line"))?;
        let dims = [a, c, b];
        let n = check_dims(name, dims)?;
        // Each pair covers at most 255 voxels: refuse before allocating a grid the data cannot fill.
        let pairs = (bytes.len() - data_start) / 2;
        if pairs.saturating_mul(255) < n {
            return Err(VoxelError::malformed(
                name,
                None,
                format!(
                    "truncated run-length data at byte {}: {pairs} runs cannot cover {n} voxels",
                    bytes.len()
                ),
            ));
        }

        let mut occ = vec![0.0f32; n];
        let mut file_index = 0usize;
        let mut pos = data_start;
        while file_index < n {
            let Some(pair) = bytes.get(pos..pos + 2) else {
                return Err(VoxelError::malformed(
                    name,
                    None,
                    format!(
                        "truncated run-length data at byte {pos} ({file_index} of {n} voxels read)"
                    ),
                ));
            };
            let (value, count) = (pair[0], pair[1] as usize);
            if value > 1 {
                return Err(VoxelError::malformed(
                    name,
                    None,
                    format!("voxel value {value} at byte {pos} is not 0 or 1"),
                ));
            }
            if file_index + count > n {
                return Err(VoxelError::malformed(
                    name,
                    None,
                    format!("run at byte {pos} overruns the grid of {n} voxels"),
                ));
            }
            if value == 1 {
                for fi in file_index..file_index + count {
                    occ[file_to_grid(fi, [a, b, c])] = 1.0;
                }
            }
            file_index += count;
            pos += 2;
        }
        Ok(Binvox {
            grid: VoxelGrid::new(dims, occ)?,
            translate,
            scale,
        })
    }

    /// Encodes to binvox bytes (occupied = occupancy >= 0.5; colour is not stored).
    pub fn to_bytes(&self) -> Vec<u8> {
        let [d, h, w] = self.grid.dims();
        let abc = [d, w, h];
        let [tx, ty, tz] = self.translate;
        // `{}` prints the shortest representation that parses back to the same f32.
        let mut out = format!(
            "#binvox 1\ndim {} {} {}\ntranslate {tx} {ty} {tz}\nscale {}\ndata\n",
            abc[0], abc[1], abc[2], self.scale
        )
        .into_bytes();
        let occ = self.grid.occupancy();
        let mut run: Option<(u8, u8)> = None;
        for fi in 0..occ.len() {
            let v = (occ[file_to_grid(fi, abc)] >= 0.5) as u8;
            run = match run {
                Some((rv, rc)) if rv == v && rc < 255 => Some((rv, rc + 1)),
                Some((rv, rc)) => {
                    out.extend([rv, rc]);
                    Some((v, 1))
                }
                None => Some((v, 1)),
            };
        }
        if let Some((rv, rc)) = run {
            out.extend([rv, rc]);
        }
        out
    }

    /// Writes a `.binvox` file.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), VoxelError> {
        write_file(path.as_ref(), &self.to_bytes())
    }
}

/// Maps a file-order index (`[x][z][y]`, dims `[A, B, C]`) to our `[x][y][z]` flat index.
fn file_to_grid(fi: usize, [_a, b, c]: [usize; 3]) -> usize {
    let (x, rest) = (fi / (b * c), fi % (b * c));
    let (z, y) = (rest / c, rest % c);
    (x * c + y) * b + z
}

/// Splits off the header lines (up to and excluding `data`) and returns where the data begins.
fn split_header<'a>(bytes: &'a [u8], name: &str) -> Result<(Vec<&'a str>, usize), VoxelError> {
    let mut lines = Vec::new();
    let mut start = 0;
    while start < bytes.len().min(MAX_HEADER) {
        let end = bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|p| start + p);
        let Some(end) = end else { break };
        let line = std::str::from_utf8(&bytes[start..end])
            .map_err(|_| {
                VoxelError::malformed(
                    name,
                    Some(lines.len() + 1),
                    "header is not text (is this a binvox file?)",
                )
            })?
            .trim_end_matches('\r');
        if line.trim() == "data" {
            if lines.is_empty() {
                return Err(VoxelError::malformed(
                    name,
                    Some(1),
                    "missing '#binvox' header",
                ));
            }
            return Ok((lines, end + 1));
        }
        lines.push(line);
        start = end + 1;
    }
    Err(VoxelError::malformed(
        name,
        None,
        format!("no 'data' line in the first {MAX_HEADER} bytes (is this a binvox file?)"),
    ))
}

/// Parses exactly `n` whitespace-separated numbers.
fn parse_n<T: std::str::FromStr>(args: &[&str], n: usize) -> Option<Vec<T>> {
    if args.len() != n {
        return None;
    }
    args.iter().map(|s| s.parse().ok()).collect()
}
