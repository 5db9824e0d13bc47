//! The technique as written: what the parser produces and every later phase reads.
//! Each node keeps the span it was read from.

use crate::front::expr::Expr;
use crate::span::{Span, Spanned};
use std::fmt;

pub type Name = Spanned<String>;

#[derive(Clone, Debug, PartialEq)]
pub struct Technique {
    pub name: Name,
    pub title: Option<String>,
    pub paper: Option<String>,
    /// The light models the technique is meant for (empty: any).
    pub lights: Vec<Spanned<LightModel>>,
    pub params: Vec<Param>,
    pub channels: Vec<Channel>,
    pub expansions: Vec<Expansion>,
    /// Functions the expressions may call, inlined at each call (docs/language.md 8.10).
    pub functions: Vec<Function>,
    /// Constant arrays the expressions index with compile-time integers (8.11).
    pub arrays: Vec<ArrayDecl>,
    pub passes: Vec<Pass>,
    /// `light_samples`: how many light samples the `PerSample` passes render views of, a
    /// compile-time expression (a fixed param); absent: 1.
    pub light_samples: Option<Expr>,
    /// `shadow_map: N`: the shadow-map size the technique was tuned for (`sshc tune` writes
    /// it); a command's `--shadow-map` outranks it, and it outranks the scene file's.
    pub shadow_map: Option<Spanned<u32>>,
    /// `tune: { "AXIS": ... }`: how `sshc tune` may vary each axis (docs/tune.md).
    pub tune: Vec<TuneAxis>,
    pub span: Span,
}

/// One entry of a technique's `tune:` block: an axis of `sshc tune`'s search (a param's
/// name, `shadow_map`, `cascades`, `precision:NAME` or `schedule:PASS`) narrowed to a list
/// of values or a sub-range, or frozen at the technique's value.
#[derive(Clone, Debug, PartialEq)]
pub struct TuneAxis {
    pub name: Spanned<String>,
    pub choice: TuneChoice,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum TuneChoice {
    /// `[v, ...]`: these values only.
    Values(Vec<Spanned<TuneValue>>),
    /// `(lo, hi)`: a sub-range of the param's declared range.
    Range(Spanned<f64>, Spanned<f64>),
    /// `Frozen`: the technique's own value.
    Frozen,
}

/// A value in a `tune:` list: a number, a boolean or a name (`F16`, `Compute`).
#[derive(Clone, Debug, PartialEq)]
pub enum TuneValue {
    Number(f64),
    Bool(bool),
    Name(String),
}

impl fmt::Display for TuneValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TuneValue::Number(x) => write!(f, "{}", crate::front::expr::fmt_float(*x).trim_end_matches(".0")),
            TuneValue::Bool(b) => write!(f, "{b}"),
            TuneValue::Name(n) => f.write_str(n),
        }
    }
}

/// The light model a technique assumes: the pass-graph schema's type, so the compiler
/// and the runtime share one list of light kinds.
pub use sshc_graph::{LightKind, LightModel, Neighbour};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ScalarTy {
    F32,
    I32,
    Bool,
}

impl ScalarTy {
    pub fn name(self) -> &'static str {
        match self {
            ScalarTy::F32 => "f32",
            ScalarTy::I32 => "i32",
            ScalarTy::Bool => "bool",
        }
    }
}

/// A parameter value known at compile time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConstValue {
    Int(i64),
    /// A u32 (its arithmetic wraps modulo 2^32, at compile time as on the GPU).
    Uint(u32),
    Float(f64),
    Bool(bool),
}

impl ConstValue {
    pub fn as_f64(self) -> f64 {
        match self {
            ConstValue::Int(v) => v as f64,
            ConstValue::Uint(v) => v as f64,
            ConstValue::Float(v) => v,
            ConstValue::Bool(b) => b as i64 as f64,
        }
    }
}

