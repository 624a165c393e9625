//! Plain-Rust f64 references for every kernel: simple loops that read like the maths, the
//! oracle the GPU kernels are tested against (forward directly, backward through finite
//! differences of these forwards).
#![allow(dead_code)]

pub mod activations;
pub mod adam;
pub mod conv;
pub mod loss;
pub mod phong;
pub mod projection;
pub mod resample;
pub mod resize_conv;
pub mod composite;
pub mod concat;
pub mod expand;
pub mod mul;
