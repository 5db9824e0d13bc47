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
                // a sweep of an older version kept no FLIP (`--redraw` of its CSV)
                if suffix == "-flip" && these.iter().all(|r| r.acc.flip.is_none()) {
                    if what == "time" {
                        println!("no FLIP recorded on {scene}: its FLIP charts are not drawn");
                    }
                    continue;
                }
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

/// The largest `sweep.csv` read back (`--redraw`): as large as the records it was written
/// from may be.
pub const MAX_CSV_BYTES: u64 = sshc_records::sweep::MAX_RECORDS_BYTES;

/// One line of `sweep.csv` as [`csv`] writes it, read back by `sshc sweep --redraw`. The
/// columns added after the first sweeps (the ground, FLIP, the timings' spread) may be
/// absent, so that the CSVs of older runs read too; `time_ratio` is derived, not read.
#[derive(serde::Deserialize)]
struct CsvLine {
    shard: String,
    device: String,
    scene: String,
    technique: String,
    config: String,
    shadow_map: u32,
    light_scale: f64,
    gpu_ms: Option<f64>,
    reference_ms: Option<f64>,
    peak_bytes: u64,
    fetches: f64,
    ops: f64,
    rms_facing: f64,
    max_facing: f64,
    rms_penumbra: f64,
    max_penumbra: f64,
    facing_pixels: usize,
    penumbra_pixels: usize,
    truth_max_se: f64,
    #[serde(default)]
    rms_ground: Option<f64>,
    #[serde(default)]
    max_ground: Option<f64>,
    #[serde(default)]
    ground_pixels: Option<usize>,
    #[serde(default)]
    flip: Option<f64>,
    #[serde(default)]
    gpu_ms_min: Option<f64>,
    #[serde(default)]
    gpu_ms_max: Option<f64>,
}

/// The adapter's name in a device's full description (`NAME (BACKEND, DRIVER INFO)`, the
/// runtime's `Gpu::describe`): what the charts' titles name.
fn adapter_name(full: &str) -> &str {
    ["Vulkan", "Metal", "Dx12", "Gl", "BrowserWebGpu", "Noop"]
        .iter()
        .filter_map(|b| full.rfind(&format!(" ({b}, ")))
        .max()
        .map_or(full, |i| &full[..i])
}

