//! Hand-written reference implementations of the bundled techniques (`techniques/hard.ron`,
//! `pcf.ron`, `vsm.ron`, `esm.ron`, `csm.ron`), written from the papers (Annen 2008,
//! chapters 3, 4, 6 and 7) and the technique files alone, independently of the compiler's
//! code generator, so that tests can check that generated and hand-written results agree.
//!
//! Every pass after the Depth pass (Map, Filter, Mipmap and the Shade lookup) exists twice:
//!
//! - [`cpu_visibility`] ([`cpu`]): the exact math in f64, intermediates kept in f64;
//! - [`GpuReference`] ([`gpu`]): hand-written WGSL compute shaders run on wgpu, storing
//!   every intermediate image at the technique's storage precision (`rgba8unorm`,
//!   `rgba16unorm`, `rgba16float`, `rgba32float`) and sampling filtered lookups with a
//!   linear, clamp-to-edge sampler at the query's explicit level of detail.
//!
//! Conventions (the runtime's): texel `(i, j)` of an `N x N` map has its centre at uv
//! `((i + 0.5) / N, (j + 0.5) / N)`; `nearest` reads the texel containing uv; `fetch(dx, dy)`
//! reads texel `floor(uv N - 0.5) + (dx, dy)` and `tf = fract(uv N - 0.5)`; reads outside the
//! map clamp to the edge; a mip chain halves down to 1 x 1 (`max(1, N >> level)`), each texel
//! the mean of the 2 x 2 texels below it; a value with the known range `[lo, hi]` stored in
//! a unorm format is kept as `(v - lo) / (hi - lo)` unless the range already lies in `[0, 1]`.
//! The receiver's `depth_slope` is taken as 0 (the slope-scaled bias is not modelled), and
//! the visibility is clamped to `[0, 1]` with NaN reading as 1.

pub mod cpu;
pub mod gpu;
pub mod tolerance;

pub use cpu::cpu_visibility;
pub use gpu::GpuReference;

use serde::Deserialize;
use std::collections::BTreeMap;

/// A square shadow map as the Depth pass writes it: linear depth `z` in `[0, 1]`,
/// row-major, row 0 first; texel `(i, j)` has its centre at uv `((i + 0.5) / size, (j + 0.5) / size)`.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthMap {
    pub size: u32,
    pub z: Vec<f32>,
}

/// One receiver: its light-space uv, its normalised depth `d` in `[0, 1]`, and the level of
/// detail at which `sample(...)` filters (used only by mipmapped resources).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    pub uv: [f32; 2],
    pub d: f32,
    pub lod: f32,
}

/// Storage precision of a stored channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Storage {
    Unorm8,
    Unorm16,
    F16,
    F32,
}

impl Storage {
    /// Whether values are kept as unsigned normalised integers (and need a range).
    pub fn is_unorm(self) -> bool {
        matches!(self, Storage::Unorm8 | Storage::Unorm16)
    }
}

/// A technique to evaluate: the name of a bundled technique file, parameter values by the
/// file's names (a missing one takes the file's default), and an optional override of the
/// precision of the stored non-depth channel or expansion (CSM's basis `f`, VSM's moments
/// `m1`/`m2`, ESM's `e`; `None` keeps the file's).
#[derive(Clone, Debug, PartialEq)]
pub struct Technique {
    pub name: String,
    pub params: BTreeMap<String, f64>,
    pub storage: Option<Storage>,
}

impl Technique {
    /// The technique at its file's defaults.
    pub fn new(name: &str) -> Technique {
        Technique {
            name: name.to_string(),
            params: BTreeMap::new(),
            storage: None,
        }
    }

    /// Set one parameter.
    pub fn with(mut self, name: &str, value: f64) -> Technique {
        self.params.insert(name.to_string(), value);
        self
    }

    /// Override the storage precision.
    pub fn stored(mut self, storage: Storage) -> Technique {
        self.storage = Some(storage);
        self
    }
}

/// The five techniques the references implement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Hard,
    Pcf,
    Vsm,
    Esm,
    Csm,
}

