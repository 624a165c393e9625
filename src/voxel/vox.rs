//! MagicaVoxel `.vox` files (version 150; 200, the current writer's number, has the same
//! chunks): a `VOX ` header, then a `MAIN` chunk whose children include `SIZE` (x, y, z as
//! i32), `XYZI` (a voxel count, then x, y, z, colour-index bytes per voxel) and an optional
//! `RGBA` palette (256 RGBA entries; colour index `c` in 1..=255 is entry `c - 1`). Other
//! chunks (scene graph, materials, layers, ...) are skipped; of a multi-model file (`PACK`)
//! only the first model is read.
//!
//! # Axis mapping
//! `.vox` is z-up (right-handed x, y, z); [`VoxelGrid`] is `[d, h, w]` = world (x, y up, z).
//! A file voxel `(x, y, z)` becomes `[d, h, w] = [x, z, SY - 1 - y]`, a rotation (no mirror):
//! vox x → world x, vox z (up) → world y (up), vox y → world −z. Dims are `[SX, SZ, SY]`.
//!
//! Read voxels get occupancy 1 and, when the file has an `RGBA` chunk, the palette colour
//! (RGB / 255; alpha ignored); without one the grid has no colour (MagicaVoxel would use its
//! built-in default palette, which is not reproduced here).

use super::{VoxelError, VoxelGrid, check_dims, read_file, write_file};
use std::path::Path;

/// Largest side `.vox` can address: coordinates are single bytes.
pub const MAX_VOX_SIDE: usize = 256;

/// A chunk header and where its content and children lie in the buffer.
struct Chunk<'a> {
    id: &'a [u8],
    content: &'a [u8],
    children: &'a [u8],
}

/// Reads a `.vox` file.
pub fn read(path: impl AsRef<Path>) -> Result<VoxelGrid, VoxelError> {
    let (name, bytes) = read_file(path.as_ref())?;
    parse(&bytes, &name)
}

/// Writes a grid as a `.vox` file ([`to_bytes`]).
pub fn write(grid: &VoxelGrid, path: impl AsRef<Path>) -> Result<(), VoxelError> {
    write_file(path.as_ref(), &to_bytes(grid)?)
}

fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// Splits `buf` (starting at absolute offset `base`) into chunks, checking every size.
fn chunks<'a>(buf: &'a [u8], base: usize, file: &str) -> Result<Vec<Chunk<'a>>, VoxelError> {
    let mut out = Vec::new();
    let mut at = 0;
    while at < buf.len() {
        let bad = |msg: String| VoxelError::malformed(file, None, format!("{msg} at byte {}", base + at));
        if buf.len() - at < 12 {
            return Err(bad("truncated chunk header".into()));
        }
        let id = &buf[at..at + 4];
        let (content, children) = (i32_at(buf, at + 4), i32_at(buf, at + 8));
        if content < 0 || children < 0 {
            return Err(bad(format!("negative chunk size in {:?}", String::from_utf8_lossy(id))));
        }
        let end = at + 12 + content as usize + children as usize;
        if end > buf.len() {
            return Err(bad(format!(
                "chunk {:?} claims {} bytes but only {} remain (truncated file?)",
                String::from_utf8_lossy(id),
                content as usize + children as usize,
                buf.len() - at - 12
            )));
        }
        let c_end = at + 12 + content as usize;
        out.push(Chunk { id, content: &buf[at + 12..c_end], children: &buf[c_end..end] });
        at = end;
    }
    Ok(out)
}

