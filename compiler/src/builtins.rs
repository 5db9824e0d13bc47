//! Names the expression language knows without a declaration: receiver- and map-side
//! inputs, constants, WGSL math functions and the sampling functions of a Shade pass.
//! Check and lower both read this one table.

use crate::front::ast::ScalarTy;
use std::fmt;

/// Types of the expression language. Integer literals are abstract until context fixes them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Ty {
    F32,
    I32,
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

    pub fn is_numeric(self) -> bool {
        matches!(self, Ty::F32 | Ty::I32 | Ty::Vec(_) | Ty::AbstractInt)
    }

    pub fn wgsl(self) -> &'static str {
        match self.concrete() {
            Ty::F32 => "f32",
            Ty::I32 => "i32",
            Ty::Bool => "bool",
            Ty::Vec(2) => "vec2<f32>",
            Ty::Vec(3) => "vec3<f32>",
            _ => "vec4<f32>",
        }
    }
}

impl fmt::Display for Ty {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Ty::AbstractInt => write!(f, "integer"),
            t => write!(f, "{}", t.wgsl()),
        }
    }
}

/// Join two operand types as WGSL does for abstract integers; `None` when they differ.
pub fn unify(a: Ty, b: Ty) -> Option<Ty> {
    match (a, b) {
        _ if a == b => Some(a),
        (Ty::AbstractInt, t @ (Ty::F32 | Ty::I32)) | (t @ (Ty::F32 | Ty::I32), Ty::AbstractInt) => Some(t),
        // scalar * vector broadcasts
        (Ty::Vec(n), Ty::F32 | Ty::AbstractInt) | (Ty::F32 | Ty::AbstractInt, Ty::Vec(n)) => Some(Ty::Vec(n)),
        _ => None,
    }
}

/// Which side of a separable expansion an input belongs to (Annen eq. 5.6: coefficients
/// depend on the receiver, basis functions on the shadow map).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Receiver,
    Map,
    Both,
}

/// Built-in inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Input {
    /// Receiver depth from the light, normalised to [0, 1] between the depth pass's near and far.
    D,
    /// Receiver distance from the light along its view axis, in world units.
    DWorld,
    /// Shadow-map coordinates of the receiver, [0, 1]^2.
    Uv,
    /// Fractional texel position of the receiver, for bilinear weights: fract(uv * size - 0.5).
    Tf,
    /// Cosine between the surface normal and the direction to the light.
    NdotL,
    /// tan of the angle between normal and light, clamped to [0, 100] (slope-scaled bias).
    Slope,
    /// Size of one shadow-map texel in uv units (1 / resolution).
    TexelSize,
    /// World size of one shadow-map texel at the receiver, in normalised depth units
    /// (for slope-scaled bias in texels).
    TexelDepth,
    /// How much the receiver's normalised depth changes over one shadow-map texel, along
    /// its steepest direction: the receiver-plane depth gradient from screen-space
    /// derivatives (Isidoro 2006), clamped to [0, 0.1]. Slope-scaled bias in texels.
    DepthSlope,
    /// Shadow-map resolution in texels.
    ShadowSize,
    /// Near and far planes of the light's depth range, world units.
    Near,
    Far,
    /// Light size in world units (radius of a sphere or disk, half-extent of a rectangle).
    LightSize,
    /// Full width of the light along the shadow map's u and v axes, world units.
    LightWidth,
    /// Angular width of a distant light, `2 tan(angle / 2)`: how much its penumbra widens
    /// per unit of distance between blocker and receiver (Lawlor 2006's distant disk);
    /// 0 for local lights, whose spread is `light_width / d` instead.
    LightSpread,
}

