//! The one writer of the files lab commands write (issue 48, item 15): a file that exists
//! at an output's name must be a regular file, and whole files go through a temporary file
//! of their own renamed over the name, so that nothing is written through a link planted in
//! an output folder. Reading goes through `sshc_scene::read_capped` (the one reader).

use std::path::Path;

/// Refuses to write `path` where something other than a regular file stands there (a
/// planted link, a FIFO, a folder): what a command writes stays in its output folder.
pub fn writable(path: &Path) -> Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.is_file() => Err(format!(
            "error: `{}` exists and is not a regular file: refusing to write through it",
            path.display()
        )),
        _ => Ok(()),
    }
}

/// Readies an output named by `option` before the long work starts (issue 51): refuses
/// what [`writable`] refuses, and creates the folders of `path` that are missing, or says
/// why they cannot be made (a file where a folder must be, no permission), so that no
/// command renders a frame and then fails to write it.
pub fn output_file(path: &Path, option: &str) -> Result<(), String> {
    writable(path)?;
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => output_folder(dir, option, path),
        None => Ok(()),
    }
}

/// Creates the folder `dir` (and those above it) where missing, for the output `path` named
/// by `option` (`path` is `dir` itself for an option that names a folder).
pub fn output_folder(dir: &Path, option: &str, path: &Path) -> Result<(), String> {
    if dir.is_dir() {
        return Ok(());
    }
    // a file where a folder must be, said as such (not "File exists" or "Not a directory")
    if let Some(file) = dir.ancestors().find(|a| !a.as_os_str().is_empty() && a.exists() && !a.is_dir()) {
        return Err(format!(
            "error: `{option} {}`: cannot create the folder `{}`: `{}` is a file, not a folder",
            path.display(),
            dir.display(),
            file.display()
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        format!(
            "error: `{option} {}`: cannot create the folder `{}`: {e}; name a file in a folder that exists or can be made",
            path.display(),
            dir.display()
        )
    })
}

/// The one writer of every file a command writes whole (issue 48, item 15): `contents`
/// to `path`, refusing where something other than a regular file stands there. The bytes
/// go to a temporary file of its own beside `path` (created exclusively, so never through
/// a link), renamed over `path`: a link planted between the check and the write is
/// replaced, not followed. The file is readable by all (0644), as `std::fs::write` leaves
/// it under the usual umask. A structural test (`no_file_is_written_around_the_one_writer`)
/// finds any other write in lab/.
pub fn write_new(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), String> {
    use std::io::Write as _;
    let fail = |e: &dyn std::fmt::Display| format!("error: cannot write `{}`: {e}", path.display());
    writable(path)?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let mut tmp = tempfile::Builder::new()
        .prefix(".sshc-write-")
        .tempfile_in(dir)
        .map_err(|e| fail(&e))?;
    tmp.write_all(contents.as_ref()).map_err(|e| fail(&e))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| fail(&e))?;
    }
    tmp.persist(path).map_err(|e| fail(&e.error))?;
    Ok(())
}

/// `path` opened for appending (created if absent), refusing where something other than
/// a regular file stands there: the logs a command appends to as it works.
pub fn append_to(path: &Path) -> Result<std::fs::File, String> {
    writable(path)?;
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(|e| format!("error: cannot write `{}`: {e}", path.display()))
}

/// An image encoded as its file name's extension says (PNG for `.png`), written by
/// [`write_new`].
pub fn save_image<P, C>(img: &image::ImageBuffer<P, C>, path: &Path) -> Result<(), String>
where
    P: image::Pixel + image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    let format = image::ImageFormat::from_path(path).map_err(|e| format!("error: cannot write `{}`: {e}", path.display()))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format)
        .map_err(|e| format!("error: cannot write `{}`: {e}", path.display()))?;
    write_new(path, bytes.into_inner())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Every `.rs` file of the lab and the scene crate, with its path from the lab's root.
    pub(crate) fn lab_sources() -> Vec<(String, String)> {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        let mut stack = vec![root.join("src"), root.join("scene/src")];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    let rel = p.strip_prefix(root).unwrap().display().to_string();
                    files.push((rel, std::fs::read_to_string(&p).unwrap()));
                }
            }
        }
        files
    }

    /// Issue 48, item 15: no writer of files in the lab or the scene crate but the one
    /// ([`write_new`], [`append_to`], [`save_image`]) and those named here with why: a
    /// `fs::write`, `File::create`, an image's `save` or a plotting backend on a path
    /// writes through a link planted in the output folder.
    #[test]
    fn no_file_is_written_around_the_one_writer() {
        // (file, what it writes): each checks the path first or cannot follow a link
        let allowed = [
            ("src/view/script.rs", "File::create(p)"), // the script's log, after `writable`
            ("src/cmd/sweep/shard.rs", "OpenOptions::new().write(true).open(&path)"), // cut a half-written line, after `writable`
            ("src/claim.rs", "create_new(true)"),      // exclusive: never through a link
            ("src/files.rs", "OpenOptions::new()"),    // `append_to`, after `writable`
        ];
        let writes = [
            "fs::write(",
            "File::create(",
            ".save(",
            "SVGBackend::new(",
            "BitMapBackend::new(",
            "OpenOptions::new(",
            "fs::copy(",
        ];
        let mut found = Vec::new();
        for (rel, text) in lab_sources() {
            let code = text.split("#[cfg(test)]").next().unwrap_or_default();
            for (n, line) in code.lines().enumerate() {
                let write = writes.iter().any(|w| line.contains(w));
                let kept = allowed.iter().any(|(file, what)| rel == *file && line.contains(what));
                if write && !kept && !line.trim_start().starts_with("//") {
                    found.push(format!("{rel}:{}: {}", n + 1, line.trim()));
                }
            }
        }
        assert!(found.is_empty(), "files written around session::write_new:\n{}", found.join("\n"));
    }

    /// The one writer replaces a file, refuses a link planted at its name (leaving the
    /// link's target as it was), and leaves no temporary file behind.
    #[test]
    fn the_one_writer_refuses_a_planted_link_and_replaces_a_file() {
        let dir = std::env::temp_dir().join(format!("sshc-writer-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let (file, outside, link) = (dir.join("out.txt"), dir.join("outside.txt"), dir.join("link.txt"));
        write_new(&file, "one").unwrap();
        write_new(&file, "two").unwrap();
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "two");
        std::fs::write(&outside, "kept").unwrap();
        std::os::unix::fs::symlink(&outside, &link).unwrap();
        let e = write_new(&link, "through").unwrap_err();
        assert!(e.contains("exists and is not a regular file"), "{e}");
        assert!(append_to(&link).is_err());
        assert_eq!(std::fs::read_to_string(&outside).unwrap(), "kept");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name()).collect();
        assert_eq!(left.len(), 3, "{left:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
