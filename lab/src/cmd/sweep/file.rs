//! The sweep file (RON) read and checked ([`load`]): its scenes (a scene of several
//! lights an entry per light), reference, techniques with their axes, CPU baselines and
//! pixel set, and every file it pulls in hashed; its configurations ([`configs`]: a
//! technique with one value on each of its axes, on one scene) and what a configuration's
//! axis values set ([`Settings`]).

use crate::cmd::sweep::report::{PixelSet, split_entry, stem};
use crate::cmd::sweep::shard;
use crate::scene::Light;
use crate::session::{load_scene, read};
use indexmap::IndexMap;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The sweep file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SweepFile {
    /// Scene files, relative to the sweep file.
    pub(super) scenes: Vec<String>,
    /// Camera size for every scene (default: each scene's own).
    #[serde(default)]
    camera: Option<(u32, u32)>,
    /// Frames timed per configuration (after one untimed frame that builds pipelines).
    #[serde(default = "default_frames")]
    pub(super) frames: usize,
    /// The technique every shard times on each scene: time ratios are against it.
    pub(super) reference: String,
    pub(super) techniques: Vec<Entry>,
    /// CPU ray-traced baselines: this many light samples per pixel, one run (Lawlor's
    /// "16 samples" row). Not timed on the GPU.
    #[serde(default)]
    pub(super) stochastic: Vec<u32>,
    /// The pixel set of the charts' error axis and the Markdown table's first error
    /// column: `Penumbra` (default: facing pixels with 0 < truth < 1) or `ShadowOnGround`
    /// (Lawlor 2006's "shadow on the ground plane", `metrics::shadow_on_ground`; every
    /// scene needs an object with `casts: false`). The CSV has every set's figures.
    #[serde(default)]
    pub(super) pixels: PixelSet,
}

fn default_frames() -> usize {
    5
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Entry {
    /// Technique file, relative to the sweep file.
    pub(super) file: String,
    /// Name in tables and charts (default: the file stem).
    #[serde(default)]
    label: Option<String>,
    /// Axes: `shadow_map` (texels), `light_scale` (multiplies the light's size),
    /// `cascades` (1 to 4 cascades of a light at infinity), `precision:NAME` (a precision
    /// name) or a param name (a `--set` value).
    #[serde(default)]
    axes: IndexMap<String, Vec<ron::Value>>,
}

/// One configuration: a technique with one value on each of its axes, on one scene.
#[derive(Clone, Debug)]
pub(crate) struct Config {
    pub(crate) scene: usize,
    pub(crate) technique: usize,
    pub(crate) label: String,
    /// `name=value` on each axis, in the file's order.
    pub(crate) values: Vec<(String, String)>,
}

impl Config {
    pub(super) fn describe(&self) -> String {
        self.values.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")
    }
}

fn value_text(v: &ron::Value) -> String {
    match v {
        ron::Value::String(s) => s.clone(),
        ron::Value::Number(n) => {
            let x = n.into_f64();
            if x.fract() == 0.0 && x.abs() < 1e15 {
                format!("{}", x as i64)
            } else {
                format!("{x}")
            }
        }
        ron::Value::Bool(b) => b.to_string(),
        other => ron::to_string(other).unwrap_or_default(),
    }
}

pub(super) fn configs(file: &SweepFile) -> Vec<Config> {
    let mut out = Vec::new();
    for scene in 0..file.scenes.len() {
        for (ti, t) in file.techniques.iter().enumerate() {
            let label = t.label.clone().unwrap_or_else(|| stem(&t.file));
            let mut combos: Vec<Vec<(String, String)>> = vec![vec![]];
            for (axis, values) in &t.axes {
                combos = combos
                    .into_iter()
                    .flat_map(|c| {
                        values.iter().map(move |v| {
                            let mut c = c.clone();
                            c.push((axis.clone(), value_text(v)));
                            c
                        })
                    })
                    .collect();
            }
            for values in combos {
                out.push(Config {
                    scene,
                    technique: ti,
                    label: label.clone(),
                    values,
                });
            }
        }
    }
    out
}

/// What one configuration's axis values set.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Settings {
    /// The `shadow_map` axis (else the scene's own).
    pub(crate) shadow_map: Option<u32>,
    /// The `light_scale` axis (else 1).
    pub(crate) light_scale: f64,
    /// The `cascades` axis (else `--cascades` or the scene file's).
    pub(crate) cascades: Option<u32>,
    /// Params, compiled in as `--set` values: each configuration compiles its technique
    /// afresh, so a fixed param (an I32 `N` of light samples) takes its value there, and
    /// the binding reads the sample count from the compiled graph
    /// ([`crate::bind::scene_inputs_for`]).
    pub(crate) set: Vec<(String, String)>,
    /// `precision:NAME` axes.
    pub(crate) precision: Vec<(String, String)>,
    /// `schedule:PASS` axes (`schedule:*`: every Map, Filter and Mipmap pass).
    pub(crate) schedule: Vec<(String, String)>,
}