impl Kind {
    pub const ALL: [Kind; 5] = [Kind::Hard, Kind::Pcf, Kind::Vsm, Kind::Esm, Kind::Csm];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Hard => "hard",
            Kind::Pcf => "pcf",
            Kind::Vsm => "vsm",
            Kind::Esm => "esm",
            Kind::Csm => "csm",
        }
    }

    fn source(self) -> &'static str {
        match self {
            Kind::Hard => include_str!("../../../techniques/hard.ron"),
            Kind::Pcf => include_str!("../../../techniques/pcf.ron"),
            Kind::Vsm => include_str!("../../../techniques/vsm.ron"),
            Kind::Esm => include_str!("../../../techniques/esm.ron"),
            Kind::Csm => include_str!("../../../techniques/csm.ron"),
        }
    }

    /// The parameters the reference reads, and whether each is an integer.
    fn params(self) -> &'static [(&'static str, bool)] {
        match self {
            Kind::Hard => &[("bias", false), ("slope_bias", false)],
            Kind::Pcf => &[("N", true), ("bias", false), ("slope_bias", false)],
            Kind::Vsm => &[
                ("K", true),
                ("min_variance", false),
                ("bleed", false),
                ("bias", false),
                ("slope_bias", false),
            ],
            Kind::Esm => &[
                ("c", false),
                ("K", true),
                ("classify", true),
                ("eps", false),
                ("zmax_offset", false),
                ("bias", false),
                ("slope_bias", false),
            ],
            Kind::Csm => &[
                ("M", true),
                ("alpha", false),
                ("fix", true),
                ("K", true),
                ("sigma", false),
                ("bias", false),
                ("slope_bias", false),
            ],
        }
    }

    /// The channels or expansions whose precision `Technique::storage` overrides.
    fn stored_names(self) -> &'static [&'static str] {
        match self {
            Kind::Hard | Kind::Pcf => &[],
            Kind::Vsm => &["m1", "m2"],
            Kind::Esm => &["e"],
            Kind::Csm => &["f"],
        }
    }
}

// The parts of a technique file the references read: parameter defaults and ranges, and the
// precisions of channels and expansions. Everything else in the file is ignored.
#[derive(Deserialize)]
#[serde(rename = "Technique")]
struct FileDecl {
    name: String,
    #[serde(default)]
    params: BTreeMap<String, ParamDecl>,
    #[serde(default)]
    channels: BTreeMap<String, ChannelDecl>,
    #[serde(default)]
    expansions: BTreeMap<String, ExpansionDecl>,
}

#[derive(Deserialize)]
#[serde(rename = "Param")]
struct ParamDecl {
    default: f64,
    range: Option<(f64, f64)>,
}

#[derive(Deserialize)]
#[serde(rename = "Channel")]
struct ChannelDecl {
    precision: Storage,
}

#[derive(Deserialize)]
#[serde(rename = "Expansion")]
struct ExpansionDecl {
    precision: Storage,
}

impl<'de> Deserialize<'de> for Storage {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        enum P {
            Unorm8,
            Unorm16,
            F16,
            F32,
        }
        Ok(match P::deserialize(d)? {
            P::Unorm8 => Storage::Unorm8,
            P::Unorm16 => Storage::Unorm16,
            P::F16 => Storage::F16,
            P::F32 => Storage::F32,
        })
    }
}

fn read_file(kind: Kind) -> Result<FileDecl, String> {
    let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let file: FileDecl = options
        .from_str(kind.source())
        .map_err(|e| format!("techniques/{}.ron: {e}", kind.name()))?;
    if file.name != kind.name() {
        return Err(format!("techniques/{}.ron names itself `{}`", kind.name(), file.name));
    }
    Ok(file)
}

/// A technique with every parameter known: the file's defaults overridden by the caller's
/// values, all checked against the file's ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    pub kind: Kind,
    pub params: BTreeMap<String, f64>,
    /// Precision of the stored non-depth channel (F32, the depth's, for hard and PCF).
    pub storage: Storage,
}

