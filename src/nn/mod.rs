//! Networks built from graph ops: RenderNet and its presets, and the camera conventions that
//! tie its resampling to the reference renderer's images.

pub mod camera;
pub mod ec;
pub mod prior;
pub mod texture;
pub mod render;
pub mod rendernet;
