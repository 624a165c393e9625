//! Voxel grids as safetensors: an `occupancy` tensor `[D, H, W]` (f32, or u8 holding
//! occupancy x 255 for a file a quarter the size, as the committed fixtures use) and an
//! optional `colour` f32 tensor `[3, D, H, W]`. Nothing else may be in the file, so a checkpoint or a grid from
//! another tool is rejected with a clear message rather than misread.

use super::{VoxelError, VoxelGrid, check_dims, read_file, write_file};
use safetensors::{Dtype, SafeTensors, tensor::TensorView};
use std::path::Path;

/// Name of the occupancy tensor.
pub const OCCUPANCY: &str = "occupancy";
/// Name of the optional colour tensor.
pub const COLOUR: &str = "colour";

/// Encodes a grid as safetensors bytes.
pub fn to_bytes(grid: &VoxelGrid) -> Result<Vec<u8>, VoxelError> {
    encode(grid, false)
}

/// Encodes a grid with occupancy quantised to u8 (`round(255 v)`; colour stays f32): a
/// quarter the size, and the error (at most 1/510) moves an iso-surface by far less than a voxel.
pub fn to_bytes_u8(grid: &VoxelGrid) -> Result<Vec<u8>, VoxelError> {
    encode(grid, true)
}

fn encode(grid: &VoxelGrid, quantise: bool) -> Result<Vec<u8>, VoxelError> {
    let [d, h, w] = grid.dims();
    let (occ_dtype, occ) = if quantise {
        let q = grid.occupancy().iter().map(|&v| (v * 255.0).round() as u8).collect();
        (Dtype::U8, q)
    } else {
        (Dtype::F32, le_bytes(grid.occupancy()))
    };
    let colour = grid.colour().map(le_bytes);
    let err =
        |e: safetensors::SafeTensorError| VoxelError::invalid("safetensors encode", e.to_string());
    let mut tensors = vec![(
        OCCUPANCY,
        TensorView::new(occ_dtype, vec![d, h, w], &occ).map_err(err)?,
    )];
    if let Some(c) = &colour {
        tensors.push((
            COLOUR,
            TensorView::new(Dtype::F32, vec![3, d, h, w], c).map_err(err)?,
        ));
    }
    safetensors::serialize(tensors, None).map_err(err)
}

/// Writes a grid to a `.safetensors` file.
pub fn write(grid: &VoxelGrid, path: impl AsRef<Path>) -> Result<(), VoxelError> {
    write_file(path.as_ref(), &to_bytes(grid)?)
}

/// Writes a grid to a `.safetensors` file with u8 occupancy ([`to_bytes_u8`]).
pub fn write_u8(grid: &VoxelGrid, path: impl AsRef<Path>) -> Result<(), VoxelError> {
    write_file(path.as_ref(), &to_bytes_u8(grid)?)
}

/// Reads a grid from a `.safetensors` file.
pub fn read(path: impl AsRef<Path>) -> Result<VoxelGrid, VoxelError> {
    let (name, bytes) = read_file(path.as_ref())?;
    from_bytes(&bytes, &name)
}

/// Decodes safetensors bytes (occupancy f32 or u8 / 255); `name` is used in error messages.
/// Checks tensor names, dtypes, shapes, limits and value ranges (occupancy in `[0, 1]`, colour finite).
pub fn from_bytes(bytes: &[u8], name: &str) -> Result<VoxelGrid, VoxelError> {
    let st = SafeTensors::deserialize(bytes).map_err(|e| {
        VoxelError::malformed(name, None, format!("not a valid safetensors file: {e}"))
    })?;
    for n in st.names() {
        if n != OCCUPANCY && n != COLOUR {
            return Err(VoxelError::malformed(
                name,
                None,
                format!(
                    "unexpected tensor {n:?} (expected only {OCCUPANCY:?} and optional {COLOUR:?})"
                ),
            ));
        }
    }
    let occ = st
        .tensor(OCCUPANCY)
        .map_err(|_| VoxelError::malformed(name, None, format!("no {OCCUPANCY:?} tensor")))?;
    let shape = occ.shape();
    if shape.len() != 3 {
        return Err(VoxelError::malformed(
            name,
            None,
            format!("{OCCUPANCY:?} has shape {shape:?}, expected [D, H, W]"),
        ));
    }
    let dims = [shape[0], shape[1], shape[2]];
    check_dims(name, dims)?;
    let occupancy = if occ.dtype() == Dtype::U8 {
        occ.data().iter().map(|&b| b as f32 / 255.0).collect()
    } else {
        f32_values(name, OCCUPANCY, &occ)?
    };
    if let Some(i) = occupancy.iter().position(|v| !(0.0..=1.0).contains(v)) {
        return Err(VoxelError::malformed(
            name,
            None,
            format!("{OCCUPANCY}[{i}] = {} is outside [0, 1]", occupancy[i]),
        ));
    }
    let grid = VoxelGrid::new(dims, occupancy)?;
    let Ok(col) = st.tensor(COLOUR) else {
        return Ok(grid);
    };
    let want = [3, dims[0], dims[1], dims[2]];
    if col.shape() != want {
        return Err(VoxelError::malformed(
            name,
            None,
            format!("{COLOUR:?} has shape {:?}, expected {want:?}", col.shape()),
        ));
    }
    let colour = f32_values(name, COLOUR, &col)?;
    if let Some(i) = colour.iter().position(|v| !v.is_finite()) {
        return Err(VoxelError::malformed(
            name,
            None,
            format!("{COLOUR}[{i}] is not finite"),
        ));
    }
    grid.with_colour(colour)
}

/// f32 values of a tensor, rejecting other dtypes. Copies through `from_le_bytes` because the
/// data need not be 4-byte aligned inside the file buffer.
fn f32_values(file: &str, tensor: &str, view: &TensorView<'_>) -> Result<Vec<f32>, VoxelError> {
    if view.dtype() != Dtype::F32 {
        return Err(VoxelError::malformed(
            file,
            None,
            format!("{tensor:?} has dtype {:?}, expected F32", view.dtype()),
        ));
    }
    Ok(view
        .data()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

fn le_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}
