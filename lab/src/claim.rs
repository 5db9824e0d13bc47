//! Claim files: among the processes sharing a folder (threads, processes, the nodes of a
//! cluster on a shared filesystem), the one that creates a claim file first (created
//! exclusively, `O_EXCL`) does a piece of work; the others wait for its result.
//!
//! A claim holds its owner (host, pid, start time) and a beat counter that the owner
//! rewrites while it works ([`Claim::beat`]). A waiter judges staleness by its own
//! clock, never by the owner's or the file server's ([`Watch`]): a claim whose text has not
//! changed for the stale time is stale, and so, at once, is a claim of a process on the
//! waiter's own host that no longer runs. A stale claim is taken over: removed if it
//! still reads as it did, then created again. Two waiters that take over the same stale
//! claim at the same moment may both win, so a piece of work is done twice at most per
//! stale claim; never while its owner beats.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// This machine's host name (`unknown-host` if it has none that reads as text).
pub fn host() -> String {
    let h = gethostname::gethostname();
    match h.to_str() {
        Some(s) if !s.is_empty() => s.to_string(),
        _ => "unknown-host".to_string(),
    }
}

/// Seconds since the Unix epoch by this machine's clock (0 before it).
pub fn unix_now() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs())
}

/// A name part unique to this process among all hosts: `HOST.PID`, with characters other
/// than letters, digits, `-` and `_` written as `_`.
pub fn process_tag() -> String {
    let host: String = host()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{host}.{}", std::process::id())
}

/// A held claim; dropping it removes the file (if it is still this owner's).
#[derive(Debug)]
pub struct Claim {
    path: PathBuf,
    /// The owner line (host, pid, start), which also tells this owner's file apart.
    owner: String,
    beats: u64,
}

/// What [`Claim::try_take`] found.
#[derive(Debug)]
pub enum Attempt {
    /// The claim is ours.
    Taken(Claim),
    /// Another owner holds it: the claim file's text.
    Held(String),
}

