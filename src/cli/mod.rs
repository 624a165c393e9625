//! Subcommand implementations: parse, call the library, report.

pub mod info;
pub mod truth;
