//! Plain-Rust f64 references for the kernel tests, one module per op.
#![allow(dead_code)]

pub mod conv;