impl Input {
    pub const ALL: [Input; 15] = [
        Input::D,
        Input::DWorld,
        Input::Uv,
        Input::Tf,
        Input::NdotL,
        Input::Slope,
        Input::TexelSize,
        Input::TexelDepth,
        Input::DepthSlope,
        Input::ShadowSize,
        Input::Near,
        Input::Far,
        Input::LightSize,
        Input::LightWidth,
        Input::LightSpread,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Input::D => "d",
            Input::DWorld => "d_world",
            Input::Uv => "uv",
            Input::Tf => "tf",
            Input::NdotL => "ndotl",
            Input::Slope => "slope",
            Input::TexelSize => "texel_size",
            Input::TexelDepth => "texel_depth",
            Input::DepthSlope => "depth_slope",
            Input::ShadowSize => "shadow_size",
            Input::Near => "near",
            Input::Far => "far",
            Input::LightSize => "light_size",
            Input::LightWidth => "light_width",
            Input::LightSpread => "light_spread",
        }
    }

    pub fn from_name(n: &str) -> Option<Input> {
        Input::ALL.into_iter().find(|i| i.name() == n)
    }

    pub fn ty(self) -> Ty {
        match self {
            Input::Uv | Input::Tf | Input::LightWidth => Ty::Vec(2),
            _ => Ty::F32,
        }
    }

    pub fn side(self) -> Side {
        match self {
            Input::TexelSize | Input::ShadowSize | Input::Near | Input::Far | Input::LightSize | Input::LightWidth | Input::LightSpread => {
                Side::Both
            }
            _ => Side::Receiver,
        }
    }

    /// The range range analysis assumes for this input.
    pub fn range(self) -> (f64, f64) {
        match self {
            Input::D | Input::Uv | Input::Tf => (0.0, 1.0),
            Input::NdotL => (-1.0, 1.0),
            Input::Slope => (0.0, 100.0),
            Input::TexelSize => (1.0 / 16384.0, 1.0),
            Input::TexelDepth => (0.0, 1e4),
            Input::DepthSlope => (0.0, 0.1),
            Input::ShadowSize => (1.0, 16384.0),
            Input::DWorld | Input::Near | Input::Far => (0.0, 1e4),
            Input::LightSize => (0.0, 1e4),
            Input::LightWidth => (0.0, 2e4),
            // 2 tan(angle / 2) for an angular diameter below 180 degrees; 4 is 126.9 degrees
            Input::LightSpread => (0.0, 4.0),
        }
    }

    pub fn doc(self) -> &'static str {
        match self {
            Input::D => "receiver depth from the light, normalised to [0, 1] between near and far",
            Input::DWorld => "receiver distance from the light along its view axis (world units)",
            Input::Uv => "shadow-map coordinates of the receiver",
            Input::Tf => "fractional texel position fract(uv * shadow_size - 0.5), for bilinear weights",
            Input::NdotL => "cosine between surface normal and direction to the light",
            Input::Slope => "tan of the angle between normal and light, clamped to [0, 100]",
            Input::TexelSize => "1 / shadow-map resolution",
            Input::TexelDepth => "world size of one shadow-map texel at the receiver, in normalised depth units",
            Input::DepthSlope => {
                "change of the receiver's normalised depth over one shadow-map texel (receiver-plane gradient), clamped to [0, 0.1]"
            }
            Input::ShadowSize => "shadow-map resolution in texels",
            Input::Near => "near plane of the light's depth range (world units)",
            Input::Far => "far plane of the light's depth range (world units)",
            Input::LightSize => "light radius or half-extent (world units)",
            Input::LightWidth => "full width of the light along the shadow map's u and v axes (world units)",
            Input::LightSpread => {
                "angular width 2 tan(angle / 2) of a distant light: penumbra width per unit of blocker-receiver distance; 0 for local lights"
            }
        }
    }
}

/// Named constants.
pub fn constant(name: &str) -> Option<f64> {
    match name {
        "PI" => Some(std::f64::consts::PI),
        "E" => Some(std::f64::consts::E),
        _ => None,
    }
}

/// Pure functions (WGSL built-ins plus `linstep`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Func {
    Abs,
    Exp,
    Exp2,
    Log,
    Log2,
    Sqrt,
    InverseSqrt,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Floor,
    Ceil,
    Fract,
    Round,
    Trunc,
    Sign,
    Saturate,
    Pow,
    Min,
    Max,
    Atan2,
    Step,
    Clamp,
    Mix,
    Smoothstep,
    /// saturate((x - a) / (b - a)); used by VSM light-bleeding reduction.
    Linstep,
    Select,
    ToF32,
    ToI32,
    Vec2,
    Vec3,
    Vec4,
    Length,
    Dot,
    /// `div_or(num, den, eps, fallback)`: num / den where |den| >= eps, else fallback
    /// (guarded division: no infinity or NaN reaches what follows).
    DivOr,
    /// `uv_width(len, dist)`: the shadow-map uv extent of a world length `len` lying across
    /// the light's view at view distance `dist` (perspective or orthographic light).
    UvWidth,
}

