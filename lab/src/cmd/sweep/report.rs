//! What a sweep writes, unsharded or merged from shards: `sweep.csv`, `sweep.md` and the
//! Pareto charts (error against time, error against memory), from its rows. Each chart is
//! drawn twice, against either metric: the RMS error of the sweep's pixel set
//! (`pareto-SCENE-WHAT.*`) and FLIP over the facing pixels (`pareto-SCENE-WHAT-flip.*`);
//! how a chart is drawn (labels, legend, ticks, error bars) is [`super::chart`]'s.

use super::chart::{Chart, Point, chart};

use std::fmt::Write as _;
use std::path::Path;

/// The pixel set and the row (in `sshc-records`, with the shard folder's reading).
pub use sshc_records::sweep::{PixelSet, Row};

/// What a chart's axis says of a pixel set.
trait Describe {
    fn describe(self) -> &'static str;
}

impl Describe for PixelSet {
    fn describe(self) -> &'static str {
        match self {
            PixelSet::Penumbra => "RMS error in penumbra (0..255)",
            PixelSet::ShadowOnGround => "RMS error, shadow on the ground (0..255)",
        }
    }
}

/// What a sweep's outputs say besides their rows.
pub struct Outputs<'a> {
    /// The rows, in the order of the sweep's configurations (CPU baselines last).
    pub rows: &'a [Row],
    /// Scene entries (a chart per scene entry with GPU rows), named by [`stem`].
    pub scenes: &'a [String],
    /// The reference technique's file as the sweep file names it.
    pub reference: &'a str,
    pub pixels: PixelSet,
}

/// A name for a technique or scene entry: the file stem, `STEM light K` for `PATH#k`.
pub fn stem(p: &str) -> String {
    let (path, light) = split_entry(p);
    let s = Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().trim_end_matches(".graph").to_string())
        .unwrap_or_else(|| path.to_string());
    match light {
        Some(k) => format!("{s} light {k}"),
        None => s,
    }
}

/// A scene entry `PATH` or `PATH#k` (light k alone): the path and the light.
pub fn split_entry(entry: &str) -> (&str, Option<usize>) {
    match entry.rsplit_once('#') {
        Some((path, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => (path, k.parse().ok()),
        _ => (entry, None),
    }
}

/// A device (in full, and its adapter's name) with the shards `(i, n)` that ran on it.
pub type DeviceShards<'a> = (&'a (String, String), Vec<(usize, usize)>);

/// The devices of `rows`, each with the shards that ran on it, in order of first use.
pub fn devices(rows: &[Row]) -> Vec<DeviceShards<'_>> {
    let mut out: Vec<DeviceShards> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|(d, _)| *d == &r.device) {
            Some((_, shards)) => {
                if !shards.contains(&r.shard) {
                    shards.push(r.shard);
                }
            }
            None => out.push((&r.device, vec![r.shard])),
        }
    }
    for (_, shards) in &mut out {
        shards.sort_unstable();
    }
    out
}

