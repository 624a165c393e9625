//! The crate's error type for the GPU runtime and the ops. Every message names the tensor,
//! op, file or limit involved so a user can act on it without reading our source.

use std::fmt;

/// Errors from the GPU runtime and the ops.
#[derive(Debug)]
pub enum Error {
    /// No adapter matched; `tried` says which backends / names were asked for, `found` the
    /// adapters present that the name filter rejected, `advice` what to do in this case.
    NoAdapter { tried: String, found: Vec<String>, advice: String },
    /// The adapter exists but refused to give us a device.
    Device(String),
    /// A tensor or op argument has the wrong shape.
    Shape { op: String, msg: String },
    /// A size is beyond what the device allows (binding size, workgroup count...).
    Limit { what: String, value: u64, limit: u64, name: &'static str },
    /// Reading results back from the GPU failed.
    Readback(String),
    /// A file could not be read or written.
    Io { path: String, source: std::io::Error },
    /// A file or argument is malformed.
    Invalid(String),
}

/// Shorthand used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NoAdapter { tried, found, advice } => {
                write!(f, "no GPU adapter found (asked for {tried}")?;
                if found.is_empty() {
                    write!(f, "; those backends have none on this machine")?;
                } else {
                    write!(f, "; present but not matching: {}", found.join(", "))?;
                }
                write!(f, "). {advice}")
            }
            Error::Device(m) => write!(f, "could not open the GPU device: {m}"),
            Error::Shape { op, msg } => write!(f, "{op}: {msg}"),
            Error::Limit { what, value, limit, name } => {
                write!(f, "{what} is {value}, beyond the device limit {name} = {limit}")
            }
            Error::Readback(m) => write!(f, "reading back from the GPU failed: {m}"),
            Error::Io { path, source } => write!(f, "{path}: {source}"),
            Error::Invalid(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Builds a shape error for `op`.
pub(crate) fn shape_err(op: &str, msg: impl Into<String>) -> Error {
    Error::Shape { op: op.to_string(), msg: msg.into() }
}

impl From<crate::voxel::VoxelError> for Error {
    /// Voxel and mesh errors already name the file, the field and the limit.
    fn from(e: crate::voxel::VoxelError) -> Self {
        Error::Invalid(e.to_string())
    }
}