/// Decodes `.vox` bytes; `name` is used in error messages.
pub fn parse(bytes: &[u8], name: &str) -> Result<VoxelGrid, VoxelError> {
    let bad = |msg: String| VoxelError::malformed(name, None, msg);
    if bytes.len() < 8 || &bytes[..4] != b"VOX " {
        return Err(bad("not a MagicaVoxel file (no \"VOX \" magic)".into()));
    }
    let version = i32_at(bytes, 4);
    if !(150..=200).contains(&version) {
        return Err(bad(format!("unsupported .vox version {version} (expected 150 to 200)")));
    }
    let top = chunks(&bytes[8..], 8, name)?;
    let main = match top.as_slice() {
        [m] if m.id == b"MAIN" => m,
        _ => return Err(bad("expected exactly one top-level MAIN chunk".into())),
    };
    let children = chunks(main.children, bytes.len() - main.children.len(), name)?;
    let size = children.iter().find(|c| c.id == b"SIZE").ok_or_else(|| bad("no SIZE chunk".into()))?;
    let xyzi = children.iter().find(|c| c.id == b"XYZI").ok_or_else(|| bad("no XYZI chunk".into()))?;
    if size.content.len() < 12 {
        return Err(bad(format!("SIZE chunk has {} bytes, expected 12", size.content.len())));
    }
    let s = [0, 4, 8].map(|o| i32_at(size.content, o));
    if s.iter().any(|&v| v <= 0 || v as usize > MAX_VOX_SIDE) {
        return Err(bad(format!("SIZE {s:?} is outside 1..={MAX_VOX_SIDE} per axis")));
    }
    let [sx, sy, sz] = s.map(|v| v as usize);
    let dims = [sx, sz, sy];
    check_dims(name, dims)?;
    if xyzi.content.len() < 4 {
        return Err(bad("XYZI chunk has no voxel count".into()));
    }
    let count = i32_at(xyzi.content, 0);
    let data = &xyzi.content[4..];
    if count < 0 || count as usize > sx * sy * sz || data.len() < 4 * count as usize {
        return Err(bad(format!(
            "XYZI voxel count {count} does not fit a {sx}x{sy}x{sz} model in {} data bytes",
            data.len()
        )));
    }
    let palette = match children.iter().find(|c| c.id == b"RGBA") {
        Some(p) if p.content.len() < 1024 => {
            return Err(bad(format!("RGBA chunk has {} bytes, expected 1024", p.content.len())));
        }
        Some(p) => Some(p.content),
        None => None,
    };
    let mut grid = VoxelGrid::zeros(dims)?;
    let n = grid.len();
    let mut colour = palette.map(|_| vec![0.0f32; 3 * n]);
    for (i, v) in data[..4 * count as usize].chunks_exact(4).enumerate() {
        let [x, y, z, c] = [v[0], v[1], v[2], v[3]].map(|b| b as usize);
        if x >= sx || y >= sy || z >= sz {
            return Err(bad(format!("voxel {i} at ({x}, {y}, {z}) is outside SIZE {s:?}")));
        }
        if c == 0 {
            return Err(bad(format!("voxel {i} has colour index 0 (reserved for empty)")));
        }
        let (d, h, w) = (x, z, sy - 1 - y);
        grid.set(d, h, w, 1.0);
        if let (Some(col), Some(pal)) = (colour.as_mut(), palette) {
            let k = grid.index(d, h, w);
            for ch in 0..3 {
                col[ch * n + k] = pal[4 * (c - 1) + ch] as f32 / 255.0;
            }
        }
    }
    match colour {
        Some(c) => grid.with_colour(c),
        None => Ok(grid),
    }
}

/// Encodes a grid as version-150 `.vox` bytes: voxels with occupancy >= 0.5 (the binvox
/// threshold), axes as in the module doc. With colour, each voxel's RGB is rounded to bytes
/// and the distinct colours form the palette (at most 255, else an error); without, every
/// voxel gets index 1 and no `RGBA` chunk is written (so reading back gives no colour).
pub fn to_bytes(grid: &VoxelGrid) -> Result<Vec<u8>, VoxelError> {
    let what = "vox encode";
    let [d, h, w] = grid.dims();
    if grid.dims().iter().any(|&s| s > MAX_VOX_SIDE) {
        return Err(VoxelError::invalid(what, format!("dims {:?} exceed {MAX_VOX_SIDE} per axis", grid.dims())));
    }
    let (sx, sy, sz) = (d, w, h);
    let n = grid.len();
    let mut palette: Vec<[u8; 3]> = Vec::new();
    let mut voxels = Vec::new();
    for x in 0..sx {
        for y in 0..sy {
            for z in 0..sz {
                let (dd, hh, ww) = (x, z, sy - 1 - y);
                if grid.get(dd, hh, ww) < 0.5 {
                    continue;
                }
                let index = match grid.colour() {
                    None => 1,
                    Some(c) => {
                        let k = grid.index(dd, hh, ww);
                        let rgb = [0, 1, 2].map(|ch| (c[ch * n + k].clamp(0.0, 1.0) * 255.0).round() as u8);
                        let p = palette.iter().position(|&q| q == rgb).unwrap_or_else(|| {
                            palette.push(rgb);
                            palette.len() - 1
                        });
                        if p >= 255 {
                            return Err(VoxelError::invalid(what, "more than 255 distinct colours"));
                        }
                        p as u8 + 1
                    }
                };
                voxels.extend([x as u8, y as u8, z as u8, index]);
            }
        }
    }
    let chunk = |id: &[u8; 4], content: &[u8]| {
        let mut b = id.to_vec();
        b.extend((content.len() as i32).to_le_bytes());
        b.extend(0i32.to_le_bytes());
        b.extend_from_slice(content);
        b
    };
    let size: Vec<u8> = [sx, sy, sz].iter().flat_map(|&v| (v as i32).to_le_bytes()).collect();
    let mut xyzi = ((voxels.len() / 4) as i32).to_le_bytes().to_vec();
    xyzi.extend(voxels);
    let mut body = [chunk(b"SIZE", &size), chunk(b"XYZI", &xyzi)].concat();
    if grid.colour().is_some() {
        let mut rgba = vec![0u8; 1024];
        for (i, p) in palette.iter().enumerate() {
            rgba[4 * i..4 * i + 4].copy_from_slice(&[p[0], p[1], p[2], 255]);
        }
        body.extend(chunk(b"RGBA", &rgba));
    }
    let mut out = b"VOX ".to_vec();
    out.extend(150i32.to_le_bytes());
    out.extend(b"MAIN");
    out.extend(0i32.to_le_bytes());
    out.extend((body.len() as i32).to_le_bytes());
    out.extend(body);
    Ok(out)
}