/// Writes `sweep.csv`, `sweep.md` and the charts into `out`, naming each file written.
pub fn write(out: &Path, o: &Outputs) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("error: {}: {e}", out.display()))?;
    let write = |name: &str, text: &str| -> Result<(), String> {
        let p = out.join(name);
        crate::session::write_new(&p, text)?;
        println!("wrote {}", p.display());
        Ok(())
    };
    write("sweep.csv", &csv(o.rows))?;
    write("sweep.md", &markdown(o.rows, o.reference, o.pixels))?;
    let devices = devices(o.rows);
    let short: Vec<&str> = devices.iter().map(|(d, _)| d.1.as_str()).collect();
    let short = short.join(" + ");
    for scene in o.scenes.iter().map(|s| stem(s)) {
        let these: Vec<&Row> = o.rows.iter().filter(|r| r.scene == scene).collect();
        if these.iter().all(|r| r.ms.is_none()) {
            continue;
        }
        for (what, x_of, x_label) in [
            (
                "time",
                ((|r: &Row| r.ratio()) as XAxis, time_spread as Spread),
                "GPU time per frame / reference technique's (log)",
            ),
            (
                "memory",
                (
                    |r: &Row| (r.ms.is_some()).then_some(r.peak_bytes as f64 / (1 << 20) as f64),
                    (|_: &Row| None) as Spread,
                ),
                "peak memory (MiB, log)",
            ),
        ] {
            let set = match o.pixels {
                PixelSet::Penumbra => "penumbra",
                PixelSet::ShadowOnGround => "shadow-on-ground",
            };
            let pixels = o.pixels;
            let rms = move |r: &Row| pixels.rms(r);
            let flip = |r: &Row| r.acc.flip.unwrap_or(f64::NAN);
            let metrics: [(&str, YAxis, String); 2] = [
                ("", (&rms, o.pixels.describe()), format!("RMS {set} error")),
                ("-flip", (&flip, "mean FLIP facing the light (0..1)"), "FLIP".to_string()),
            ];
            for (suffix, (y_of, y_label), metric) in metrics {
                for ext in ["svg", "png"] {
                    let p = out.join(chart_file(&scene, what, suffix, ext));
                    pareto(
                        &p,
                        &these,
                        x_of,
                        x_label,
                        (y_of, y_label),
                        &format!("{scene}: {metric} vs {what} on {short}"),
                    )?;
                    println!("wrote {}", p.display());
                }
            }
        }
    }
    Ok(())
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map(|x| format!("{x:.digits$}")).unwrap_or_default()
}

/// The CSV: a row per configuration, every figure a row has, with its shard and device.
fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "shard,device,scene,technique,config,shadow_map,light_scale,gpu_ms,reference_ms,time_ratio,peak_bytes,fetches,ops,rms_facing,max_facing,rms_penumbra,max_penumbra,facing_pixels,penumbra_pixels,truth_max_se,rms_ground,max_ground,ground_pixels,flip,gpu_ms_min,gpu_ms_max\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{}/{},\"{}\",{},{},\"{}\",{},{},{},{},{},{},{:.0},{:.0},{:.3},{:.3},{:.3},{:.3},{},{},{:.5},{},{},{},{},{},{}",
            r.shard.0,
            r.shard.1,
            r.device.0,
            r.scene,
            r.label,
            r.config,
            r.shadow_map,
            r.light_scale,
            opt(r.ms, 4),
            opt(r.reference_ms, 4),
            opt(r.ratio(), 4),
            r.peak_bytes,
            r.fetches,
            r.ops,
            r.acc.facing.rms,
            r.acc.facing.max,
            r.acc.penumbra.rms,
            r.acc.penumbra.max,
            r.acc.facing.pixels,
            r.acc.penumbra.pixels,
            r.truth_se,
            opt(r.acc.ground.map(|g| g.rms), 3),
            opt(r.acc.ground.map(|g| g.max), 3),
            r.acc.ground.map(|g| g.pixels.to_string()).unwrap_or_default(),
            opt(r.acc.flip, 5),
            opt(r.ms_range.map(|m| m.0), 4),
            opt(r.ms_range.map(|m| m.1), 4),
        );
    }
    s
}