pub(crate) fn settings(c: &Config) -> Result<Settings, String> {
    let mut out = Settings {
        shadow_map: None,
        light_scale: 1.0,
        cascades: None,
        set: Vec::new(),
        precision: Vec::new(),
        schedule: Vec::new(),
    };
    for (k, v) in &c.values {
        match k.as_str() {
            "shadow_map" => out.shadow_map = Some(v.parse().map_err(|_| format!("error: shadow_map = `{v}` is not a whole number"))?),
            "light_scale" => out.light_scale = v.parse().map_err(|_| format!("error: light_scale = `{v}` is not a number"))?,
            "cascades" => out.cascades = Some(v.parse().map_err(|_| format!("error: cascades = `{v}` is not a whole number"))?),
            k if k.starts_with("precision:") => out.precision.push((k["precision:".len()..].to_string(), v.clone())),
            k if k.starts_with("schedule:") => out.schedule.push((k["schedule:".len()..].to_string(), v.clone())),
            k => out.set.push((k.to_string(), v.clone())),
        }
    }
    Ok(out)
}

/// Scale a light's extent (radius, half-extents, segment length about its midpoint,
/// triangle about its centroid, angular diameter).
fn scale_light(l: &mut Light, f: f32) {
    *l = l.scaled(f);
}

impl Settings {
    /// The axes that change the scene: the shadow map and the light's size; the precision
    /// budget checked again for them.
    pub(crate) fn apply(&self, scene: &mut crate::scene::Scene) -> Result<(), String> {
        if let Some(n) = self.shadow_map {
            scene.shadow_map = n;
        }
        if let Some(l) = scene.lights.first_mut() {
            scale_light(l, self.light_scale as f32);
        }
        scene.check_precision().map_err(|e| e.to_string())
    }
}

/// The most light samples per pixel of a `stochastic` baseline: 2^36 light samples
/// (`session::MAX_TRUTH_SAMPLES`) over a camera of up to 4096 x 4096 pixels.
pub const MAX_STOCHASTIC_SAMPLES: u32 = 4096;