/// The rows of a `sweep.csv` (`path`, for errors) as [`csv`] wrote them: every figure the
/// charts and the table use (the regions' signed means and the non-finite counts, which the
/// CSV does not keep, read as zero). Refuses a line that does not parse or whose numbers
/// are out of their domain, naming its line.
pub fn read_csv(path: &Path, text: &str) -> Result<Vec<Row>, String> {
    let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    let mut rows = Vec::new();
    for (k, line) in reader.deserialize::<CsvLine>().enumerate() {
        // line 1 is the header
        let at = |what: String| format!("error: {}:{}: {what}", path.display(), k + 2);
        let l = line.map_err(|e| at(format!("not a line of a sweep's CSV: {e}")))?;
        let shard = l
            .shard
            .split_once('/')
            .and_then(|(i, n)| Some((i.parse::<usize>().ok()?, n.parse::<usize>().ok()?)))
            .filter(|&(i, n)| i < n && n <= sshc_records::sweep::MAX_SHARDS)
            .ok_or_else(|| at(format!("shard `{}` is not i/n with i < n", l.shard)))?;
        let times = [l.gpu_ms, l.reference_ms, l.gpu_ms_min, l.gpu_ms_max];
        let figures = [
            l.light_scale,
            l.fetches,
            l.ops,
            l.rms_facing,
            l.max_facing,
            l.rms_penumbra,
            l.max_penumbra,
            l.truth_max_se,
        ];
        if times
            .iter()
            .flatten()
            .chain(&figures)
            .chain(l.rms_ground.iter())
            .chain(l.max_ground.iter())
            .chain(l.flip.iter())
            .any(|x| !x.is_finite() || *x < 0.0)
        {
            return Err(at("a time or a figure is negative or not a number".into()));
        }
        let stats = |rms, max, pixels| sshc_records::accuracy::ErrorStats {
            rms,
            max,
            pixels,
            ..Default::default()
        };
        let ground = match (l.rms_ground, l.max_ground, l.ground_pixels) {
            (Some(rms), Some(max), Some(pixels)) => Some(stats(rms, max, pixels)),
            (None, None, None) => None,
            _ => return Err(at("the ground's columns are partly empty".into())),
        };
        let ms_range = match (l.gpu_ms_min, l.gpu_ms_max) {
            (Some(a), Some(b)) if a <= b => Some((a, b)),
            (None, None) => None,
            _ => {
                return Err(at(
                    "the timings' spread is partly empty or its fastest is slower than its slowest".into()
                ));
            }
        };
        let short = adapter_name(&l.device).to_string();
        rows.push(Row {
            scene: l.scene,
            label: l.technique,
            config: l.config,
            shadow_map: l.shadow_map,
            light_scale: l.light_scale,
            ms: l.gpu_ms,
            ms_range,
            peak_bytes: l.peak_bytes,
            fetches: l.fetches,
            ops: l.ops,
            acc: sshc_records::accuracy::Accuracy {
                facing: stats(l.rms_facing, l.max_facing, l.facing_pixels),
                penumbra: stats(l.rms_penumbra, l.max_penumbra, l.penumbra_pixels),
                ground,
                flip: l.flip,
                ..Default::default()
            },
            truth_se: l.truth_max_se,
            reference_ms: l.reference_ms,
            shard,
            device: (l.device, short),
        });
    }
    Ok(rows)
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

    fn row(ms: Option<f64>, ground: bool) -> Row {
        let stats = |rms, max, pixels| sshc_records::accuracy::ErrorStats {
            rms,
            max,
            pixels,
            ..Default::default()
        };
        Row {
            scene: "bunny".into(),
            label: "pcss".into(),
            config: "N=3 bias=0.0005".into(),
            shadow_map: 512,
            light_scale: 1.5,
            ms,
            ms_range: ms.map(|m| (m - 0.25, m + 0.5)),
            peak_bytes: 1 << 20,
            fetches: 6553600.0,
            ops: 113377280.0,
            acc: sshc_records::accuracy::Accuracy {
                facing: stats(23.781, 255.0, 49041),
                penumbra: stats(78.081, 254.502, 2407),
                ground: ground.then(|| stats(12.5, 200.25, 900)),
                flip: ms.map(|_| 0.02722),
                ..Default::default()
            },
            truth_se: 0.00907,
            reference_ms: ms.map(|_| 20.0024),
            shard: (1, 3),
            device: (
                "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, llvmpipe Mesa 22.3.6 (LLVM 15.0.6))".into(),
                "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            ),
        }
    }

    /// `--redraw` reads back what a sweep wrote: every figure the charts and the table use,
    /// the device's short name included (figures chosen exact at the CSV's digits).
    #[test]
    fn the_csv_reads_back_the_rows_it_was_written_from() {
        let rows = vec![row(Some(19.9596), false), row(Some(8.5), true), row(None, false)];
        let back = read_csv(Path::new("sweep.csv"), &csv(&rows)).unwrap();
        assert_eq!(back, rows);
        // a CSV of an older sweep: no ground, FLIP or spread columns
        let old = "shard,device,scene,technique,config,shadow_map,light_scale,gpu_ms,reference_ms,time_ratio,peak_bytes,fetches,ops,rms_facing,max_facing,rms_penumbra,max_penumbra,facing_pixels,penumbra_pixels,truth_max_se\n\
            0/1,\"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, llvmpipe Mesa 22.3.6 (LLVM 15.0.6))\",bunny,hard,\"shadow_map=256\",256,1,8.6376,10.5794,0.8165,262144,65536,4390912,21.547,255.000,91.346,254.751,49041,2043,0.00923\n";
        let back = read_csv(Path::new("old.csv"), old).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!((back[0].ms, back[0].ms_range, back[0].acc.flip), (Some(8.6376), None, None));
        assert_eq!(back[0].device.1, "llvmpipe (LLVM 15.0.6, 256 bits)");
    }

    /// A hostile CSV is refused with its file and line, never drawn from.
    #[test]
    fn a_bad_csv_line_is_refused_with_its_line() {
        let good = csv(&[row(Some(8.5), true)]);
        let (head, line) = good.split_once('\n').unwrap();
        for (bad, want) in [
            (line.replacen("1/3", "3/3", 1), "shard `3/3` is not i/n"),
            (line.replacen("8.5000", "-8.5", 1), "negative or not a number"),
            (line.replacen("8.5000", "NaN", 1), "negative or not a number"),
            (line.replacen(",512,", ",big,", 1), "not a line of a sweep's CSV"),
            (line.replacen("12.500", "", 1), "the ground's columns are partly empty"),
            (line.replacen("8.2500", "9.5", 1), "its fastest is slower than its slowest"),
        ] {
            let text = format!("{head}\n{line}{bad}");
            let err = read_csv(Path::new("s.csv"), &text).expect_err(want);
            assert!(err.contains("s.csv:3:") && err.contains(want), "{want}: {err}");
        }
    }

    #[test]
    fn chart_files_have_no_spaces() {
        assert_eq!(
            chart_file("three-lights light 0", "time", "-flip", "svg"),
            "pareto-three-lights-light-0-time-flip.svg"
        );
        assert_eq!(chart_file("bunny", "memory", "", "png"), "pareto-bunny-memory.png");
    }
}
