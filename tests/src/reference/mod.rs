//! Hand-written reference implementations of the bundled techniques (`techniques/hard.ron`,
//! `pcf.ron`, `vsm.ron`, `esm.ron`, `evsm.ron`, `msm.ron`, `csm.ron`, `cssm.ron`,
//! `pcss.ron`, and `vssm.ron`, `mssm.ron`, `msm-hausdorff.ron` in [`moments`]), written from
//! the papers (Annen 2008, chapters 3, 4, 6, 7 and 8; Fernando 2005; Lauritzen & McCool
//! 2008; Peters & Klein 2015; Yang et al. 2010, "Variance Soft Shadow Mapping"; Peters,
//! Münstermann, Wetzstein & Klein 2017, "Improved Moment Shadow Maps for Translucent
//! Occluders, Soft Shadows and Single Scattering") and the technique files alone (for VSSM,
//! MSSM and Hausdorff MSM, the papers and a specification of their stated choices, without
//! reading the files' expressions: [`moments`] says which papers could be read),
//! independently of the compiler's code generator, so that tests can check that generated
//! and hand-written results agree.
//!
//! EVSM (exponential variance shadow maps; Lauritzen & McCool 2008, "Layered variance
//! shadow maps", section on exponential warping, with Chebyshev's one-sided bound of
//! Donnelly & Lauritzen 2006): the depth is mapped to `t = 2z - 1` in `[-1, 1]` and warped
//! by `w+(t) = exp(c_pos t)` and `w-(t) = -exp(-c_neg t)`, both increasing in `t`; the Map
//! pass stores `(w+, w+^2, w-, w-^2)`, which are box-filtered and mipmapped like VSM's
//! moments; the Shade pass bounds the lit fraction with Chebyshev's inequality in each
//! warped space, `p = var / (var + (w(t_r) - mean)^2)` behind the mean and 1 in front of it,
//! the variance clamped below by the minimum variance scaled by the square of the warp's
//! derivative with respect to `t` at the receiver, `min_variance (c w(t_r))^2` (the scaling
//! of Lauritzen's sample code: the minimum variance is in units of `t`), and takes the
//! smaller of the two bounds (both are upper bounds of the same lit fraction), then
//! `linstep(bleed, 1, p)`. EVSM has no constant bias (`evsm.ron` declares none).
//!
//! MSM (moment shadow mapping, Hamburger 4MSM; Peters & Klein 2015, Algorithm 2): the Map
//! pass stores `b = (z, z^2, z^3, z^4)`, filtered and mipmapped; the Shade pass biases the
//! filtered moments, `b' = (1 - alpha) b + alpha (1/2, 1/2, 1/2, 1/2)`, solves
//! `[1 b1' b2'; b1' b2' b3'; b2' b3' b4'] c = (1, z_f, z_f^2)` by a Cholesky factorisation,
//! takes the roots `z2 <= z3` of `c1 + c2 z + c3 z^2` and returns the lower bound `G` of the
//! shadow intensity by the paper's three cases (`z_f <= z2`: 0; `z_f <= z3`:
//! `(z_f z3 - b1' (z_f + z3) + b2') / ((z3 - z2)(z_f - z2))`; else
//! `1 - (z2 z3 - b1' (z2 + z3) + b2') / ((z_f - z2)(z_f - z3))`); the visibility is `1 - G`. `alpha` is the file's
//! (default 3e-5, the paper's value for moments stored as 32-bit floats; the paper takes a
//! larger one for 16-bit storage). Where every filtered depth is exactly 0 or exactly 1 the
//! biased moments lie on the boundary of the moment space (the Hankel matrix is singular:
//! the bias distribution has its two atoms at 0 and 1); there the Cholesky pivots are
//! clamped below at [`cpu::MSM_PIVOT`] and the bound is the limit of the positive-definite
//! case (its coefficients are affine in the last pivot).
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
//!
//! The soft-shadow techniques (`cssm`, `pcss`) also need the light: its width, the world
//! distances of the fitted depth range and its projection ([`LightFrame`], set with
//! [`Technique::lit`]). A receiver's view distance is `d_world = near + d (far - near)`
//! (the Depth pass's linear normalisation, docs/language.md section 7).
//!
//! [`penumbra`] is a separate f64 reference of penumbra maps (Wyman & Hansen 2003): silhouettes,
//! a ray-cast shadow map, exact cones and sheets, the resolve rules and the final lookup, from
//! world triangles rather than a depth map; [`penumbra_gpu`] is a hand-written WGSL penumbra map
//! (analytic cones and sheets in f32) to compare with it texel by texel.
//!
//! [`plm`] is a separate f64 reference of penumbra limit maps (Lawlor 2006) and smoothies:
//! ribbons per silhouette edge, the maps `g`, `c`, `b`, `p_i`, equations 1 and 2 and the
//! visibility-to-illumination tables; [`plm_gpu`] is its hand-written WGSL twin (ribbons and
//! `b` in f32).
//!
//! [`linear`] is a separate f64 reference of soft shadow maps for linear lights (Heidrich,
//! Brabec & Seidel 2000): per-sample depth maps, skins warped between neighbouring samples into
//! two visibility channels, and the shade; [`linear_gpu`] is its hand-written WGSL twin (the
//! detector and the warp in f32) to compare with it channel by channel.