/// The Markdown table per scene. Rows of several devices (a merge of shards that ran on
/// different GPUs) are said to be so, with a device column: each row's time ratio is
/// against the reference timed by its own shard, on its own device.
fn markdown(rows: &[Row], reference: &str, pixels: PixelSet) -> String {
    let devices = devices(rows);
    let mixed = devices.len() > 1;
    let device_line = match devices.as_slice() {
        [] => "Device: none".to_string(),
        [(d, _)] => format!("Device: {}", d.0),
        several => {
            let each: Vec<String> = several
                .iter()
                .map(|(d, shards)| {
                    let s: Vec<String> = shards.iter().map(|(i, n)| format!("{i}/{n}")).collect();
                    format!("{} (shards {})", d.0, s.join(", "))
                })
                .collect();
            format!(
                "Devices: {}. Time ratios are per device: each row's is against `{reference}` timed by its own shard on its own device",
                each.join("; ")
            )
        }
    };
    let mut s = format!(
        "{device_line}. Errors in 0..255 units against the ground truth (RMS over pixels facing the light, and over penumbra pixels{}); time as a ratio to `{reference}` timed in the same run (median of repeated frames).\n\n",
        match pixels {
            PixelSet::Penumbra => "",
            PixelSet::ShadowOnGround => ", first over Lawlor's shadow on the ground plane",
        }
    );
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let _ = writeln!(s, "### {scene}\n");
        let ground = pixels == PixelSet::ShadowOnGround;
        s.push_str("| technique | config | ");
        if ground {
            s.push_str("RMS shadow on ground | ");
        }
        s.push_str("RMS facing | RMS penumbra | max penumbra | FLIP | time ratio | GPU ms | peak MiB | fetches/frame | ops/frame |");
        if mixed {
            s.push_str(" device |");
        }
        s.push_str("\n|---|---|---|---|---|---|---|---|---|---|---|");
        if ground {
            s.push_str("---|");
        }
        if mixed {
            s.push_str("---|");
        }
        s.push('\n');
        for r in rows.iter().filter(|r| r.scene == scene) {
            let first = if ground {
                format!(" {} |", opt(r.acc.ground.map(|g| g.rms), 2))
            } else {
                String::new()
            };
            let last = if mixed { format!(" {} |", r.device.1) } else { String::new() };
            let _ = writeln!(
                s,
                "| {} | {} |{first} {:.2} | {:.2} | {:.1} | {} | {} | {} | {:.2} | {:.3e} | {:.3e} |{last}",
                r.label,
                r.config,
                r.acc.facing.rms,
                r.acc.penumbra.rms,
                r.acc.penumbra.max,
                opt(r.acc.flip, 4),
                opt(r.ratio(), 2),
                opt(r.ms, 2),
                r.peak_bytes as f64 / (1 << 20) as f64,
                r.fetches,
                r.ops
            );
        }
        s.push('\n');
    }
    s
}

/// A chart's file name: `pareto-SCENE-WHAT[-flip].EXT`, the scene's row name with its
/// spaces as `-` (a scene of several lights has a row per light, `three-lights light 0`).
fn chart_file(scene: &str, what: &str, suffix: &str, ext: &str) -> String {
    format!("pareto-{}-{what}{suffix}.{ext}", scene.replace(' ', "-"))
}

/// What the time charts' error bars span ([`time_spread`]).
pub const TIME_SPREAD: &str =
    "error bars: fastest to slowest of the configuration's timed frames (the point: their median), over the reference's median";

/// A row's time ratio's spread: its fastest and slowest frames over the reference's median
/// (the reference's own spread is not in it).
fn time_spread(r: &Row) -> Option<(f64, f64)> {
    let (lo, hi) = r.ms_range?;
    let reference = r.reference_ms?;
    Some((lo / reference, hi / reference))
}

/// The error of a row a chart ranks by, and its axis label.
type YAxis<'a> = (&'a dyn Fn(&Row) -> f64, &'a str);

/// A row's cost on a chart's x axis.
type XAxis = fn(&Row) -> Option<f64>;
/// A row's spread on a chart's x axis (none on the memory charts).
type Spread = fn(&Row) -> Option<(f64, f64)>;

fn pareto(
    path: &Path,
    rows: &[&Row],
    (x_of, spread_of): (XAxis, Spread),
    x_label: &str,
    (y_of, y_label): YAxis,
    title: &str,
) -> Result<(), String> {
    let pts: Vec<Point> = rows
        .iter()
        .filter_map(|r| {
            Some(Point {
                technique: r.label.clone(),
                config: r.config.clone(),
                x: x_of(r)?,
                y: y_of(r),
                spread: spread_of(r),
            })
        })
        .filter(|p| p.x.is_finite() && p.y.is_finite() && p.x > 0.0)
        .collect();
    chart(
        path,
        &pts,
        &Chart {
            title,
            x_label,
            y_label,
            spread: TIME_SPREAD,
            mark: None,
        },
    )
    .map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chart_files_have_no_spaces() {
        assert_eq!(
            chart_file("three-lights light 0", "time", "-flip", "svg"),
            "pareto-three-lights-light-0-time-flip.svg"
        );
        assert_eq!(chart_file("bunny", "memory", "", "png"), "pareto-bunny-memory.png");
    }
}
