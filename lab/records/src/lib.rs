//! The files sshc's lab commands write and read back across processes and machines: a
//! sweep shard's manifest and records ([`sweep`]), the truth cache's records ([`truth`]),
//! the error figures their rows hold ([`accuracy`]), and the viewer's scripts
//! ([`script`]). Types and the checked reading of
//! their contents, with no GPU, file I/O or command line, so that the fuzz targets
//! (compiler/fuzz: `shard`, `truth`, `script`) reach exactly the code the lab runs.

pub mod accuracy;
pub mod script;
pub mod sweep;
pub mod truth;