impl Func {
    pub const ALL: [Func; 39] = [
        Func::Abs,
        Func::Exp,
        Func::Exp2,
        Func::Log,
        Func::Log2,
        Func::Sqrt,
        Func::InverseSqrt,
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Floor,
        Func::Ceil,
        Func::Fract,
        Func::Round,
        Func::Trunc,
        Func::Sign,
        Func::Saturate,
        Func::Pow,
        Func::Min,
        Func::Max,
        Func::Atan2,
        Func::Step,
        Func::Clamp,
        Func::Mix,
        Func::Smoothstep,
        Func::Linstep,
        Func::Select,
        Func::ToF32,
        Func::ToI32,
        Func::Vec2,
        Func::Vec3,
        Func::Vec4,
        Func::Length,
        Func::Dot,
        Func::DivOr,
        Func::UvWidth,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Abs => "abs",
            Func::Exp => "exp",
            Func::Exp2 => "exp2",
            Func::Log => "log",
            Func::Log2 => "log2",
            Func::Sqrt => "sqrt",
            Func::InverseSqrt => "inverseSqrt",
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Floor => "floor",
            Func::Ceil => "ceil",
            Func::Fract => "fract",
            Func::Round => "round",
            Func::Trunc => "trunc",
            Func::Sign => "sign",
            Func::Saturate => "saturate",
            Func::Pow => "pow",
            Func::Min => "min",
            Func::Max => "max",
            Func::Atan2 => "atan2",
            Func::Step => "step",
            Func::Clamp => "clamp",
            Func::Mix => "mix",
            Func::Smoothstep => "smoothstep",
            Func::Linstep => "linstep",
            Func::Select => "select",
            Func::ToF32 => "f32",
            Func::ToI32 => "i32",
            Func::Vec2 => "vec2",
            Func::Vec3 => "vec3",
            Func::Vec4 => "vec4",
            Func::Length => "length",
            Func::Dot => "dot",
            Func::DivOr => "div_or",
            Func::UvWidth => "uv_width",
        }
    }

    pub fn from_name(n: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == n)
    }

    pub fn arity(self) -> usize {
        match self {
            Func::Pow | Func::Min | Func::Max | Func::Atan2 | Func::Step | Func::Dot | Func::UvWidth => 2,
            Func::DivOr => 4,
            Func::Clamp | Func::Mix | Func::Smoothstep | Func::Linstep | Func::Select => 3,
            Func::Vec2 => 2,
            Func::Vec3 => 3,
            Func::Vec4 => 4,
            _ => 1,
        }
    }

    /// Result type for these argument types, or a message saying what was expected.
    pub fn result(self, args: &[Ty]) -> Result<Ty, String> {
        if args.len() != self.arity() {
            return Err(format!(
                "`{}` takes {} argument(s), found {}",
                self.name(),
                self.arity(),
                args.len()
            ));
        }
        let same = |tys: &[Ty]| -> Option<Ty> { tys.iter().try_fold(tys[0], |acc, t| unify(acc, *t)) };
        match self {
            Func::Abs | Func::Sign => match args[0] {
                t if t.is_numeric() => Ok(t.concrete_or_f32_for(self)),
                t => Err(format!("`{}` expects a number, found {t}", self.name())),
            },
            Func::Min | Func::Max | Func::Clamp => match same(args) {
                Some(t) if t.is_numeric() => Ok(t.concrete()),
                _ => Err(format!(
                    "`{}` expects arguments of one numeric type, found {}",
                    self.name(),
                    list(args)
                )),
            },
            Func::Select => match (unify(args[0], args[1]), args[2]) {
                (Some(t), Ty::Bool) => Ok(t.concrete()),
                (None, _) => Err(format!("`select(f, t, cond)` needs `f` and `t` of one type, found {}", list(args))),
                (_, c) => Err(format!("`select(f, t, cond)` needs a bool condition, found {c}")),
            },
            Func::ToF32 => match args[0] {
                Ty::F32 | Ty::I32 | Ty::Bool | Ty::AbstractInt => Ok(Ty::F32),
                t => Err(format!("`f32` converts a scalar, found {t}")),
            },
            Func::ToI32 => match args[0] {
                Ty::F32 | Ty::I32 | Ty::Bool | Ty::AbstractInt => Ok(Ty::I32),
                t => Err(format!("`i32` converts a scalar, found {t}")),
            },
            Func::Vec2 | Func::Vec3 | Func::Vec4 => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::Vec(self.arity() as u8))
                } else {
                    Err(format!("`{}` takes f32 components, found {}", self.name(), list(args)))
                }
            }
            Func::Length => match args[0] {
                Ty::Vec(_) | Ty::F32 | Ty::AbstractInt => Ok(Ty::F32),
                t => Err(format!("`length` expects a vector, found {t}")),
            },
            Func::Dot => match same(args) {
                Some(Ty::Vec(_)) => Ok(Ty::F32),
                _ => Err(format!("`dot` expects two vectors of one size, found {}", list(args))),
            },
            Func::DivOr | Func::UvWidth => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::F32)
                } else {
                    Err(format!("`{}` takes f32 arguments, found {}", self.name(), list(args)))
                }
            }
            _ => match same(args) {
                Some(t) if t.is_float_like() => Ok(if t == Ty::AbstractInt { Ty::F32 } else { t }),
                _ => Err(format!("`{}` expects f32 or vector arguments, found {}", self.name(), list(args))),
            },
        }
    }
}

