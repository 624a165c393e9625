//! PLY loader (ascii, binary_little_endian and binary_big_endian): keeps `vertex` x, y, z (and
//! red, green, blue when present) and `face` `vertex_indices` (or `vertex_index`) lists; every
//! other element and property is read past using its declared type, so scanner output with
//! extra properties loads too.

use super::{MAX_TRIANGLES, MAX_VERTICES, Mesh, VoxelError};

/// Polygons larger than this are rejected (real files have 3 or 4; guards allocation).
const MAX_POLYGON: usize = 1 << 16;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Format {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// A scalar type and its size in bytes.
#[derive(Clone, Copy, Debug)]
struct Scalar {
    size: usize,
    float: bool,
    signed: bool,
}

#[derive(Debug)]
enum Property {
    Scalar(String, Scalar),
    List(String, Scalar, Scalar),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

fn scalar(ty: &str) -> Option<Scalar> {
    let (size, float, signed) = match ty {
        "char" | "int8" => (1, false, true),
        "uchar" | "uint8" => (1, false, false),
        "short" | "int16" => (2, false, true),
        "ushort" | "uint16" => (2, false, false),
        "int" | "int32" => (4, false, true),
        "uint" | "uint32" => (4, false, false),
        "float" | "float32" => (4, true, true),
        "double" | "float64" => (8, true, true),
        _ => return None,
    };
    Some(Scalar {
        size,
        float,
        signed,
    })
}

/// Parses PLY bytes; `name` is used in error messages (header and ascii errors give the line,
/// binary errors the byte offset).
pub fn parse_ply(bytes: &[u8], name: &str) -> Result<Mesh, VoxelError> {
    let (format, elements, body, header_lines) = parse_header(bytes, name)?;
    let mut reader = match format {
        Format::Ascii => Reader::Ascii {
            lines: std::str::from_utf8(&bytes[body..]).unwrap_or("").lines(),
            line: header_lines,
            tokens: Vec::new(),
            next: 0,
        },
        _ => Reader::Binary {
            bytes,
            pos: body,
            le: format == Format::BinaryLe,
        },
    };
    let mut mesh = Mesh::default();
    let mut poly = Vec::new();
    let mut n_vertices: Option<usize> = None;
    for el in &elements {
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        if is_vertex {
            mesh.positions.reserve(el.count.min(bytes.len() / 12));
            n_vertices = Some(el.count);
        }
        // Vertex colours: `red`, `green`, `blue`, integers scaled by 255 (uchar, as scanners
        // and Blender write them) or floats in [0, 1].
        let has_colour = is_vertex
            && ["red", "green", "blue"].iter().all(|c| el.props.iter().any(|p| matches!(p, Property::Scalar(n, _) if n == c)));
        for _ in 0..el.count {
            let mut p = [0.0f32; 3];
            let mut rgb = [1.0f32; 3];
            for prop in &el.props {
                match prop {
                    Property::Scalar(pname, ty) => {
                        let v = reader.scalar(*ty, name)?;
                        if let (true, Some(axis)) =
                            (is_vertex, ["x", "y", "z"].iter().position(|a| a == pname))
                        {
                            p[axis] = v as f32;
                        }
                        if let (true, Some(c)) = (has_colour, ["red", "green", "blue"].iter().position(|a| a == pname)) {
                            rgb[c] = if ty.float { v as f32 } else { v as f32 / 255.0 };
                        }
                    }
                    Property::List(pname, count_ty, item_ty) => {
                        let n = reader.scalar(*count_ty, name)?;
                        if !(0.0..=MAX_POLYGON as f64).contains(&n) || n.fract() != 0.0 {
                            return Err(reader.error(
                                name,
                                format!("list length {n} is invalid (limit {MAX_POLYGON})"),
                            ));
                        }
                        let wanted =
                            is_face && (pname == "vertex_indices" || pname == "vertex_index");
                        poly.clear();
                        for _ in 0..n as usize {
                            let v = reader.scalar(*item_ty, name)?;
                            if wanted {
                                let nv = n_vertices.unwrap_or(0);
                                if v < 0.0 || v >= nv as f64 || v.fract() != 0.0 {
                                    return Err(reader.error(
                                        name,
                                        format!("face index {v} out of range ({nv} vertices)"),
                                    ));
                                }
                                poly.push(v as u32);
                            }
                        }
                        if wanted {
                            let line = reader.line();
                            mesh.push_polygon(&poly, name, line)
                                .map_err(|e| reader.rewrap(e, name))?;
                        }
                    }
                }
            }
            if is_vertex {
                let line = reader.line();
                mesh.push_vertex(p, name, line)
                    .map_err(|e| reader.rewrap(e, name))?;
                mesh.set_last_colour(has_colour.then_some(rgb), name, line)
                    .map_err(|e| reader.rewrap(e, name))?;
            }
        }
    }
    Ok(mesh)
}

/// Parses the header; returns the format, elements, the byte offset of the body and the
/// number of header lines (so ascii body errors report file line numbers).
fn parse_header(
    bytes: &[u8],
    name: &str,
) -> Result<(Format, Vec<Element>, usize, usize), VoxelError> {
    let mut pos = 0;
    let mut lineno = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map(|p| pos + p);
        let Some(end) = end else {
            return Err(VoxelError::malformed(
                name,
                Some(lineno.max(1)),
                "header has no 'end_header' line",
            ));
        };
        lineno += 1;
        let bad = |m: String| VoxelError::malformed(name, Some(lineno), m);
        let line = std::str::from_utf8(&bytes[pos..end])
            .map_err(|_| bad("header is not text".into()))?
            .trim();
        pos = end + 1;
        let tok: Vec<&str> = line.split_whitespace().collect();
        match tok.as_slice() {
            ["ply"] if lineno == 1 => {}
            _ if lineno == 1 => return Err(bad(format!("expected 'ply' magic, found {line:?}"))),
            ["format", f, _version] => {
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    _ => return Err(bad(format!("unsupported format {f:?}"))),
                })
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", el, count] => {
                let count: usize = count
                    .parse()
                    .map_err(|_| bad(format!("bad element count {count:?}")))?;
                let limit = if *el == "face" {
                    MAX_TRIANGLES
                } else {
                    MAX_VERTICES
                };
                VoxelError::check_limit(
                    name,
                    &format!("{el} elements"),
                    count as u128,
                    limit as u128,
                )?;
                elements.push(Element {
                    name: el.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", ct, it, pname] => {
                let (c, i) = (scalar(ct), scalar(it));
                let (Some(c), Some(i)) = (c, i) else {
                    return Err(bad(format!("unknown list types {ct:?} {it:?}")));
                };
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element".into()))?;
                el.props.push(Property::List(pname.to_string(), c, i));
            }
            ["property", ty, pname] => {
                let ty = scalar(ty).ok_or_else(|| bad(format!("unknown property type {ty:?}")))?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before any element".into()))?;
                el.props.push(Property::Scalar(pname.to_string(), ty));
            }
            ["end_header"] => break,
            _ => return Err(bad(format!("unrecognised header line {line:?}"))),
        }
    }
    let format = format
        .ok_or_else(|| VoxelError::malformed(name, Some(lineno), "header has no 'format' line"))?;
    let vertex = elements.iter().position(|e| e.name == "vertex");
    let Some(v) = vertex else {
        return Err(VoxelError::malformed(name, None, "no 'vertex' element"));
    };
    for axis in ["x", "y", "z"] {
        if !elements[v]
            .props
            .iter()
            .any(|p| matches!(p, Property::Scalar(n, _) if n == axis))
        {
            return Err(VoxelError::malformed(
                name,
                None,
                format!("vertex element has no '{axis}' property"),
            ));
        }
    }
    if elements
        .iter()
        .position(|e| e.name == "face")
        .is_some_and(|f| f < v)
    {
        return Err(VoxelError::malformed(
            name,
            None,
            "'face' element comes before 'vertex' (unsupported)",
        ));
    }
    Ok((format, elements, pos, lineno))
}

/// Reads scalars from the body in either encoding; all values come back as f64 (exact for
/// every PLY integer type).
enum Reader<'a> {
    Ascii {
        lines: std::str::Lines<'a>,
        line: usize,
        tokens: Vec<&'a str>,
        next: usize,
    },
    Binary {
        bytes: &'a [u8],
        pos: usize,
        le: bool,
    },
}