pub mod compute;
pub mod cpu;
pub mod gpu;
pub mod linear;
pub mod linear_gpu;
pub mod moments;
pub mod moments_tolerance;
pub mod penumbra;
pub mod penumbra_gpu;
pub mod plm;
pub mod plm_gpu;
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

/// How the light's view maps world lengths to shadow-map uv (`uv_width` in
/// docs/language.md: `len / (texel world size at dist * shadow_size)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// An orthographic view whose shadow map covers `extent` world units along each of its
    /// x and y axes (the square map's full width): `uv_width(len, dist) = len / extent` at any
    /// distance.
    Orthographic { extent: f64 },
    /// A perspective view of vertical (and, the map being square, horizontal) field of view
    /// `fov_y` radians: the map covers `2 dist tan(fov_y / 2)` at view distance `dist`, so
    /// `uv_width(len, dist) = len / (2 dist tan(fov_y / 2))` (Annen 2008, 8.3.1).
    Perspective { fov_y: f64 },
}

/// The light as the soft-shadow techniques see it (the `light_width`, `near`, `far` inputs
/// of docs/language.md section 8.5, and the projection `uv_width` needs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightFrame {
    /// `light_width`: the full width of the light's outline along the light view's x and y
    /// axes (the shadow map's u and v), world units; 0 for a point light.
    pub width: [f64; 2],
    /// `near`, `far`: world distances along the light's view axis of the fitted depth range;
    /// the Depth pass stores `z = (distance - near) / (far - near)`.
    pub near: f64,
    pub far: f64,
    pub projection: Projection,
}

impl LightFrame {
    /// The tests' query plane: an orthographic light of extent `[-1, 1] x [-1, 1]` (a length
    /// L is L / 2 in uv), near 8, far 12, a square light `width` wide.
    pub fn query_plane(width: f64) -> LightFrame {
        LightFrame {
            width: [width, width],
            near: 8.0,
            far: 12.0,
            projection: Projection::Orthographic { extent: 2.0 },
        }
    }

    /// `uv_width(len, dist)`: the uv extent of a world length `len` across the light's view
    /// at view distance `dist`.
    pub fn uv_width(&self, len: f64, dist: f64) -> f64 {
        len * self.uv_per_world(dist)
    }

    /// `1 / (texel world size at dist * shadow_size)`: uv units per world unit at `dist`.
    pub fn uv_per_world(&self, dist: f64) -> f64 {
        match self.projection {
            Projection::Orthographic { extent } => 1.0 / extent,
            Projection::Perspective { fov_y } => 1.0 / (2.0 * dist * (0.5 * fov_y).tan()),
        }
    }

    /// `d_world` of a receiver at normalised depth `d`.
    pub fn d_world(&self, d: f64) -> f64 {
        self.near + d * (self.far - self.near)
    }