impl Resolved {
    /// A parameter the reference reads ([`resolve`] checked that the file declares it).
    pub fn get(&self, name: &str) -> f64 {
        self.params.get(name).copied().unwrap_or(f64::NAN)
    }

    /// An integer parameter.
    pub fn int(&self, name: &str) -> i64 {
        self.get(name) as i64
    }

    /// The channels the Map pass stores at `storage`, in the order the GPU reference packs
    /// them (four per RGBA layer), each with the range of its value for `z` in `[0, 1]`.
    pub fn stored_channels(&self) -> Vec<StoredChannel> {
        let ch = |name: String, lo: f64, hi: f64| StoredChannel { name, lo, hi };
        match self.kind {
            Kind::Hard | Kind::Pcf => Vec::new(),
            // z and z^2 of z in [0, 1]
            Kind::Vsm => vec![ch("m1".into(), 0.0, 1.0), ch("m2".into(), 0.0, 1.0)],
            // exp(c z) of z in [0, 1] (eq. 7.1)
            Kind::Esm => vec![ch("e_t0_k1".into(), 1.0, self.get("c").exp())],
            // sin(c_k z), cos(c_k z) with c_k = pi (2k - 1) (eq. 6.6): sin(pi z) is
            // non-negative on [0, 1]; every other basis sweeps at least a whole period
            // (c_k >= 3 pi for k >= 2, and cos(pi z) goes from 1 to -1), so spans [-1, 1].
            Kind::Csm => (1..=self.int("M"))
                .flat_map(|k| {
                    let sin_lo = if k == 1 { 0.0 } else { -1.0 };
                    [ch(format!("f_t0_k{k}"), sin_lo, 1.0), ch(format!("f_t1_k{k}"), -1.0, 1.0)]
                })
                .collect(),
        }
    }
}

/// A channel stored by a Map pass, and the range of its values.
#[derive(Clone, Debug, PartialEq)]
pub struct StoredChannel {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
}

impl StoredChannel {
    /// `(lo, span)` with `value = stored * span + lo`: the affine encoding of a unorm
    /// channel whose range is not inside `[0, 1]`, the identity otherwise.
    pub fn encoding(&self, storage: Storage) -> (f64, f64) {
        if storage.is_unorm() && !(self.lo >= 0.0 && self.hi <= 1.0) {
            (self.lo, self.hi - self.lo)
        } else {
            (0.0, 1.0)
        }
    }
}

/// Fill in defaults, check names, types and ranges, and check that the chosen precision can
/// hold the stored channel. The CPU and GPU references share this, so they refuse the same
/// techniques with the same message.
pub fn resolve(t: &Technique) -> Result<Resolved, String> {
    let kind = Kind::ALL.into_iter().find(|k| k.name() == t.name).ok_or_else(|| {
        format!(
            "no reference implementation of technique `{}` (there are: hard, pcf, vsm, esm, csm)",
            t.name
        )
    })?;
    let file = read_file(kind)?;
    for (name, _) in kind.params() {
        if !file.params.contains_key(*name) {
            return Err(format!(
                "techniques/{}.ron lacks the parameter `{name}` the reference reads",
                kind.name()
            ));
        }
    }
    let mut params = BTreeMap::new();
    for (name, decl) in &file.params {
        params.insert(name.clone(), decl.default);
    }
    for (name, &value) in &t.params {
        let Some(decl) = file.params.get(name) else {
            let known: Vec<&str> = file.params.keys().map(String::as_str).collect();
            return Err(format!(
                "`{}` has no parameter `{name}` (it has: {})",
                kind.name(),
                known.join(", ")
            ));
        };
        if !value.is_finite() {
            return Err(format!("parameter `{name}` = {value} is not finite"));
        }
        if let Some((lo, hi)) = decl.range
            && !(lo..=hi).contains(&value)
        {
            return Err(format!("parameter `{name}` = {value} lies outside its range [{lo}, {hi}]"));
        }
        params.insert(name.clone(), value);
    }
    for (name, integer) in kind.params() {
        let v = params.get(*name).copied().unwrap_or(f64::NAN);
        if *integer && v.fract() != 0.0 {
            return Err(format!("parameter `{name}` = {v} must be an integer"));
        }
    }
    // The file's precision of the stored channel(s); the depth itself is F32 in all five.
    let mut file_storage = None;
    for name in kind.stored_names() {
        let p = file
            .channels
            .get(*name)
            .map(|c| c.precision)
            .or_else(|| file.expansions.get(*name).map(|e| e.precision))
            .ok_or_else(|| format!("techniques/{}.ron lacks the channel `{name}`", kind.name()))?;
        if file_storage.is_some_and(|q| q != p) {
            return Err(format!(
                "techniques/{}.ron stores its channels at different precisions",
                kind.name()
            ));
        }
        file_storage = Some(p);
    }
    for name in ["z", "zm"] {
        if let Some(c) = file.channels.get(name)
            && c.precision != Storage::F32
        {
            return Err(format!(
                "techniques/{}.ron stores `{name}` at {:?}; the reference keeps it at F32",
                kind.name(),
                c.precision
            ));
        }
    }
    let storage = match (file_storage, t.storage) {
        (None, None | Some(Storage::F32)) => Storage::F32,
        (None, Some(s)) => {
            return Err(format!(
                "`{}` stores no channel besides the F32 depth: its precision cannot be {s:?}",
                kind.name()
            ));
        }
        (Some(f), s) => s.unwrap_or(f),
    };
    let r = Resolved { kind, params, storage };
    check_sizes(&r)?;
    check_storage(&r)?;
    Ok(r)
}

