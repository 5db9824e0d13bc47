//! What a scene of many triangles costs in memory, checked against what the process has
//! before its triangles are built (issue 48, item 14: the limit of 2^24 triangles needed
//! 5.8 GB, and under a 4 GB address-space cap the BVH builder panicked).
//!
//! The cost is measured, not derived (`scripts/memory-figures.sh`, the debug build on
//! lavapipe): `sshc truth` (the heaviest path: the triangles, their normals, the
//! ray-casting BVH built over them, the G-buffer frame) peaked at 625 and 648 MiB (two runs) for a
//! generated city of 1.0 M triangles and at 1,060 MiB for 2.0 M: 432 to 456 bytes a
//! triangle beyond about 200 MiB. `sshc render` took 246 to 288 bytes a triangle.
//! [`BYTES_PER_TRIANGLE`] and [`BASE_BYTES`] round the truth's figures up.

use std::path::Path;

/// Memory a scene needs beyond its triangles' (the process, the device, one frame).
pub const BASE_BYTES: u64 = 256 << 20;
/// Memory a scene needs per triangle, on the heaviest path (the truth's ray casting).
pub const BYTES_PER_TRIANGLE: u64 = 512;
/// Below this need no limit is read: a small scene is never refused, and nothing is read
/// from /proc for it.
pub const CHECKED_FROM_BYTES: u64 = 1 << 30;

/// The memory a scene of `triangles` triangles needs, in bytes.
pub fn needed(triangles: usize) -> u64 {
    BASE_BYTES.saturating_add((triangles as u64).saturating_mul(BYTES_PER_TRIANGLE))
}

/// The memory this process may still take, in bytes, and what bounds it: the least of
/// the system's available memory (`MemAvailable`), the cgroup's `memory.max` less its
/// `memory.current`, and the address-space limit (`ulimit -v`) less the process's size.
/// `None` where none of them can be read (not Linux).
pub fn available() -> Option<(u64, &'static str)> {
    let read = |p: &str| crate::read_text(Path::new(p), 1 << 16).ok();
    let field = |text: &str, key: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..].split_whitespace().next()?.parse().ok()
    };
    let mut bounds: Vec<(u64, &'static str)> = Vec::new();
    if let Some(m) = read("/proc/meminfo").and_then(|t| field(&t, "MemAvailable:")) {
        bounds.push((m.saturating_mul(1024), "the system's available memory"));
    }
    if let (Some(max), Some(cur)) = (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current"))
        && let (Ok(max), Ok(cur)) = (max.trim().parse::<u64>(), cur.trim().parse::<u64>())
    {
        bounds.push((max.saturating_sub(cur), "the cgroup's memory.max"));
    }
    if let Some(limits) = read("/proc/self/limits")
        && let Some(limit) = field(&limits, "Max address space")
    {
        let size = read("/proc/self/status").and_then(|t| field(&t, "VmSize:")).unwrap_or(0);
        bounds.push((
            limit.saturating_sub(size.saturating_mul(1024)),
            "the address-space limit (ulimit -v)",
        ));
    }
    bounds.into_iter().min_by_key(|b| b.0)
}

/// Refuses `triangles` where they need more memory than `available` holds, saying both.
pub fn check_with(triangles: usize, available: Option<(u64, &'static str)>) -> Result<(), String> {
    let need = needed(triangles);
    if need < CHECKED_FROM_BYTES {
        return Ok(());
    }
    match available {
        Some((have, what)) if have < need => Err(format!(
            "{triangles} triangles need about {:.1} GB ({} MB and {BYTES_PER_TRIANGLE} bytes a triangle: the triangles, their ray-casting BVH and a frame), and {what} leaves {:.1} GB",
            need as f64 / 1e9,
            BASE_BYTES >> 20,
            have as f64 / 1e9
        )),
        _ => Ok(()),
    }
}

/// [`check_with`] against what this process has ([`available`]).
pub fn check(triangles: usize) -> Result<(), String> {
    if needed(triangles) < CHECKED_FROM_BYTES {
        return Ok(());
    }
    check_with(triangles, available())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_is_refused_only_where_its_need_passes_what_is_available() {
        // small scenes are never checked, whatever is available
        assert_eq!(check_with(1000, Some((0, "nothing"))), Ok(()));
        // 2^24 triangles need about 8.9 GB
        let big = 1 << 24;
        assert_eq!(needed(big), (256 << 20) + 512 * (1 << 24));
        let e = check_with(big, Some((4 << 30, "the address-space limit (ulimit -v)"))).unwrap_err();
        assert!(
            e.contains("16777216 triangles need about 8.9 GB") && e.contains("ulimit -v) leaves 4.3 GB"),
            "{e}"
        );
        assert_eq!(check_with(big, Some((16 << 30, "x"))), Ok(()));
        assert_eq!(check_with(big, None), Ok(()));
        // this machine reads at least the system's available memory
        if cfg!(target_os = "linux") {
            assert!(available().is_some());
        }
    }
}
