//! Scripted use: a list of events a script replays frame by frame, and the JSON-lines log
//! of what happened (each event, each recompilation with its diagnostics, each screenshot
//! with the view's state). Tests read the log, not pixels, for what is text.

use std::io::Write as _;
use std::path::Path;

/// The events, their limits and their check (in `sshc-records`).
pub use sshc_records::script::{Event, MAX_TRUTH_ROUNDS, MAX_WAIT_FRAMES, MAX_WAIT_SECONDS, check};

/// Reads a script file, and checks each event's values ([`check`]).
pub fn load(path: &Path) -> Result<Vec<Event>, String> {
    let text = crate::session::read(path)?;
    sshc_records::script::parse(&text, path)
}

/// The log: one JSON object a line, flushed as written.
pub struct Log {
    file: Option<std::fs::File>,
}

impl Log {
    pub fn open(path: Option<&Path>) -> Result<Log, String> {
        let file = path
            .map(|p| {
                crate::session::writable(p)?;
                std::fs::File::create(p).map_err(|e| format!("error: cannot write `{}`: {e}", p.display()))
            })
            .transpose()?;
        Ok(Log { file })
    }

    /// Writes `entry` (a JSON object) with the frame number added.
    pub fn write(&mut self, frame: u64, mut entry: serde_json::Value) {
        if let Some(f) = &mut self.file {
            if let Some(o) = entry.as_object_mut() {
                o.insert("frame".into(), frame.into());
            }
            let _ = writeln!(f, "{entry}");
            let _ = f.flush();
        }
    }
}
