//! Subcommand implementations: parse, call the library, report.

pub mod dataset;
pub mod info;
pub mod truth;