    fn check(&self) -> Result<(), String> {
        let [wx, wy] = self.width;
        if !(wx.is_finite() && wy.is_finite() && wx >= 0.0 && wy >= 0.0) {
            return Err(format!("the light's width {:?} must be finite and non-negative", self.width));
        }
        if !(self.near.is_finite() && self.far.is_finite() && self.near > 0.0 && self.far > self.near) {
            return Err(format!(
                "the light's depth range must satisfy 0 < near < far (near {}, far {})",
                self.near, self.far
            ));
        }
        match self.projection {
            Projection::Orthographic { extent } if !(extent.is_finite() && extent > 0.0) => {
                Err(format!("an orthographic light's extent {extent} must be positive"))
            }
            Projection::Perspective { fov_y } if !(fov_y > 0.0 && fov_y < std::f64::consts::PI) => {
                Err(format!("a perspective light's field of view {fov_y} must lie in (0, pi)"))
            }
            _ => Ok(()),
        }
    }
}

/// A technique to evaluate: the name of a bundled technique file, parameter values by the
/// file's names (a missing one takes the file's default), an optional override of the
/// precision of the stored non-depth channel or expansion (CSM's basis `f`, VSM's moments
/// `m1`/`m2`, ESM's `e`; `None` keeps the file's; not supported for CSSM, whose channels
/// keep the file's precisions), and the light (needed by `cssm` and `pcss`, ignored by the
/// others).
#[derive(Clone, Debug, PartialEq)]
pub struct Technique {
    pub name: String,
    pub params: BTreeMap<String, f64>,
    pub storage: Option<Storage>,
    pub light: Option<LightFrame>,
}

impl Technique {
    /// The technique at its file's defaults.
    pub fn new(name: &str) -> Technique {
        Technique {
            name: name.to_string(),
            params: BTreeMap::new(),
            storage: None,
            light: None,
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

    /// Set the light (for `cssm` and `pcss`).
    pub fn lit(mut self, light: LightFrame) -> Technique {
        self.light = Some(light);
        self
    }
}

/// The nine techniques the references implement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Hard,
    Pcf,
    Vsm,
    Esm,
    Evsm,
    Msm,
    Csm,
    Cssm,
    Pcss,
    Vssm,
    Mssm,
    MsmHausdorff,
}

impl Kind {
    pub const ALL: [Kind; 12] = [
        Kind::Hard,
        Kind::Pcf,
        Kind::Vsm,
        Kind::Esm,
        Kind::Evsm,
        Kind::Msm,
        Kind::Csm,
        Kind::Cssm,
        Kind::Pcss,
        Kind::Vssm,
        Kind::Mssm,
        Kind::MsmHausdorff,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Hard => "hard",
            Kind::Pcf => "pcf",
            Kind::Vsm => "vsm",
            Kind::Esm => "esm",
            Kind::Evsm => "evsm",
            Kind::Msm => "msm",
            Kind::Csm => "csm",
            Kind::Cssm => "cssm",
            Kind::Pcss => "pcss",
            Kind::Vssm => "vssm",
            Kind::Mssm => "mssm",
            Kind::MsmHausdorff => "msm-hausdorff",
        }
    }

