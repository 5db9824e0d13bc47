//! One selectable variant of a bundled technique, compiled by sshc and described to the
//! hand-written references alike: shared by the agreement tests and the agreement timings
//! (benches/agreement_timings.rs).

use super::{QueryPlane, technique_source};
use sshc_tests::reference::{LightFrame, Storage};

/// The Bool params of the bundled techniques, given to a variant as 1 or 0.
const BOOL_PARAMS: [&str; 2] = ["subdivide", "quantise"];

/// One selectable variant of a technique: params (`--set`) and the precision of its
/// stored channel or expansion (`--precision`).
#[derive(Clone)]
pub struct Variant {
    pub technique: &'static str,
    pub params: Vec<(&'static str, f64)>,
    pub storage: Option<Storage>,
    /// The width of the square area light over the query plane (world units; the plane is
    /// 2 wide), for the soft techniques.
    pub light: Option<f64>,
    /// The schedule of every Map, Filter and Mipmap pass (`--schedule *=...`), else the default.
    pub schedule: Option<&'static str>,
}

impl Variant {
    pub fn new(technique: &'static str, params: &[(&'static str, f64)], storage: Option<Storage>) -> Variant {
        Variant {
            technique,
            params: params.to_vec(),
            storage,
            light: None,
            schedule: None,
        }
    }

    /// With every Map, Filter and Mipmap pass under `schedule` (`compute`).
    pub fn scheduled(mut self, schedule: &'static str) -> Variant {
        self.schedule = Some(schedule);
        self
    }

    /// Under a square light `width` wide.
    pub fn lit(mut self, width: f64) -> Variant {
        self.light = Some(width);
        self
    }

    pub fn inputs(&self, plane: &QueryPlane) -> sshc_runtime::gpu::SceneInputs {
        match self.light {
            Some(w) => plane.lit_inputs(w as f32),
            None => plane.inputs(),
        }
    }

    pub fn label(&self) -> String {
        let mut s = self.technique.to_string();
        for (k, v) in &self.params {
            s.push_str(&format!(" {k}={v}"));
        }
        if let Some(p) = self.storage {
            s.push_str(&format!(" {p:?}"));
        }
        if let Some(w) = self.light {
            s.push_str(&format!(" light {w}"));
        }
        if let Some(sch) = self.schedule {
            s.push_str(&format!(" schedule {sch}"));
        }
        s
    }

    /// The channels or expansions the storage override applies to, as the compiler names them.
    pub fn stored_names(&self) -> &'static [&'static str] {
        match self.technique {
            "vsm" => &["m1", "m2"],
            "esm" => &["e"],
            "evsm" => &["p1", "p2", "n1", "n2"],
            "msm" => &["b1", "b2", "b3", "b4"],
            "csm" => &["f"],
            _ => &[],
        }
    }

    pub fn compiled(&self) -> sshc::Compiled {
        // slope-scaled bias needs screen-space derivatives the references do not model
        let mut set: Vec<(&str, String)> = vec![("slope_bias", "0.0".into())];
        for (k, v) in &self.params {
            // integral values as integers: i32 params refuse `3.0`, f32 params take `3`;
            // the Bool params (VSSM's `subdivide`, MSSM's `quantise`) as `true` / `false`
            set.push((
                k,
                if BOOL_PARAMS.contains(k) {
                    format!("{}", *v != 0.0)
                } else if v.fract() == 0.0 {
                    format!("{}", *v as i64)
                } else {
                    format!("{v:?}")
                },
            ));
        }
        let precision: Vec<(&str, &str)> = match self.storage {
            Some(p) => {
                let name = match p {
                    Storage::Unorm8 => "Unorm8",
                    Storage::Unorm16 => "Unorm16",
                    Storage::F16 => "F16",
                    Storage::F32 => "F32",
                };
                self.stored_names().iter().map(|c| (*c, name)).collect()
            }
            None => vec![],
        };
        let src = technique_source(self.technique);
        let opts = sshc::CompileOptions {
            set: set.iter().map(|(a, b)| (a.to_string(), b.clone())).collect(),
            precision: precision.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect(),
            schedule: self.schedule.iter().map(|s| ("*".to_string(), s.to_string())).collect(),
            ..Default::default()
        };
        sshc::compile_str(&src, &opts).unwrap_or_else(|d| panic!("{}", d.render(self.technique, &src)))
    }

    pub fn reference(&self) -> sshc_tests::reference::Technique {
        let mut t = sshc_tests::reference::Technique::new(self.technique).with("slope_bias", 0.0);
        for (k, v) in &self.params {
            t = t.with(k, *v);
        }
        t.storage = self.storage;
        match self.light {
            Some(w) => t.lit(LightFrame::query_plane(w)),
            None => t,
        }
    }
}
