//! Subcommand implementations: parse, call the library, report.

pub mod bench;
pub mod dataset;
pub mod eval;
pub mod frontier;
pub mod info;
pub mod invert;
pub mod output;
pub mod prior;
pub mod render;
pub mod shape;
pub mod texture;
pub mod stress;
pub mod train;
pub mod truth;
pub mod weights;