impl Claim {
    /// Creates the claim file at `path` exclusively, or reports the text of the one there.
    pub fn try_take(path: &Path) -> std::io::Result<Attempt> {
        let owner = format!("host={} pid={} since={}", host(), std::process::id(), unix_now());
        let text = format!("{owner}\nbeat=0\n");
        match std::fs::OpenOptions::new().write(true).create_new(true).open(path) {
            Ok(mut f) => {
                f.write_all(text.as_bytes())?;
                Ok(Attempt::Taken(Claim {
                    path: path.to_path_buf(),
                    owner,
                    beats: 0,
                }))
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => match read_claim(path) {
                Ok(t) => Ok(Attempt::Held(t)),
                // released between the two calls: try again
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Claim::try_take(path),
                Err(e) => Err(e),
            },
            Err(e) => Err(e),
        }
    }

    /// The claim's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Tells waiters that the owner still works: the beat counter, rewritten whole (a
    /// temporary file of this process's own name, renamed over the claim).
    pub fn beat(&mut self) -> std::io::Result<()> {
        self.beats += 1;
        let tmp = self.path.with_extension(format!("{}.beat", process_tag()));
        // created exclusively: a link planted under the temporary name in a shared cache
        // is refused, not written through
        let _ = std::fs::remove_file(&tmp);
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        std::io::Write::write_all(&mut f, format!("{}\nbeat={}\n", self.owner, self.beats).as_bytes())?;
        drop(f);
        std::fs::rename(&tmp, &self.path)
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        // Remove only our own claim: one taken over as stale is another's now.
        if read_claim(&self.path).is_ok_and(|t| t.starts_with(&self.owner)) {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// A claim's owner as its text states it: host and pid.
fn owner_of(text: &str) -> Option<(&str, u32)> {
    let line = text.lines().next()?;
    let mut host = None;
    let mut pid = None;
    for part in line.split(' ') {
        if let Some(h) = part.strip_prefix("host=") {
            host = Some(h);
        } else if let Some(p) = part.strip_prefix("pid=") {
            pid = p.parse().ok();
        }
    }
    Some((host?, pid?))
}

/// The owner in words, for messages: `host vm, pid 41`.
pub fn describe(text: &str) -> String {
    match owner_of(text) {
        Some((h, p)) => format!("host {h}, pid {p}"),
        None => "an owner not named yet".to_string(),
    }
}

/// Whether the claim's owner is a process of this host that has ended (Linux: no
/// `/proc/PID`); `false` where that cannot be told.
fn owner_ended(text: &str) -> bool {
    let Some((h, pid)) = owner_of(text) else {
        return false;
    };
    h == host() && Path::new("/proc/self").exists() && !Path::new(&format!("/proc/{pid}")).exists()
}

/// A waiter's view of one claim: the text it last read and since when, by its own clock.
#[derive(Debug)]
pub struct Watch {
    stale_after: Duration,
    last: Option<(String, Instant)>,
}

impl Watch {
    pub fn new(stale_after: Duration) -> Watch {
        Watch { stale_after, last: None }
    }

    /// Whether the claim whose text now reads `text` is stale: its owner's process ended
    /// on this host, or its text has not changed for the stale time.
    pub fn is_stale(&mut self, text: &str) -> bool {
        if owner_ended(text) {
            return true;
        }
        let now = Instant::now();
        match &self.last {
            Some((t, since)) if t == text => now.duration_since(*since) >= self.stale_after,
            _ => {
                self.last = Some((text.to_string(), now));
                false
            }
        }
    }

    /// Forgets what it read (after a take-over).
    pub fn reset(&mut self) {
        self.last = None;
    }
}

/// A claim file's text: a regular file of at most [`MAX_CLAIM_BYTES`] (a FIFO planted in a
/// shared cache would hang every task that needs the truth).
fn read_claim(path: &Path) -> std::io::Result<String> {
    sshc_scene::read_text(path, MAX_CLAIM_BYTES)
}

/// The largest claim file read: a host name, a process id and a time.
pub const MAX_CLAIM_BYTES: u64 = 4096;

/// Removes a stale claim at `path` if it still reads `text` (a take-over: the caller then
/// tries [`Claim::try_take`] again).
pub fn remove_stale(path: &Path, text: &str) -> std::io::Result<()> {
    match read_claim(path) {
        Ok(t) if t == text => match std::fs::remove_file(path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
            _ => Ok(()),
        },
        Ok(_) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sshc-claim-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn one_taker_and_the_others_see_its_owner() {
        let d = dir("one");
        let p = d.join("k.claim");
        let Attempt::Taken(mut c) = Claim::try_take(&p).unwrap() else {
            panic!("the first take")
        };
        let Attempt::Held(text) = Claim::try_take(&p).unwrap() else {
            panic!("the second take")
        };
        assert_eq!(owner_of(&text), Some((host().as_str(), std::process::id())));
        assert!(describe(&text).contains(&format!("pid {}", std::process::id())));
        // a live owner on this host: not stale until its text stands still for the stale time
        let mut w = Watch::new(Duration::from_millis(200));
        assert!(!w.is_stale(&text));
        c.beat().unwrap();
        let beaten = std::fs::read_to_string(&p).unwrap();
        assert!(beaten.ends_with("beat=1\n"), "{beaten}");
        assert!(!w.is_stale(&beaten), "a beat renews the claim");
        std::thread::sleep(Duration::from_millis(250));
        assert!(w.is_stale(&beaten), "no beat for the stale time");
        drop(c);
        assert!(!p.exists(), "dropping the claim removes it");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "no beat files left");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_claim_of_an_ended_process_on_this_host_is_stale_at_once_and_taken_over() {
        let d = dir("ended");
        let p = d.join("k.claim");
        // a pid no process has (above the kernel's pid_max of 2^22)
        let text = format!("host={} pid=4194305 since=0\nbeat=0\n", host());
        std::fs::write(&p, &text).unwrap();
        let mut w = Watch::new(Duration::from_secs(3600));
        assert!(w.is_stale(&text));
        // another host's claim is judged by its beats alone
        assert!(!w.is_stale("host=elsewhere pid=1 since=0\nbeat=0\n"));
        remove_stale(&p, &text).unwrap();
        assert!(matches!(Claim::try_take(&p).unwrap(), Attempt::Taken(_)));
        // a claim that changed since it was read is left alone
        std::fs::write(&p, "host=elsewhere pid=1 since=0\nbeat=7\n").unwrap();
        remove_stale(&p, &text).unwrap();
        assert!(p.exists());
        let _ = std::fs::remove_dir_all(&d);
    }
}