    fn source(self) -> &'static str {
        match self {
            Kind::Hard => include_str!("../../../techniques/hard.ron"),
            Kind::Pcf => include_str!("../../../techniques/pcf.ron"),
            Kind::Vsm => include_str!("../../../techniques/vsm.ron"),
            Kind::Esm => include_str!("../../../techniques/esm.ron"),
            Kind::Evsm => include_str!("../../../techniques/evsm.ron"),
            Kind::Msm => include_str!("../../../techniques/msm.ron"),
            Kind::Csm => include_str!("../../../techniques/csm.ron"),
            Kind::Cssm => include_str!("../../../techniques/cssm.ron"),
            Kind::Pcss => include_str!("../../../techniques/pcss.ron"),
            Kind::Vssm => include_str!("../../../techniques/vssm.ron"),
            Kind::Mssm => include_str!("../../../techniques/mssm.ron"),
            Kind::MsmHausdorff => include_str!("../../../techniques/msm-hausdorff.ron"),
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
            Kind::Evsm => &[
                ("c_pos", false),
                ("c_neg", false),
                ("K", true),
                ("min_variance", false),
                ("bleed", false),
                ("slope_bias", false),
            ],
            Kind::Msm => &[("K", true), ("alpha", false), ("bias", false), ("slope_bias", false)],
            Kind::Csm => &[
                ("M", true),
                ("alpha", false),
                ("fix", true),
                ("K", true),
                ("sigma", false),
                ("bias", false),
                ("slope_bias", false),
            ],
            Kind::Cssm => &[
                ("M", true),
                ("alpha", false),
                ("fix", true),
                ("filter", true),
                ("K", true),
                ("sigma", false),
                ("ring", false),
                ("min_blocker", false),
                ("A", false),
                ("B", false),
                ("bias", false),
                ("slope_bias", false),
            ],
            Kind::Pcss => &[("N", true), ("M", true), ("bias", false), ("slope_bias", false)],
            // `subdivide` and `quantise` are Bool params, read as 1 or 0
            Kind::Vssm => &[("min_variance", false), ("bias", false), ("slope_bias", false), ("subdivide", true)],
            Kind::Mssm => &[
                ("alpha", false),
                ("bias", false),
                ("slope_bias", false),
                ("lit_weight", false),
                ("quantise", true),
            ],
            Kind::MsmHausdorff => &[("K", true), ("alpha", false), ("bias", false), ("slope_bias", false)],
        }
    }

    /// The channels or expansions whose precision `Technique::storage` overrides.
    fn stored_names(self) -> &'static [&'static str] {
        match self {
            // CSSM's channels have their own precisions (see `Resolved::channel_storage`)
            Kind::Hard | Kind::Pcf | Kind::Pcss | Kind::Cssm => &[],
            Kind::Vsm => &["m1", "m2"],
            Kind::Esm => &["e"],
            Kind::Evsm => &["p1", "p2", "n1", "n2"],
            Kind::Msm | Kind::MsmHausdorff => &["b1", "b2", "b3", "b4"],
            Kind::Csm => &["f"],
            Kind::Vssm => &["m1", "m2"],
            Kind::Mssm => &["q1", "q2", "q3", "q4"],
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
    #[serde(deserialize_with = "number_or_bool")]
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

/// A parameter's default: a number, or a `Bool` param's `true` / `false` read as 1 / 0.
fn number_or_bool<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum V {
        B(bool),
        N(f64),
    }
    Ok(match V::deserialize(d)? {
        V::B(b) => f64::from(u8::from(b)),
        V::N(n) => n,
    })
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
    // the file's own name: its stem, but `msm_hausdorff` in msm-hausdorff.ron (a name is an
    // identifier)
    let declared = kind.name().replace('-', "_");
    if file.name != declared {
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
    /// Precision of the stored non-depth channel (F32, the depth's, for hard, PCF and
    /// PCSS; for CSSM the precision of the CSM basis, Unorm8, see
    /// [`Resolved::channel_storage`] for the others).
    pub storage: Storage,
    /// The light (checked present for CSSM and PCSS).
    pub light: Option<LightFrame>,
}

impl Resolved {
    /// A parameter the reference reads ([`resolve`] checked that the file declares it).
    pub fn get(&self, name: &str) -> f64 {
        self.params.get(name).copied().unwrap_or(f64::NAN)
    }

    /// The constant depth bias: the file's `bias`, 0 for a technique without one (EVSM).
    pub fn bias(&self) -> f64 {
        self.params.get("bias").copied().unwrap_or(0.0)
    }

    /// An integer parameter.
    pub fn int(&self, name: &str) -> i64 {
        self.get(name) as i64
    }

    /// The precision of one stored channel (by its name in [`Resolved::stored_channels`]).
    /// CSSM (techniques/cssm.ron): the CSM basis `f_*` at Unorm8, the z-weighted basis `g_*`
    /// and `zh` at F16 (mipmaps); every table channel `fs_*`, `gs_*`, `zhs` at Unorm8. The
    /// other techniques store every channel at [`Resolved::storage`].
    pub fn channel_storage(&self, name: &str) -> Storage {
        match self.kind {
            Kind::Cssm if name.starts_with("g_") || name == "zh" => Storage::F16,
            Kind::Cssm => Storage::Unorm8,
            _ => self.storage,
        }
    }

    /// The light frame (CSSM and PCSS; `resolve` refused them without one).
    pub fn light(&self) -> LightFrame {
        self.light.unwrap_or(LightFrame::query_plane(0.0))
    }

    /// The channels the Map pass stores at `storage` ([`Resolved::channel_storage`] for
    /// CSSM), in the order the GPU reference packs them (four per RGBA layer; CSSM packs the
    /// CSM basis and the z-weighted channels in two textures), each with the range of its
    /// value for `z` in `[0, 1]`.
    pub fn stored_channels(&self) -> Vec<StoredChannel> {
        let ch = |name: String, lo: f64, hi: f64| StoredChannel { name, lo, hi };
        match self.kind {
            Kind::Hard | Kind::Pcf | Kind::Pcss => Vec::new(),
            // z and z^2 of z in [0, 1]
            Kind::Vsm => vec![ch("m1".into(), 0.0, 1.0), ch("m2".into(), 0.0, 1.0)],
            // exp(c z) of z in [0, 1] (eq. 7.1)
            Kind::Esm => vec![ch("e_t0_k1".into(), 1.0, self.get("c").exp())],
            // the warps of t = 2z - 1 in [-1, 1]: exp(c+ t) and its square, increasing;
            // -exp(-c- t), increasing and negative, and its square
            Kind::Evsm => {
                let (p, n) = (self.get("c_pos"), self.get("c_neg"));
                vec![
                    ch("p1".into(), (-p).exp(), p.exp()),
                    ch("p2".into(), (-2.0 * p).exp(), (2.0 * p).exp()),
                    ch("n1".into(), -n.exp(), -(-n).exp()),
                    ch("n2".into(), (-2.0 * n).exp(), (2.0 * n).exp()),
                ]
            }
            // z^k of z in [0, 1]
            Kind::Msm | Kind::MsmHausdorff => (1..=4).map(|k| ch(format!("b{k}"), 0.0, 1.0)).collect(),
            // VSSM: z and z^2 of z in [0, 1] (summed into f32 tables less 1/2)
            Kind::Vssm => vec![ch("m1".into(), 0.0, 1.0), ch("m2".into(), 0.0, 1.0)],
            // MSSM: the quantised signed moments (each in [0, 1] for s in [-1, 1]; JCGT 2017,
            // section 3.1), or the raw z^k
            Kind::Mssm => (1..=4).map(|k| ch(format!("q{k}"), 0.0, 1.0)).collect(),
            // sin(c_k z), cos(c_k z) with c_k = pi (2k - 1) (eq. 6.6): sin(pi z) is
            // non-negative on [0, 1]; every other basis sweeps at least a whole period
            // (c_k >= 3 pi for k >= 2, and cos(pi z) goes from 1 to -1), so spans [-1, 1].
            Kind::Csm => (1..=self.int("M"))
                .flat_map(|k| {
                    let sin_lo = if k == 1 { 0.0 } else { -1.0 };
                    [ch(format!("f_t0_k{k}"), sin_lo, 1.0), ch(format!("f_t1_k{k}"), -1.0, 1.0)]
                })
                .collect(),
            // CSSM (cssm.ron), mipmaps (filter 0): the CSM basis `f` as for CSM; the
            // z-weighted basis z sin(c_k z), z cos(c_k z) (eq. 8.8) and z/2. Their ranges are
            // the interval products of docs/language.md 5 (z in [0, 1] times the basis's
            // exact range): z sin(pi z) in [0, 1], every other product in [-1, 1]; z/2 in
            // [0, 1/2]. Summed-area tables (filter 1): the same as `fs`, `gs`, `zhs`.
            Kind::Cssm => {
                let (f, g, zh) = if self.int("filter") == 1 {
                    ("fs", "gs", "zhs")
                } else {
                    ("f", "g", "zh")
                };
                let m = self.int("M");
                let series = |name: &str| -> Vec<StoredChannel> {
                    (1..=m)
                        .flat_map(|k| {
                            let sin_lo = if k == 1 { 0.0 } else { -1.0 };
                            [ch(format!("{name}_t0_k{k}"), sin_lo, 1.0), ch(format!("{name}_t1_k{k}"), -1.0, 1.0)]
                        })
                        .collect()
                };
                let mut out = series(f);
                out.extend(series(g));
                out.push(ch(zh.into(), 0.0, 0.5));
                out
            }
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
            "no reference implementation of technique `{}` (there are: hard, pcf, vsm, esm, evsm, msm, csm, cssm, pcss, vssm, mssm, msm-hausdorff)",
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
    if kind == Kind::Cssm {
        if let Some(s) = t.storage {
            return Err(format!(
                "`cssm` keeps the precisions of its file (f Unorm8, g and zh F16, fs, gs and zhs Unorm8): an override to {s:?} is not supported"
            ));
        }
        for (name, want) in [("zh", Storage::F16), ("zhs", Storage::Unorm8)] {
            let p = file.channels.get(name).map(|c| c.precision);
            if p != Some(want) {
                return Err(format!(
                    "techniques/cssm.ron stores `{name}` at {p:?}; the reference expects {want:?}"
                ));
            }
        }
        for (name, want) in [
            ("f", Storage::Unorm8),
            ("g", Storage::F16),
            ("fs", Storage::Unorm8),
            ("gs", Storage::Unorm8),
        ] {
            let p = file.expansions.get(name).map(|e| e.precision);
            if p != Some(want) {
                return Err(format!(
                    "techniques/cssm.ron stores `{name}` at {p:?}; the reference expects {want:?}"
                ));
            }
        }
    }
    let light = match kind {
        Kind::Cssm | Kind::Pcss | Kind::Vssm | Kind::Mssm => {
            let light = t.light.ok_or_else(|| {
                format!(
                    "`{}` needs the light (`Technique::light`: its width, near, far and projection)",
                    kind.name()
                )
            })?;
            light.check()?;
            Some(light)
        }
        _ => t.light,
    };
    let file_storage = if kind == Kind::Cssm { Some(Storage::Unorm8) } else { file_storage };
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
    let r = Resolved {
        kind,
        params,
        storage,
        light,
    };
    check_sizes(&r)?;
    check_storage(&r)?;
    Ok(r)
}

fn check_sizes(r: &Resolved) -> Result<(), String> {
    let sizes: Vec<(&str, i64)> = match r.kind {
        Kind::Hard | Kind::Pcf | Kind::Pcss => Vec::new(),
        Kind::Vsm | Kind::Evsm | Kind::Msm | Kind::MsmHausdorff | Kind::Csm | Kind::Cssm => vec![("K", r.int("K"))],
        Kind::Vssm | Kind::Mssm => Vec::new(),
        Kind::Esm => vec![("K", r.int("K")), ("K + 2", r.int("K") + 2)],
    };
    for (what, n) in sizes {
        if !(1..=63).contains(&n) || n % 2 == 0 {
            return Err(format!("filter size {what} = {n} must be odd and in 1..=63"));
        }
    }
    if matches!(r.kind, Kind::Csm | Kind::Cssm) && r.get("sigma") <= 0.0 {
        return Err("the Gaussian's sigma must be positive".into());
    }
    if r.kind == Kind::Pcf && r.int("N") < 1 {
        return Err("PCF needs N >= 1".into());
    }
    if matches!(r.kind, Kind::Csm | Kind::Cssm) && r.int("M") < 1 {
        return Err("CSM needs M >= 1".into());
    }
    if r.kind == Kind::Pcss && (r.int("N") < 1 || r.int("M") < 1) {
        return Err("PCSS needs N >= 1 and M >= 1".into());
    }
    if r.kind == Kind::Cssm && r.get("ring") >= 0.5 {
        return Err("CSSM's ring must stay below 1/2".into());
    }
    Ok(())
}

fn check_storage(r: &Resolved) -> Result<(), String> {
    for c in r.stored_channels() {
        let max = match r.channel_storage(&c.name) {
            Storage::Unorm8 | Storage::Unorm16 => f64::MAX,
            Storage::F16 => 65504.0,
            Storage::F32 => f32::MAX as f64,
        };
        if !(c.lo.is_finite() && c.hi.is_finite()) || c.lo.abs().max(c.hi.abs()) > max {
            return Err(format!(
                "channel `{}` of `{}` spans [{}, {:e}], which {:?} cannot hold",
                c.name,
                r.kind.name(),
                c.lo,
                c.hi,
                r.channel_storage(&c.name)
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
