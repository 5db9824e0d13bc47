//! The measurement commands of the `sshc` command line; their arguments are clap structs
//! that the binary flattens into its subcommands.

pub mod compare;
pub mod render;
pub mod sweep;
pub mod truth;
pub mod tune;
pub mod verify;