fn check_sizes(r: &Resolved) -> Result<(), String> {
    let sizes: Vec<(&str, i64)> = match r.kind {
        Kind::Hard | Kind::Pcf => Vec::new(),
        Kind::Vsm | Kind::Csm => vec![("K", r.int("K"))],
        Kind::Esm => vec![("K", r.int("K")), ("K + 2", r.int("K") + 2)],
    };
    for (what, n) in sizes {
        if !(1..=63).contains(&n) || n % 2 == 0 {
            return Err(format!("filter size {what} = {n} must be odd and in 1..=63"));
        }
    }
    if r.kind == Kind::Csm && r.get("sigma") <= 0.0 {
        return Err("the Gaussian's sigma must be positive".into());
    }
    if r.kind == Kind::Pcf && r.int("N") < 1 {
        return Err("PCF needs N >= 1".into());
    }
    if r.kind == Kind::Csm && r.int("M") < 1 {
        return Err("CSM needs M >= 1".into());
    }
    Ok(())
}

fn check_storage(r: &Resolved) -> Result<(), String> {
    let max = match r.storage {
        Storage::Unorm8 | Storage::Unorm16 => f64::MAX,
        Storage::F16 => 65504.0,
        Storage::F32 => f32::MAX as f64,
    };
    for c in r.stored_channels() {
        if !(c.lo.is_finite() && c.hi.is_finite()) || c.lo.abs().max(c.hi.abs()) > max {
            return Err(format!(
                "channel `{}` of `{}` spans [{}, {:e}], which {:?} cannot hold",
                c.name,
                r.kind.name(),
                c.lo,
                c.hi,
                r.storage
            ));
        }
    }
    Ok(())
}

/// Check a depth map: square, every depth finite and in `[0, 1]`.
pub fn check_map(map: &DepthMap) -> Result<(), String> {
    let n = map.size as usize;
    if n == 0 {
        return Err("the depth map is empty (size 0)".into());
    }
    if n.checked_mul(n) != Some(map.z.len()) {
        return Err(format!(
            "a depth map of size {} needs {} texels, not {}",
            map.size,
            n.saturating_mul(n),
            map.z.len()
        ));
    }
    if let Some((i, z)) = map.z.iter().enumerate().find(|(_, z)| !(0.0..=1.0).contains(*z)) {
        return Err(format!("depth {z} at texel {} lies outside [0, 1]", i));
    }
    Ok(())
}

/// Clamp a visibility to `[0, 1]`; NaN reads as 1 (lit).
pub fn clamp_visibility(v: f64) -> f64 {
    if v.is_nan() { 1.0 } else { v.clamp(0.0, 1.0) }
}