/// Refuses empty axes, a `shadow_map` value below 1 texel or not whole, a `light_scale`
/// that is not finite or is negative, and a `stochastic` count above
/// [`MAX_STOCHASTIC_SAMPLES`], naming the technique and the axis.
fn check_axes(file: &SweepFile) -> Result<(), String> {
    for (i, t) in file.techniques.iter().enumerate() {
        let name = t.label.clone().unwrap_or_else(|| t.file.clone());
        for (axis, values) in &t.axes {
            let at = format!("techniques[{i}] (`{name}`), axis `{axis}`");
            if values.is_empty() {
                return Err(format!(
                    "{at}: the list of values is empty, so the sweep would run nothing; give at least one value"
                ));
            }
            for v in values {
                let x = match v {
                    ron::Value::Number(n) => Some(n.into_f64()),
                    _ => None,
                };
                match axis.as_str() {
                    "shadow_map" => match x {
                        Some(x) if x.fract() == 0.0 && x >= 1.0 && x <= f64::from(u32::MAX) => {}
                        _ => {
                            return Err(format!(
                                "{at}: `{}`: the shadow map needs a whole number of at least 1 texel",
                                value_text(v)
                            ));
                        }
                    },
                    "cascades" => match x {
                        Some(x) if x.fract() == 0.0 && (1.0..=f64::from(sshc_runtime::light::MAX_CASCADES)).contains(&x) => {}
                        _ => {
                            return Err(format!(
                                "{at}: `{}`: a light has 1 to {} cascades",
                                value_text(v),
                                sshc_runtime::light::MAX_CASCADES
                            ));
                        }
                    },
                    "light_scale" => match x {
                        Some(x) if x.is_finite() && x >= 0.0 => {}
                        _ => {
                            return Err(format!("{at}: `{}`: a light scale must be a finite number >= 0", value_text(v)));
                        }
                    },
                    _ => {}
                }
            }
        }
    }
    // the grid's size, before `configs` builds it: a few long axes multiply past memory
    let per_scene = file.techniques.iter().try_fold(0usize, |sum, t| {
        t.axes
            .values()
            .try_fold(1usize, |p, v| p.checked_mul(v.len()))
            .and_then(|p| sum.checked_add(p))
    });
    let rows = per_scene
        .and_then(|p| p.checked_mul(file.scenes.len()))
        .and_then(|c| c.checked_add(file.scenes.len().checked_mul(file.stochastic.len())?));
    if rows.is_none_or(|r| r > shard::MAX_ROWS) {
        return Err(format!(
            "the grid has {} configurations and baselines over its {} scenes; a sweep has at most {} (split it into several sweeps, or use `sshc tune` to search a large space)",
            rows.map_or_else(|| "more than 2^64".to_string(), |r| r.to_string()),
            file.scenes.len(),
            shard::MAX_ROWS
        ));
    }
    for (k, &n) in file.stochastic.iter().enumerate() {
        if n == 0 || n > MAX_STOCHASTIC_SAMPLES {
            return Err(format!(
                "stochastic[{k}] = {n} light samples per pixel is outside 1..={MAX_STOCHASTIC_SAMPLES} (the budget is 2^36 light samples over up to 4096x4096 pixels)"
            ));
        }
    }
    Ok(())
}

/// A sweep file read and checked, with its scenes as entries (`PATH#k` for each light of a
/// scene of several) and the files it pulls in.
pub(super) struct Loaded {
    pub(super) path: PathBuf,
    pub(super) file: SweepFile,
    base: PathBuf,
    /// The sweep file, the reference, the techniques, the scene files and the meshes they
    /// load, each with the hash of its bytes.
    pub(super) inputs: Vec<(String, String)>,
}

impl Loaded {
    pub(super) fn resolve(&self, p: &str) -> PathBuf {
        self.base.join(p)
    }

    /// An entry's scene: the file, with light k alone for `PATH#k`.
    pub(super) fn scene(&self, entry: &str) -> Result<crate::scene::Scene, String> {
        let (path, light) = split_entry(entry);
        let scene = load_scene(&self.resolve(path), self.file.camera, None)?;
        Ok(match light {
            Some(k) if k < scene.lights.len() => crate::session::single_light(&scene, k),
            _ => scene,
        })
    }
}

