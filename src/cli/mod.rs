//! Subcommand implementations: parse, call the library, report.

pub mod bench;
pub mod info;
pub mod truth;
