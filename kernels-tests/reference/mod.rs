//! Plain-Rust f64 references of the kernels, one module per op.
#![allow(dead_code)]

pub mod resample;