impl Ty {
    fn concrete_or_f32_for(self, _f: Func) -> Ty {
        self.concrete()
    }
}

fn list(args: &[Ty]) -> String {
    args.iter().map(|t| format!("`{t}`")).collect::<Vec<_>>().join(", ")
}

/// How a Shade pass reads a channel (DESIGN.md section 2: filtered lookups into channels).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SampleFn {
    /// `sample(ch)`: hardware-filtered (bilinear, trilinear over mips) at `uv`.
    Sample,
    /// `sample_lod(ch, lod)`: filtered at an explicit level of detail.
    SampleLod,
    /// `sample_width(ch, w)`: filtered over a footprint `w` wide in shadow-map uv units,
    /// i.e. at level of detail log2(max(w * shadow_size, 1)).
    SampleWidth,
    /// `nearest(ch)`: the texel containing `uv`, level 0.
    Nearest,
    /// `fetch(ch, dx, dy)`: texel `floor(uv * size - 0.5) + (dx, dy)`, clamped to the edge.
    Fetch,
    /// `nearest_at(ch, du, dv)`: the texel containing `uv + (du, dv)`, level 0, clamped to the edge.
    NearestAt,
    /// `sample_box(ch, wx, wy)`: the mean over a `wx` x `wy` box (shadow-map uv units, at least
    /// one texel each way) centred at `uv`, from a summed-area table.
    Box,
}

impl SampleFn {
    /// Every lookup function of the language.
    pub const NAMES: [&'static str; 14] = [
        "sample",
        "sample_lod",
        "sample_width",
        "nearest",
        "fetch",
        "sample_box",
        "nearest_at",
        "expand",
        "expand_lod",
        "expand_width",
        "expand_nearest",
        "expand_fetch",
        "expand_box",
        "expand_nearest_at",
    ];

    pub fn from_name(n: &str) -> Option<(SampleFn, bool)> {
        Some(match n {
            "sample" => (SampleFn::Sample, false),
            "sample_lod" => (SampleFn::SampleLod, false),
            "sample_width" => (SampleFn::SampleWidth, false),
            "nearest" => (SampleFn::Nearest, false),
            "fetch" => (SampleFn::Fetch, false),
            "sample_box" => (SampleFn::Box, false),
            "nearest_at" => (SampleFn::NearestAt, false),
            "expand_nearest_at" => (SampleFn::NearestAt, true),
            "expand_box" => (SampleFn::Box, true),
            "expand" => (SampleFn::Sample, true),
            "expand_lod" => (SampleFn::SampleLod, true),
            "expand_width" => (SampleFn::SampleWidth, true),
            "expand_nearest" => (SampleFn::Nearest, true),
            "expand_fetch" => (SampleFn::Fetch, true),
            _ => return None,
        })
    }

    /// Arguments after the channel or expansion name.
    pub fn extra_args(self) -> &'static [Ty] {
        match self {
            SampleFn::Sample | SampleFn::Nearest => &[],
            SampleFn::SampleLod | SampleFn::SampleWidth => &[Ty::F32],
            SampleFn::Fetch => &[Ty::I32, Ty::I32],
            SampleFn::Box | SampleFn::NearestAt => &[Ty::F32, Ty::F32],
        }
    }

    pub fn name(self, expand: bool) -> &'static str {
        match (self, expand) {
            (SampleFn::Sample, false) => "sample",
            (SampleFn::SampleLod, false) => "sample_lod",
            (SampleFn::SampleWidth, false) => "sample_width",
            (SampleFn::SampleWidth, true) => "expand_width",
            (SampleFn::Nearest, false) => "nearest",
            (SampleFn::Fetch, false) => "fetch",
            (SampleFn::Sample, true) => "expand",
            (SampleFn::SampleLod, true) => "expand_lod",
            (SampleFn::Nearest, true) => "expand_nearest",
            (SampleFn::Fetch, true) => "expand_fetch",
            (SampleFn::Box, false) => "sample_box",
            (SampleFn::Box, true) => "expand_box",
            (SampleFn::NearestAt, false) => "nearest_at",
            (SampleFn::NearestAt, true) => "expand_nearest_at",
        }
    }
}

/// Every name reserved by the language (declarations may not take them).
pub fn is_reserved(name: &str) -> bool {
    Input::from_name(name).is_some()
        || constant(name).is_some()
        || Func::from_name(name).is_some()
        || SampleFn::from_name(name).is_some()
        || matches!(name, "let" | "sum" | "in" | "true" | "false")
}
