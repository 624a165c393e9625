//! Plain-Rust f64 references of every kernel, shared by the kernel tests.
#![allow(dead_code)]

pub mod adam;
pub mod loss;
pub mod phong;