impl std::fmt::Display for ConstValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ConstValue::Int(v) => write!(f, "{v}"),
            ConstValue::Uint(v) => write!(f, "{v}u"),
            ConstValue::Float(v) => write!(f, "{}", crate::front::expr::fmt_float(*v)),
            ConstValue::Bool(v) => write!(f, "{v}"),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    pub name: Name,
    pub ty: Spanned<ScalarTy>,
    pub default: Spanned<ConstValue>,
    /// Inclusive range `(lo, hi)`.
    pub range: Option<(Spanned<f64>, Spanned<f64>)>,
    /// Fixed at compile time (substituted, series unrolled) or a runtime uniform.
    pub fixed: bool,
    pub doc: Option<String>,
    pub span: Span,
}

/// A function declared in the technique: typed parameters and a body expression, inlined
/// at every call, in the caller's context (its pass, its lookups), seeing its parameters,
/// the technique's params and the built-in inputs but not the caller's `let`s.
#[derive(Clone, Debug, PartialEq)]
pub struct Function {
    pub name: Name,
    /// In call order: each parameter's name and type (`F32`, `I32`, `U32`, `Bool`, `Vec2` to
    /// `Vec4`, or `Channel` / `Expansion`: a name passed through to the lookups).
    pub params: Vec<(Name, Spanned<ParamTy>)>,
    pub body: Expr,
    pub doc: Option<String>,
    pub span: Span,
}

/// The type of a function's parameter: a value, or a channel or expansion passed by name
/// (calls are inlined, so the body's lookups read the argument's channel).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ParamTy {
    Value(Ty),
    Channel,
    Expansion,
}

impl fmt::Display for ParamTy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamTy::Value(t) => write!(f, "{t}"),
            ParamTy::Channel => write!(f, "channel"),
            ParamTy::Expansion => write!(f, "expansion"),
        }
    }
}

/// A constant array of the technique: elements of one type, each an expression known at
/// compile time (literals, fixed params, constants), read as `name[i]` with `i` an integer
/// known at compile time (a literal or a series variable).
#[derive(Clone, Debug, PartialEq)]
pub struct ArrayDecl {
    pub name: Name,
    pub ty: Spanned<Ty>,
    pub values: Vec<Expr>,
    pub doc: Option<String>,
    pub span: Span,
}

/// Storage precision of a channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Precision {
    Unorm8,
    Unorm16,
    F16,
    F32,
}

impl Precision {
    pub const ALL: [Precision; 4] = [Precision::Unorm8, Precision::Unorm16, Precision::F16, Precision::F32];