pub(super) fn load(path: &Path) -> Result<Loaded, String> {
    if path == Path::new("merge") && !path.exists() {
        return Err(
            "error: cannot read the sweep file `merge`: the merge is `sshc sweep merge DIR... -o OUT`, the word `merge` before any option (a sweep file named merge is `./merge`)"
                .into(),
        );
    }
    let text = read(path)?;
    let file: SweepFile =
        ron::from_str(&text).map_err(|e| format!("error: {}:{}:{}: {}", path.display(), e.span.start.line, e.span.start.col, e.code))?;
    if file.scenes.is_empty() || (file.techniques.is_empty() && file.stochastic.is_empty()) {
        return Err(format!("error: {}: a sweep needs scenes and techniques", path.display()));
    }
    check_axes(&file).map_err(|e| format!("error: {}: {e}", path.display()))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut inputs = vec![(
        path.file_name()
            .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned()),
        shard::hash_file(path)?,
    )];
    for t in std::iter::once(&file.reference).chain(file.techniques.iter().map(|t| &t.file)) {
        if !inputs.iter().any(|(n, _)| n == t) {
            inputs.push((t.clone(), shard::hash_file(&base.join(t))?));
        }
    }
    // Several lights: a scene of n lights becomes n entries `PATH#k`, each that
    // light alone (its own truth, metrics and rows).
    let mut file = file;
    let mut entries = Vec::new();
    for path in &file.scenes {
        let scene = load_scene(&base.join(path), file.camera, None)?;
        if !inputs.iter().any(|(n, _)| n == path) {
            inputs.push((path.clone(), shard::hash_file(&base.join(path))?));
        }
        for mesh in scene.files() {
            let name = mesh.strip_prefix(&base).unwrap_or(mesh).display().to_string();
            if !inputs.iter().any(|(n, _)| *n == name) {
                inputs.push((name, shard::hash_file(mesh)?));
            }
        }
        if scene.lights.len() > 1 {
            entries.extend((0..scene.lights.len()).map(|k| format!("{path}#{k}")));
        } else {
            entries.push(path.clone());
        }
    }
    file.scenes = entries;
    let loaded = Loaded {
        path: path.to_path_buf(),
        file,
        base,
        inputs,
    };
    if loaded.file.pixels == PixelSet::ShadowOnGround {
        for entry in &loaded.file.scenes {
            let scene = loaded.scene(entry)?;
            if (0..scene.objects().len()).all(|i| scene.casts(i)) {
                return Err(format!(
                    "error: {}: `pixels: ShadowOnGround` needs a ground that casts no shadow, but every object of `{entry}` casts; mark the ground `casts: false` or write `pixels: Penumbra`",
                    path.display()
                ));
            }
        }
    }
    Ok(loaded)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cmd::sweep::measure::compile;

    #[test]
    fn bad_axes_and_huge_stochastic_counts_are_refused_with_the_axis_named() {
        let file = |axes: &str, stochastic: &str| -> SweepFile {
            ron::from_str(&format!(
                r#"(scenes: ["a.ron"], reference: "h.ron", stochastic: [{stochastic}], techniques: [(file: "p.ron", axes: {{ {axes} }})])"#
            ))
            .unwrap()
        };
        assert_eq!(check_axes(&file(r#""shadow_map": [16], "light_scale": [0.5, 2.0]"#, "16")), Ok(()));
        for (axes, want) in [
            (
                r#""light_scale": [NaN]"#,
                "axis `light_scale`: `NaN`: a light scale must be a finite number >= 0",
            ),
            (
                r#""light_scale": [-1.0]"#,
                "axis `light_scale`: `-1`: a light scale must be a finite number >= 0",
            ),
            (r#""cascades": [5]"#, "axis `cascades`: `5`: a light has 1 to 4 cascades"),
            (r#""cascades": [1.5]"#, "axis `cascades`: `1.5`: a light has 1 to 4 cascades"),
            (
                r#""shadow_map": [0]"#,
                "axis `shadow_map`: `0`: the shadow map needs a whole number of at least 1 texel",
            ),
            (r#""r": []"#, "axis `r`: the list of values is empty"),
        ] {
            let e = check_axes(&file(axes, "")).unwrap_err();
            assert!(e.contains("techniques[0] (`p.ron`)") && e.contains(want), "{axes}: {e}");
            assert!(!e.contains("device"), "{e}");
        }
        let e = check_axes(&file("", "4294967295")).unwrap_err();
        assert!(e.contains("stochastic[0] = 4294967295") && e.contains("1..=4096"), "{e}");
        // a grid past what a sweep holds is refused before it is built: five axes of 100
        // values (10^10 configurations), and twelve (a product past 2^64)
        let axis = format!("[{}]", (0..100).map(|v| v.to_string()).collect::<Vec<_>>().join(", "));
        for (k, want) in [(5, "10000000000 configurations"), (12, "more than 2^64 configurations")] {
            let axes: Vec<String> = (0..k).map(|i| format!(r#""a{i}": {axis}"#)).collect();
            let e = check_axes(&file(&axes.join(", "), "")).unwrap_err();
            assert!(e.contains(want) && e.contains("at most 1048576"), "{e}");
        }
        assert!(shard("0/65537").unwrap_err().contains("at most 65536 shards"));
    }

    #[test]
    fn axes_multiply_per_technique_and_scene() {
        let f: SweepFile = ron::from_str(
            r#"(scenes: ["a.ron", "b.ron"], reference: "h.ron", techniques: [
                (file: "p.ron", axes: { "shadow_map": [16, 32], "r": [1, 2, 3] }),
                (file: "c.ron", label: Some("csm"), axes: { "precision:f": ["Unorm8", "F16"] }),
            ])"#,
        )
        .unwrap();
        let c = configs(&f);
        assert_eq!(c.len(), 2 * (2 * 3 + 2));
        assert_eq!(c[0].describe(), "shadow_map=16 r=1");
        assert_eq!(c[6].label, "csm");
        assert_eq!(c[6].describe(), "precision:f=Unorm8");
        assert_eq!(shard("1/3"), Ok((1, 3)));
        assert!(shard("3/3").is_err());
    }

    /// sweeps/linear.ron: a fixed I32 param axis (`N`, light samples) gives one
    /// configuration per value, each compiling its technique with that value (`--set`),
    /// which a fixed param takes at compile time: the compiled graph's param holds it, and
    /// the binding reads the sample count from the graph.
    #[test]
    fn schedule_and_precision_axes_become_compile_options() {
        let c = Config {
            scene: 0,
            technique: 0,
            label: "vsm".into(),
            values: vec![
                ("schedule:*".into(), "compute".into()),
                ("precision:m1,m2".into(), "F16".into()),
                ("shadow_map".into(), "64".into()),
            ],
        };
        let s = settings(&c).unwrap();
        assert_eq!(s.schedule, [("*".to_string(), "compute".to_string())]);
        assert_eq!(s.precision, [("m1,m2".to_string(), "F16".to_string())]);
        assert_eq!((s.shadow_map, s.set.len()), (Some(64), 0));
    }

    #[test]
    fn a_fixed_param_axis_recompiles_each_value() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let f: SweepFile = ron::from_str(&std::fs::read_to_string(root.join("sweeps/linear.ron")).unwrap()).unwrap();
        assert_eq!(check_axes(&f), Ok(()));
        assert_eq!(f.scenes, ["../scenes/linear.ron"]);
        let c = configs(&f);
        let got: Vec<(String, Settings)> = c.iter().map(|c| (c.label.clone(), settings(c).unwrap())).collect();
        let want = |label: &str, n: &str| {
            (
                label.to_string(),
                Settings {
                    shadow_map: None,
                    light_scale: 1.0,
                    cascades: None,
                    set: vec![("N".to_string(), n.to_string())],
                    precision: vec![],
                    schedule: vec![],
                },
            )
        };
        assert_eq!(
            got,
            [
                want("linear-light", "2"),
                want("linear-light", "3"),
                want("linear-light", "5"),
                want("linear-light", "9"),
                want("point-samples", "2"),
                want("point-samples", "10"),
            ]
        );
        // A bundled technique with a fixed I32 param (PCSS's `N`), compiled per value as
        // the sweep does: the value is compiled in, so each configuration's graph differs.
        let pcss = root.join("techniques/pcss.ron");
        let source = std::fs::read_to_string(&pcss).unwrap();
        for n in ["4", "8"] {
            let g = compile(&pcss, &source, &[("N".to_string(), n.to_string())], &[], &[])
                .unwrap()
                .graph;
            let p = g.params.iter().find(|p| p.name == "N").unwrap();
            assert_eq!((p.value, p.offset), (n.parse::<f64>().unwrap(), None), "N = {n}");
        }
    }
}