impl<'a> Reader<'a> {
    fn scalar(&mut self, ty: Scalar, name: &str) -> Result<f64, VoxelError> {
        match self {
            Reader::Ascii {
                lines,
                line,
                tokens,
                next,
            } => {
                while *next >= tokens.len() {
                    let Some(l) = lines.next() else {
                        return Err(VoxelError::malformed(
                            name,
                            Some(*line),
                            "file ends before all elements were read",
                        ));
                    };
                    *line += 1;
                    *tokens = l.split_whitespace().collect();
                    *next = 0;
                }
                let s = tokens[*next];
                *next += 1;
                s.parse::<f64>()
                    .ok()
                    .filter(|v| ty.float || v.fract() == 0.0)
                    .ok_or_else(|| {
                        VoxelError::malformed(name, Some(*line), format!("bad number {s:?}"))
                    })
            }
            Reader::Binary { bytes, pos, le } => {
                let Some(b) = bytes.get(*pos..*pos + ty.size) else {
                    return Err(VoxelError::malformed(
                        name,
                        None,
                        format!("truncated binary data at byte {pos}"),
                    ));
                };
                *pos += ty.size;
                let mut buf = [0u8; 8];
                buf[..ty.size].copy_from_slice(b);
                if !*le {
                    buf[..ty.size].reverse();
                }
                Ok(match (ty.size, ty.float, ty.signed) {
                    (4, true, _) => f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    (8, true, _) => f64::from_le_bytes(buf),
                    (1, _, true) => buf[0] as i8 as f64,
                    (2, _, true) => i16::from_le_bytes([buf[0], buf[1]]) as f64,
                    (4, _, true) => i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]]) as f64,
                    _ => u64::from_le_bytes(buf) as f64,
                })
            }
        }
    }

    /// Current 1-based line for ascii bodies.
    fn line(&self) -> Option<usize> {
        match self {
            Reader::Ascii { line, .. } => Some(*line),
            Reader::Binary { .. } => None,
        }
    }

    /// An error at the current position (line for ascii, byte offset for binary).
    fn error(&self, name: &str, msg: String) -> VoxelError {
        match self {
            Reader::Ascii { line, .. } => VoxelError::malformed(name, Some(*line), msg),
            Reader::Binary { pos, .. } => {
                VoxelError::malformed(name, None, format!("{msg} (before byte {pos})"))
            }
        }
    }

    /// Adds the byte offset to a malformed-content error raised by shared mesh code.
    fn rewrap(&self, e: VoxelError, name: &str) -> VoxelError {
        match (e, self) {
            (
                VoxelError::Malformed {
                    line: None, msg, ..
                },
                _,
            ) => self.error(name, msg),
            (e, _) => e,
        }
    }
}