    pub fn name(self) -> &'static str {
        match self {
            Precision::Unorm8 => "Unorm8",
            Precision::Unorm16 => "Unorm16",
            Precision::F16 => "F16",
            Precision::F32 => "F32",
        }
    }

    pub fn parse(s: &str) -> Option<Precision> {
        Some(match s.to_ascii_lowercase().as_str() {
            "unorm8" => Precision::Unorm8,
            "unorm16" => Precision::Unorm16,
            "f16" => Precision::F16,
            "f32" => Precision::F32,
            _ => return None,
        })
    }

    /// How a channel of this precision is stored: one component of a texture format
    /// (the graph's table of formats says the rest).
    pub fn component(self) -> sshc_graph::Component {
        match self {
            Precision::Unorm8 => sshc_graph::Component::Unorm8,
            Precision::Unorm16 => sshc_graph::Component::Unorm16,
            Precision::F16 => sshc_graph::Component::Float16,
            Precision::F32 => sshc_graph::Component::Float32,
        }
    }

    /// Bytes of one channel.
    pub fn bytes(self) -> u32 {
        self.component().bytes()
    }

    pub fn is_unorm(self) -> bool {
        self.component().is_unorm()
    }

    /// Whether no precision holds a wider range (so "store it wider" is no fix).
    pub fn is_widest(self) -> bool {
        match self {
            Precision::F32 => true,
            Precision::Unorm8 | Precision::Unorm16 | Precision::F16 => false,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub name: Name,
    pub precision: Spanned<Precision>,
    /// `precision: Auto`: left to the compiler (`precision` is then F32 until it chooses).
    pub precision_auto: bool,
    /// The per-texel value (map side). `None`: the channel is written by a Depth pass.
    pub value: Option<Expr>,
    /// `range: (lo, hi)`: the values the channel stores, declared (clamped at encode; the
    /// encodes use it in place of the analysed interval).
    pub range: Option<(Spanned<f64>, Spanned<f64>)>,
    pub doc: Option<String>,
    pub span: Span,
}

/// A basis expansion `f(d, z) ~ constant + sum_k sum_terms coeff(d) * basis(z)`, written as data.
#[derive(Clone, Debug, PartialEq)]
pub struct Expansion {
    pub name: Name,
    pub index: Name,
    pub from: Expr,
    pub to: Expr,
    /// `let` bindings, in order; each may use the index, params and earlier lets.
    pub lets: Vec<(Name, Expr)>,
    pub constant: Expr,
    pub terms: Vec<Term>,
    /// Precision of the basis channels.
    pub precision: Spanned<Precision>,
    /// `precision: Auto`: left to the compiler.
    pub precision_auto: bool,
    pub doc: Option<String>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    /// Receiver side: may use `d` and other receiver inputs, params, the index and lets.
    pub coeff: Expr,
    /// Map side: may use channels of the map (such as `z`), params, the index and lets.
    pub basis: Expr,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Pass {
    pub name: Name,
    pub kind: PassKind,
    /// Span of the pass kind's name (`Filter` in `Filter(...)`).
    pub kind_span: Span,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightView {
    /// The light's centre (a hard shadow map under an area light uses it).
    Center,
    /// One view per light sample (linear lights).
    PerSample,
}

impl LightView {
    /// One view per light sample (rather than the centre's alone).
    pub fn is_per_sample(self) -> bool {
        match self {
            LightView::PerSample => true,
            LightView::Center => false,
        }
    }
}

/// How a pass runs on the GPU (the technique says what is computed, the
/// schedule how). Map, Filter, Mipmap and Shade passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Schedule {
    /// One full-screen triangle; a fragment per texel writes the channels as colour targets.
    /// A Shade pass: forward, the camera raster's fragments evaluate the visibility.
    #[default]
    Fragment,
    /// One compute invocation per texel (8 x 8 per workgroup), storing into storage
    /// textures; only where every written format is a storage format. A Filter's
    /// workgroup loads its tile and the kernel's apron into workgroup memory once per
    /// layer and filters from there. A Shade pass: deferred, a camera raster writes a
    /// G-buffer and one compute invocation per pixel evaluates the visibility from it.
    Compute,
}

impl PassKind {
    /// The schedule a technique gives a pass (Map, Filter, Mipmap and Shade passes have one).
    pub fn schedule(&self) -> Option<Schedule> {
        match self {
            PassKind::Map { schedule, .. }
            | PassKind::Filter { schedule, .. }
            | PassKind::Mipmap { schedule, .. }
            | PassKind::Shade { schedule, .. } => schedule.as_ref().map(|s| s.value),
            PassKind::Depth { .. } | PassKind::SummedArea { .. } | PassKind::Geometry { .. } => None,
        }
    }

    /// Where the technique writes the pass's `schedule:` value, if it does.
    pub fn schedule_span(&self) -> Option<Span> {
        match self {
            PassKind::Map { schedule, .. }
            | PassKind::Filter { schedule, .. }
            | PassKind::Mipmap { schedule, .. }
            | PassKind::Shade { schedule, .. } => schedule.as_ref().map(|s| s.span),
            PassKind::Depth { .. } | PassKind::SummedArea { .. } | PassKind::Geometry { .. } => None,
        }
    }

    /// Whether a pass kind has schedules to choose from.
    pub fn schedulable(&self) -> bool {
        matches!(
            self,
            PassKind::Map { .. } | PassKind::Filter { .. } | PassKind::Mipmap { .. } | PassKind::Shade { .. }
        )
    }
}

impl Schedule {
    pub const NAMES: [&'static str; 2] = ["Fragment", "Compute"];

    /// A schedule by its name in a technique (`Compute`) or on the command line (`compute`).
    pub fn parse(s: &str) -> Option<Schedule> {
        match s {
            "Fragment" | "fragment" => Some(Schedule::Fragment),
            "Compute" | "compute" => Some(Schedule::Compute),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Schedule::Fragment => "fragment",
            Schedule::Compute => "compute",
        }
    }

    /// One invocation per texel or pixel, rather than a raster.
    pub fn is_compute(self) -> bool {
        match self {
            Schedule::Compute => true,
            Schedule::Fragment => false,
        }
    }

    /// The name a technique file writes (`Compute`).
    pub fn variant(self) -> &'static str {
        match self {
            Schedule::Fragment => Schedule::NAMES[0],
            Schedule::Compute => Schedule::NAMES[1],
        }
    }
}

/// What a summed-area table over a float channel sums (`SummedArea(sum: ...)`); a table
/// over a unorm channel sums its unorm codes in u32.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TableSum {
    /// f32 prefix sums of the values less the midpoint of the channel's range (0 where
    /// it is not finite).
    F32,
    /// u32 prefix sums of fixed-point codes: `round((v - lo) / (hi - lo) * (2^bits - 1))`
    /// over the channel's range, as a unorm of `bits` bits.
    Fixed(u8),
}

impl TableSum {
    /// The widest fixed-point code: codes are converted exactly in f32.
    pub const MAX_BITS: u8 = 24;

    pub fn describe(self) -> String {
        match self {
            TableSum::F32 => "F32".into(),
            TableSum::Fixed(b) => format!("Fixed(bits: {b})"),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reduce {
    Mean,
    Max,
    Min,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Primitive {
    /// Wyman & Hansen: cones at silhouette vertices and sheets along silhouette edges.
    ConesAndSheets,
    /// Lawlor: silhouette ribbons.
    Ribbons,
    /// Heidrich et al.: skins between depth discontinuities, warped into another view.
    Skins,
    /// The scene's triangles that face away from the light, rasterised from it (Lawlor
    /// 2006, section 3.1, step 3).
    BackFaces,
}

impl Primitive {
    /// The names a technique writes, in declaration order.
    pub const NAMES: [&'static str; 4] = ["ConesAndSheets", "Ribbons", "Skins", "BackFaces"];

    /// Whether it joins two light-sample views (skins span one sample's depth
    /// discontinuities, warped into its neighbour's view): it needs `view: PerSample`, a
    /// per-sample Depth resource and the discontinuity threshold.
    pub fn joins_sample_views(self) -> bool {
        match self {
            Primitive::Skins => true,
            Primitive::ConesAndSheets | Primitive::Ribbons | Primitive::BackFaces => false,
        }
    }

    /// The resolve its fragments need: `Some(true)`, the nearest (a depth test on their
    /// depth: ribbons, back faces); `Some(false)`, a blend rule (cones and sheets write no
    /// depth); `None`, any (skins).
    pub fn keeps_nearest(self) -> Option<bool> {
        match self {
            Primitive::Ribbons | Primitive::BackFaces => Some(true),
            Primitive::ConesAndSheets => Some(false),
            Primitive::Skins => None,
        }
    }

    /// Whether its fragments behind the surface the light sees are discarded, which needs
    /// the Depth resource the pass reads (Wyman & Hansen 2003, section 3: the penumbra map
    /// holds the penumbrae of those surfaces only).
    pub fn behind_the_lit_surface_discarded(self) -> bool {
        match self {
            Primitive::ConesAndSheets => true,
            Primitive::Ribbons | Primitive::Skins | Primitive::BackFaces => false,
        }
    }
}

/// A Geometry pass's resolve rule: the graph's (one definition, issue 52).
pub use sshc_graph::Resolve;

/// A Geometry pass's resolve rule: named, or an integer known at compile time (a fixed
/// param, so that sweeps vary it) indexing [`Resolve::ALL`].
#[derive(Clone, Debug, PartialEq)]
pub enum ResolveSpec {
    Rule(Resolve),
    Expr(Expr),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Kernel {
    Box {
        size: Expr,
    },
    Gaussian {
        size: Expr,
        sigma: Expr,
    },
    Max {
        size: Expr,
    },
    Min {
        size: Expr,
    },
    /// 3x3 Laplacian of Gaussian.
    LoG,
}

#[derive(Clone, Debug, PartialEq)]
pub enum PassKind {
    Depth {
        writes: Name,
        channel: Name,
        view: LightView,
    },
    Map {
        reads: Vec<Name>,
        writes: Name,
        /// Channels and expansions (all of an expansion's basis channels) to compute.
        channels: Vec<Name>,
        /// How it runs; the compiler's default where absent.
        schedule: Option<Spanned<Schedule>>,
    },
    Filter {
        reads: Name,
        writes: Name,
        kernel: Spanned<Kernel>,
        /// How it runs; the compiler's default where absent.
        schedule: Option<Spanned<Schedule>>,
    },
    Mipmap {
        reads: Name,
        writes: Name,
        reduce: Reduce,
        /// How it runs; the compiler's default where absent.
        schedule: Option<Spanned<Schedule>>,
    },
    SummedArea {
        reads: Name,
        writes: Name,
        /// What a table over a float channel sums (`F32` where absent); refused over a
        /// unorm channel, whose codes are summed.
        sum: Option<Spanned<TableSum>>,
    },
    Geometry {
        reads: Vec<Name>,
        writes: Name,
        primitive: Primitive,
        channels: Vec<Name>,
        resolve: ResolveSpec,
        view: LightView,
        /// Fragments for which this is false are discarded before the channels are
        /// computed (a bool per fragment).
        keep: Option<Expr>,
        /// `Skins`: the neighbouring sample whose depth discontinuities are warped in.
        from: Option<Spanned<Neighbour>>,
    },
    Shade {
        reads: Vec<Name>,
        visibility: Expr,
        /// How it runs; the compiler's default where absent.
        schedule: Option<Spanned<Schedule>>,
        /// Named per-pixel debug outputs (`debug: {"name": "expr"}`), in the order written;
        /// compiled only where `CompileOptions::debug` asks for them.
        debug: Vec<DebugOutput>,
    },
}

/// A named per-pixel debug output of the Shade pass: an f32 or vector the Shade computes
/// besides the visibility, written to a camera-sized texture `debug_<name>` by builds that
/// ask for it (`CompileOptions::debug`) and left out of the others.
#[derive(Clone, Debug, PartialEq)]
pub struct DebugOutput {
    pub name: Name,
    /// The expression inside the visibility's leading `let`s, so that it sees them (what
    /// check and lower read); its span, and the wrappers', is the expression as written.
    pub value: Expr,
}

impl PassKind {
    /// The kind without its data, whose facts every phase asks (`sshc_graph::PassKind`).
    pub fn kind(&self) -> sshc_graph::PassKind {
        use sshc_graph::PassKind as K;
        match self {
            PassKind::Depth { .. } => K::Depth,
            PassKind::Map { .. } => K::Map,
            PassKind::Filter { .. } => K::Filter,
            PassKind::Mipmap { .. } => K::Mipmap,
            PassKind::SummedArea { .. } => K::SummedArea,
            PassKind::Geometry { .. } => K::Geometry,
            PassKind::Shade { .. } => K::Shade,
        }
    }

    pub fn kind_name(&self) -> &'static str {
        match self {
            PassKind::Depth { .. } => "Depth",
            PassKind::Map { .. } => "Map",
            PassKind::Filter { .. } => "Filter",
            PassKind::Mipmap { .. } => "Mipmap",
            PassKind::SummedArea { .. } => "SummedArea",
            PassKind::Geometry { .. } => "Geometry",
            PassKind::Shade { .. } => "Shade",
        }
    }

    /// Resources this pass reads.
    pub fn reads(&self) -> Vec<&Name> {
        match self {
            PassKind::Depth { .. } => vec![],
            PassKind::Map { reads, .. } | PassKind::Geometry { reads, .. } | PassKind::Shade { reads, .. } => reads.iter().collect(),
            PassKind::Filter { reads, .. } | PassKind::Mipmap { reads, .. } | PassKind::SummedArea { reads, .. } => {
                vec![reads]
            }
        }
    }

    /// The resource this pass writes (`None` for Shade, which writes the camera outputs).
    pub fn writes(&self) -> Option<&Name> {
        match self {
            PassKind::Depth { writes, .. }
            | PassKind::Map { writes, .. }
            | PassKind::Filter { writes, .. }
            | PassKind::Mipmap { writes, .. }
            | PassKind::SummedArea { writes, .. }
            | PassKind::Geometry { writes, .. } => Some(writes),
            PassKind::Shade { .. } => None,
        }
    }
}

/// Types of the expression language. Integer literals are abstract until context fixes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Ty {
    F32,
    I32,
    /// Unsigned 32-bit integers, modulo 2^32 (hashes, bit patterns): never abstract, never
    /// implied; written `7u`, `0x9e3779b9u` or converted with `u32(x)`.
    U32,
    Bool,
    /// `vecN<f32>`, N in 2..=4.
    Vec(u8),
    AbstractInt,
}

impl Ty {
    pub fn from_scalar(s: ScalarTy) -> Ty {
        match s {
            ScalarTy::F32 => Ty::F32,
            ScalarTy::I32 => Ty::I32,
            ScalarTy::Bool => Ty::Bool,
        }
    }

    /// The concrete type an abstract type becomes when nothing else decides it.
    pub fn concrete(self) -> Ty {
        if self == Ty::AbstractInt { Ty::I32 } else { self }
    }

    pub fn is_float_like(self) -> bool {
        matches!(self, Ty::F32 | Ty::Vec(_) | Ty::AbstractInt)
    }

    /// f32, i32 and vectors (what negation, `abs` and `sign` take); u32 is not among them.
    pub fn is_numeric(self) -> bool {
        matches!(self, Ty::F32 | Ty::I32 | Ty::Vec(_) | Ty::AbstractInt)
    }

    /// What arithmetic (`+ - * / %`), comparisons, `min`/`max`/`clamp` and series take:
    /// the numeric types and u32.
    pub fn is_arithmetic(self) -> bool {
        self.is_numeric() || self == Ty::U32
    }

    /// i32, u32 or an abstract integer: what the bit operators take.
    pub fn is_integer(self) -> bool {
        matches!(self, Ty::I32 | Ty::U32 | Ty::AbstractInt)
    }

    pub fn wgsl(self) -> &'static str {
        match self.concrete() {
            Ty::F32 => "f32",
            Ty::I32 => "i32",
            Ty::U32 => "u32",
            Ty::Bool => "bool",
            Ty::Vec(2) => "vec2<f32>",
            Ty::Vec(3) => "vec3<f32>",
            Ty::Vec(_) => "vec4<f32>",
            // `concrete` leaves no abstract type
            Ty::AbstractInt => "i32",
        }
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Ty::AbstractInt => write!(f, "integer"),
            t @ (Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::Vec(_)) => write!(f, "{}", t.wgsl()),
        }
    }
}
