//! Technique files as Bevy assets: a `.ron` technique compiled by sshc when Bevy loads it
//! (and again when its file changes, through Bevy's asset watcher).
//!
//! A file that does not compile is a load error carrying sshc's diagnostic, rendered with
//! the file's path and the line and column of each problem; Bevy logs it, and a technique
//! already loaded from that file keeps its last good version (a failed reload replaces
//! nothing).

use bevy::asset::{Asset, AssetLoader, LoadContext, io::Reader};
use bevy::reflect::TypePath;

/// Largest technique file read (the CLI's own cap: a technique is a few kilobytes).
pub const MAX_TECHNIQUE_BYTES: usize = 1 << 20;

/// A compiled technique: its pass graph and its WGSL, as `sshc compile` writes them.
#[derive(Asset, TypePath, Clone, Debug)]
pub struct SshcTechnique {
    pub compiled: sshc::Compiled,
}

impl SshcTechnique {
    /// The technique's name (from its file).
    pub fn name(&self) -> &str {
        &self.compiled.graph.technique
    }
}

/// Compiles `.ron` technique files.
#[derive(Default, TypePath)]
pub struct TechniqueLoader;

/// Why a technique file did not load: its bytes, or sshc's diagnostic.
#[derive(Debug)]
pub enum TechniqueError {
    Read(String),
    Compile(String),
}

impl std::fmt::Display for TechniqueError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TechniqueError::Read(m) | TechniqueError::Compile(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for TechniqueError {}

/// Compile a technique's source, `path` naming it in the diagnostic.
pub fn compile(path: &str, bytes: &[u8]) -> Result<sshc::Compiled, TechniqueError> {
    if bytes.len() > MAX_TECHNIQUE_BYTES {
        return Err(TechniqueError::Read(format!(
            "{path}: more than the {MAX_TECHNIQUE_BYTES} bytes a technique file may have ({} read)",
            bytes.len()
        )));
    }
    let source = std::str::from_utf8(bytes).map_err(|e| TechniqueError::Read(format!("{path}: not UTF-8: {e}")))?;
    sshc::compile_str(source, &Default::default()).map_err(|d| TechniqueError::Compile(d.render(path, source)))
}

impl AssetLoader for TechniqueLoader {
    type Asset = SshcTechnique;
    type Settings = ();
    type Error = TechniqueError;

    async fn load(&self, reader: &mut dyn Reader, _: &(), load_context: &mut LoadContext<'_>) -> Result<SshcTechnique, TechniqueError> {
        let path = load_context.path().to_string();
        // read at most one byte past the cap: a larger file is refused by `compile`
        // without being read whole
        use bevy::tasks::futures_lite::AsyncReadExt;
        let mut bytes = Vec::new();
        reader
            .take(MAX_TECHNIQUE_BYTES as u64 + 1)
            .read_to_end(&mut bytes)
            .await
            .map_err(|e| TechniqueError::Read(format!("{path}: {e}")))?;
        Ok(SshcTechnique {
            compiled: compile(&path, &bytes)?,
        })
    }

    fn extensions(&self) -> &[&str] {
        &["technique.ron", "ron"]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_past_the_cap_or_broken_is_refused_naming_it() {
        let e = compile("t/big.ron", &vec![b' '; MAX_TECHNIQUE_BYTES + 1]).unwrap_err().to_string();
        assert!(e.starts_with("t/big.ron: more than"), "{e}");
        let e = compile("t/bad.ron", b"Technique(name: \"x\", passes: [").unwrap_err().to_string();
        assert!(e.contains("t/bad.ron:1:"), "{e}");
        let e = compile("t/bin.ron", &[0xff, 0xfe]).unwrap_err().to_string();
        assert!(e.contains("not UTF-8"), "{e}");
    }
}
