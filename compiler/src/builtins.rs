//! Names the expression language knows without a declaration: receiver- and map-side
//! inputs, constants, WGSL math functions and the sampling functions of a Shade pass.
//! Each function, input and lookup has one descriptor here (`Func::desc`, `Input::desc`,
//! `SampleFn::desc`): its name, type rule, constant folding, range rule and WGSL. check,
//! lower, the arena's folding, analyse and codegen read these descriptors and do not
//! match on the function themselves.

/// The expression language's types live beside the syntax tree that names them.
pub use crate::front::ast::Ty;
use crate::front::ast::{ConstValue, Primitive};
use crate::interval::Interval;
use std::f64::consts::PI;
use std::fmt;

/// The name of the per-sample lookup `at_sample(k, e)` (a Shade pass evaluating `e` in
/// light sample `k`'s view), which check types and lower unrolls.
pub const AT_SAMPLE: &str = "at_sample";

/// Join two operand types as WGSL does for abstract integers; `None` when they differ.
pub fn unify(a: Ty, b: Ty) -> Option<Ty> {
    match (a, b) {
        _ if a == b => Some(a),
        (Ty::AbstractInt, t @ (Ty::F32 | Ty::I32 | Ty::U32)) | (t @ (Ty::F32 | Ty::I32 | Ty::U32), Ty::AbstractInt) => Some(t),
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
    /// Fragments of the primitives a Geometry pass generates: only in the values of the
    /// channels it writes (which may also read map-side channels at the fragment's texel).
    Geometry,
}

/// Built-in inputs. Everything about one input is its [`InputDesc`] (see [`Input::desc`]).
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
    /// Z_F of penumbra maps (Wyman & Hansen 2003, eq. 1): the light-view distance of the
    /// generated primitive's fragment, world units.
    ZFrag,
    /// Z_v: the light-view distance of the silhouette vertex the fragment's cone or sheet
    /// grows from (interpolated along a sheet), world units.
    ZVertex,
    /// The radius of the fragment's cone at its distance, `(Z_F - Z_v) L_r / Z_v`, world units.
    ConeRadius,
    /// Z_P: the light-view distance of the foremost surface the light sees at the
    /// fragment's texel (the Depth resource the Geometry pass reads), world units.
    ZSurface,
    /// 1 for a distant light (orthographic light view), 0 for a local one.
    LightDistant,
    /// c of penumbra limit maps (Lawlor 2006, section 3): the normalised depth of the
    /// silhouette edge point nearest the ribbon fragment.
    OccluderDepth,
    /// p_i of penumbra limit maps (Lawlor 2006, eq. 1 and section 3, `p_i = w s r`): the
    /// fragment's signed distance from the silhouette edge (positive outward) times the
    /// light's depth rate, in normalised depth units.
    PenumbraLimit,
    /// The normalised depth of the penumbra-limit surface at the ribbon fragment (where
    /// the penumbra begins below the edge): the depth its depth test keeps the nearest of.
    LimitDepth,
    /// Inside `at_sample(k, ..)`: the weight of the segment of light before sample k (0
    /// for the first of an open chain; 1 for a lone sample).
    SegmentBefore,
    /// Inside `at_sample(k, ..)`: the weight of the segment after sample k.
    SegmentAfter,
    /// The Gouraud value of a skin fragment (Heidrich et al. 2000, section 3.2): 0 on the
    /// occluder edge, 1 on the receiver, interpolated across the skin.
    Skin,
    /// The camera pixel being shaded, integer coordinates from the top-left as floats.
    Pixel,
    /// Frames run since the scene was bound (0, 1, 2, ...).
    Frame,
}

/// Everything the compiler knows about one built-in input: check reads its name, type and
/// side, analyse its range, codegen its WGSL, `rounding` its typical value, `interp` the
/// error the GPU may leave in it.
#[derive(Debug)]
pub struct InputDesc {
    pub name: &'static str,
    pub ty: Ty,
    pub side: Side,
    /// The range range analysis assumes.
    pub range: (f64, f64),
    /// The WGSL expression for it. Receiver-side inputs are the `in_*` locals the Shade
    /// module computes before the visibility; the others read the `Frame` uniform.
    pub wgsl: &'static str,
    /// The value it takes in a typical configuration (a 512^2 map over depths 1 to 11 in
    /// world units, a receiver facing the light, no slope, the centre of a texel), where
    /// `rounding` estimates the visibility's sensitivity to storage rounding.
    pub typical: f64,
    /// What the GPU's f32 transforms may leave in it (`interp::input_error`).
    pub error: InputError,
    /// How it is seen from a light sample's view inside `at_sample(k, ..)`.
    pub view: InView,
    pub doc: &'static str,
}

/// How an input is seen from light sample `k`'s view (inside `at_sample(k, ..)`).
#[derive(Clone, Copy, Debug)]
pub enum InView {
    /// The same in every view: the frame's, the pixel's, or a Geometry fragment's.
    Same,
    /// Computed again in each view: the WGSL lines (`{k}` the sample) defining
    /// `<wgsl>_v{k}` from `sv{k} = light_samples.views[k]`, `world` and `n`, after those of
    /// the inputs it needs.
    Own {
        needs: &'static [Input],
        wgsl: &'static [&'static str],
    },
    /// Exists only in a view, inside `at_sample` (the sample's segment weights): its lines.
    OnlyThere(&'static [&'static str]),
}

/// What the f32 transforms of a receiver's position leave in the inputs computed from it,
/// 2^-20 (absolute for the normalised ones, relative for the others).
const TRANSFORM_ERROR: f64 = 1.0 / 1048576.0;

/// What the GPU's f32 transforms may leave in an input, for `interp`'s error bounds.
#[derive(Clone, Copy, Debug)]
pub enum InputError {
    /// Nothing: a uniform's value, or one computed exactly.
    Exact,
    /// At most this much.
    Absolute(f64),
    /// At most this fraction of its magnitude.
    Relative(f64),
    /// `2 tan(angle / 2)` computed in f32: `tan`'s accuracy, twice (nothing where it is 0;
    /// docs/language.md section 8.5).
    TanHalfAngle,
}

impl Input {
    pub const ALL: [Input; 28] = [
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
        Input::ZFrag,
        Input::ZVertex,
        Input::ConeRadius,
        Input::ZSurface,
        Input::LightDistant,
        Input::OccluderDepth,
        Input::PenumbraLimit,
        Input::LimitDepth,
        Input::SegmentBefore,
        Input::SegmentAfter,
        Input::Skin,
        Input::Pixel,
        Input::Frame,
    ];

    /// The Geometry primitives whose fragments have this input (every one for the others).
    pub fn primitives(self) -> &'static [Primitive] {
        match self {
            Input::ZFrag => &[Primitive::ConesAndSheets, Primitive::BackFaces, Primitive::Skins],
            Input::Skin => &[Primitive::Skins],
            Input::ZVertex | Input::ConeRadius | Input::ZSurface => &[Primitive::ConesAndSheets],
            Input::OccluderDepth | Input::PenumbraLimit | Input::LimitDepth => &[Primitive::Ribbons],
            Input::D
            | Input::DWorld
            | Input::Uv
            | Input::Tf
            | Input::NdotL
            | Input::Slope
            | Input::TexelSize
            | Input::TexelDepth
            | Input::DepthSlope
            | Input::ShadowSize
            | Input::Near
            | Input::Far
            | Input::LightSize
            | Input::LightWidth
            | Input::LightSpread
            | Input::SegmentBefore
            | Input::SegmentAfter
            | Input::Pixel
            | Input::Frame
            | Input::LightDistant => &[
                Primitive::ConesAndSheets,
                Primitive::Ribbons,
                Primitive::Skins,
                Primitive::BackFaces,
            ],
        }
    }

    /// The descriptor: adding an input means adding a variant, its entry in
    /// [`Input::ALL`] and its arm here (and its `in_*` local in the Shade prelude of
    /// `back/shade.rs` when it is receiver-side).
    pub fn desc(self) -> &'static InputDesc {
        use Side::{Both, Geometry, Receiver};
        match self {
            Input::D => &InputDesc {
                name: "d",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 1.0),
                wgsl: "in_d",
                typical: 0.5,
                error: InputError::Absolute(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[Input::DWorld],
                    wgsl: &["let in_d_v{k} = (in_d_world_v{k} - sv{k}.depth_range.x) * sv{k}.depth_range.z;"],
                },
                doc: "receiver depth from the light, normalised to [0, 1] between near and far",
            },
            Input::DWorld => &InputDesc {
                name: "d_world",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 1e4),
                wgsl: "in_d_world",
                typical: 6.0,
                error: InputError::Relative(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[],
                    wgsl: &["let in_d_world_v{k} = -(sv{k}.view * world).z;"],
                },
                doc: "receiver distance from the light along its view axis (world units)",
            },
            Input::Uv => &InputDesc {
                name: "uv",
                ty: Ty::Vec(2),
                side: Receiver,
                range: (0.0, 1.0),
                wgsl: "in_uv",
                typical: 0.5,
                error: InputError::Absolute(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[],
                    wgsl: &[
                        "let light_clip_v{k} = sv{k}.view_proj * world;",
                        "let in_uv_v{k} = light_clip_v{k}.xy / light_clip_v{k}.w * vec2<f32>(0.5, -0.5) + vec2<f32>(0.5);",
                    ],
                },
                doc: "shadow-map coordinates of the receiver",
            },
            Input::Tf => &InputDesc {
                name: "tf",
                ty: Ty::Vec(2),
                side: Receiver,
                range: (0.0, 1.0),
                wgsl: "in_tf",
                typical: 0.5,
                error: InputError::Absolute(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[Input::Uv],
                    wgsl: &["let in_tf_v{k} = fract(in_uv_v{k} * frame.shadow_size.xy - 0.5);"],
                },
                doc: "fractional texel position fract(uv * shadow_size - 0.5), for bilinear weights",
            },
            Input::NdotL => &InputDesc {
                name: "ndotl",
                ty: Ty::F32,
                side: Receiver,
                range: (-1.0, 1.0),
                wgsl: "in_ndotl",
                typical: 1.0,
                error: InputError::Relative(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[],
                    wgsl: &["let in_ndotl_v{k} = dot(n, normalize(sv{k}.position.xyz - in.world));"],
                },
                doc: "cosine between surface normal and direction to the light",
            },
            Input::Slope => &InputDesc {
                name: "slope",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 100.0),
                wgsl: "in_slope",
                typical: 0.0,
                error: InputError::Relative(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[Input::NdotL],
                    wgsl: &[
                        "let in_slope_v{k} = min(sqrt(max(1.0 - in_ndotl_v{k} * in_ndotl_v{k}, 0.0)) / max(abs(in_ndotl_v{k}), 0.01), 100.0);",
                    ],
                },
                doc: "tan of the angle between normal and light, clamped to [0, 100]",
            },
            Input::TexelSize => &InputDesc {
                name: "texel_size",
                ty: Ty::F32,
                side: Both,
                range: (1.0 / 16384.0, 1.0),
                wgsl: "frame.shadow_size.z",
                typical: 1.0 / 512.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "1 / shadow-map resolution",
            },
            Input::TexelDepth => &InputDesc {
                name: "texel_depth",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 1e4),
                wgsl: "in_texel_depth",
                typical: 0.0,
                error: InputError::Relative(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[Input::DWorld],
                    wgsl: &["let in_texel_depth_v{k} = sv{k}.weights.z * in_d_world_v{k} * sv{k}.depth_range.z;"],
                },
                doc: "world size of one shadow-map texel at the receiver, in normalised depth units",
            },
            Input::DepthSlope => &InputDesc {
                name: "depth_slope",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 0.1),
                wgsl: "in_depth_slope",
                typical: 0.0,
                error: InputError::Relative(TRANSFORM_ERROR),
                view: InView::Own {
                    needs: &[Input::Uv, Input::D],
                    wgsl: &[
                        "let duv_dx_v{k} = dpdx(in_uv_v{k});",
                        "let duv_dy_v{k} = dpdy(in_uv_v{k});",
                        "let dd_dx_v{k} = dpdx(in_d_v{k});",
                        "let dd_dy_v{k} = dpdy(in_d_v{k});",
                        "let det_v{k} = duv_dx_v{k}.x * duv_dy_v{k}.y - duv_dx_v{k}.y * duv_dy_v{k}.x;",
                        "let g_v{k} = vec2<f32>(dd_dx_v{k} * duv_dy_v{k}.y - duv_dx_v{k}.y * dd_dy_v{k}, duv_dx_v{k}.x * dd_dy_v{k} - dd_dx_v{k} * duv_dy_v{k}.x);",
                        "let in_depth_slope_v{k} = select(0.0, min(length(g_v{k} / det_v{k}) * frame.shadow_size.z, 0.1), abs(det_v{k}) > 1e-14);",
                    ],
                },
                doc: "change of the receiver's normalised depth over one shadow-map texel (receiver-plane gradient), clamped to [0, 0.1]",
            },
            Input::ShadowSize => &InputDesc {
                name: "shadow_size",
                ty: Ty::F32,
                side: Both,
                range: (1.0, 16384.0),
                wgsl: "frame.shadow_size.x",
                typical: 512.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "shadow-map resolution in texels",
            },
            Input::Near => &InputDesc {
                name: "near",
                ty: Ty::F32,
                side: Both,
                range: (0.0, 1e4),
                wgsl: "frame.depth_range.x",
                typical: 1.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "near plane of the light's depth range (world units)",
            },
            Input::Far => &InputDesc {
                name: "far",
                ty: Ty::F32,
                side: Both,
                range: (0.0, 1e4),
                wgsl: "frame.depth_range.y",
                typical: 11.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "far plane of the light's depth range (world units)",
            },
            Input::LightSize => &InputDesc {
                name: "light_size",
                ty: Ty::F32,
                side: Both,
                range: (0.0, 1e4),
                wgsl: "frame.light_size.x",
                typical: 0.25,
                error: InputError::Exact,
                view: InView::Same,
                doc: "light radius or half-extent (world units)",
            },
            Input::LightWidth => &InputDesc {
                name: "light_width",
                ty: Ty::Vec(2),
                side: Both,
                range: (0.0, 2e4),
                wgsl: "(frame.light_size.zw * 2.0)",
                typical: 0.5,
                error: InputError::Exact,
                view: InView::Same,
                doc: "full width of the light along the shadow map's u and v axes (world units)",
            },
            Input::LightSpread => &InputDesc {
                name: "light_spread",
                ty: Ty::F32,
                side: Both,
                // 2 tan(angle / 2) for an angular diameter below 180 degrees; 4 is 126.9 degrees
                range: (0.0, 4.0),
                wgsl: "(2.0 * tan(0.5 * frame.light_size.y))",
                typical: 0.0,
                error: InputError::TanHalfAngle,
                view: InView::Same,
                doc: "angular width 2 tan(angle / 2) of a distant light: penumbra width per unit of blocker-receiver distance; 0 for local lights",
            },
            Input::ZFrag => &InputDesc {
                name: "z_frag",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1e4),
                wgsl: "in_z_frag",
                typical: 6.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "light-view distance of the generated primitive's fragment (Z_F of Wyman & Hansen eq. 1, world units)",
            },
            Input::ZVertex => &InputDesc {
                name: "z_vertex",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1e4),
                wgsl: "in_z_vertex",
                typical: 6.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "light-view distance of the fragment's silhouette vertex (Z_v, interpolated along a sheet; world units)",
            },
            Input::ConeRadius => &InputDesc {
                name: "cone_radius",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1e4),
                wgsl: "in_cone_radius",
                typical: 0.1,
                error: InputError::Exact,
                view: InView::Same,
                doc: "radius of the fragment's cone at its distance, (Z_F - Z_v) L_r / Z_v (world units)",
            },
            Input::ZSurface => &InputDesc {
                name: "z_surface",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1e4),
                wgsl: "in_z_surface",
                typical: 6.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "light-view distance of the foremost surface the light sees at the fragment's texel (Z_P of Wyman & Hansen eq. 1, world units)",
            },
            Input::LightDistant => &InputDesc {
                name: "light_distant",
                ty: Ty::F32,
                side: Both,
                range: (0.0, 1.0),
                wgsl: "select(0.0, 1.0, frame.light_position.w == 0.0)",
                typical: 0.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "1 for a distant light (orthographic light view), 0 for a local one",
            },
            Input::OccluderDepth => &InputDesc {
                name: "occluder_depth",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1.0),
                wgsl: "in_occluder_depth",
                typical: 0.5,
                error: InputError::Exact,
                view: InView::Same,
                doc: "c of penumbra limit maps (Lawlor 2006, section 3): normalised depth of the silhouette edge point nearest the ribbon fragment",
            },
            Input::PenumbraLimit => &InputDesc {
                name: "penumbra_limit",
                ty: Ty::F32,
                side: Geometry,
                range: (-1e4, 1e4),
                wgsl: "in_penumbra_limit",
                typical: 0.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "p_i of penumbra limit maps (Lawlor 2006, eq. 1, p_i = w s r): signed distance from the silhouette edge (positive outward) times the light's depth rate, normalised depth units",
            },
            Input::LimitDepth => &InputDesc {
                name: "limit_depth",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1.0),
                wgsl: "in_limit_depth",
                typical: 0.5,
                error: InputError::Exact,
                view: InView::Same,
                doc: "normalised depth of the penumbra-limit surface at the ribbon fragment (the depth Nearest keeps the smallest of)",
            },
            Input::SegmentBefore => &InputDesc {
                name: "segment_before",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 1.0),
                wgsl: "in_segment_before",
                typical: 1.0,
                error: InputError::Exact,
                view: InView::OnlyThere(&["let in_segment_before_v{k} = sv{k}.weights.x;"]),
                doc: "inside at_sample(k, ..): weight of the light segment before sample k (its share of the light; 0 for the first sample of an open chain, 1 for a lone sample)",
            },
            Input::SegmentAfter => &InputDesc {
                name: "segment_after",
                ty: Ty::F32,
                side: Receiver,
                range: (0.0, 1.0),
                wgsl: "in_segment_after",
                typical: 1.0,
                error: InputError::Exact,
                view: InView::OnlyThere(&["let in_segment_after_v{k} = sv{k}.weights.y;"]),
                doc: "inside at_sample(k, ..): weight of the light segment after sample k (0 for the last sample of an open chain, 1 for a lone sample)",
            },
            Input::Pixel => &InputDesc {
                name: "pixel",
                ty: Ty::Vec(2),
                side: Receiver,
                range: (0.0, 16384.0),
                wgsl: "in_pixel",
                typical: 0.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "the camera pixel being shaded: integer coordinates (x, y) from the top-left, as floats",
            },
            Input::Frame => &InputDesc {
                name: "frame",
                ty: Ty::I32,
                side: Both,
                range: (0.0, 16777216.0),
                wgsl: "i32(frame.counters.x)",
                typical: 0.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "frames run since the scene was bound: 0, 1, 2, ... (for noise that changes from frame to frame)",
            },
            Input::Skin => &InputDesc {
                name: "skin",
                ty: Ty::F32,
                side: Geometry,
                range: (0.0, 1.0),
                wgsl: "in_skin",
                typical: 1.0,
                error: InputError::Exact,
                view: InView::Same,
                doc: "Skins only: the skin's Gouraud value, 0 on the occluder edge and 1 on the receiver (Heidrich et al. 2000, section 3.2)",
            },
        }
    }

    /// Inputs that exist only for one light sample (inside `at_sample`).
    pub fn per_sample(self) -> bool {
        match self.desc().view {
            InView::OnlyThere(_) => true,
            InView::Same | InView::Own { .. } => false,
        }
    }

    pub fn name(self) -> &'static str {
        self.desc().name
    }

    pub fn from_name(n: &str) -> Option<Input> {
        Input::ALL.into_iter().find(|i| i.name() == n)
    }

    pub fn ty(self) -> Ty {
        self.desc().ty
    }

    pub fn side(self) -> Side {
        self.desc().side
    }

    /// The range range analysis assumes for this input.
    pub fn range(self) -> (f64, f64) {
        self.desc().range
    }

    pub fn doc(self) -> &'static str {
        self.desc().doc
    }
}

/// The error of the two exponentials WGSL's `sinh` and `cosh` are specified through
/// (accuracy inherited from `(exp(x) -+ exp(-x)) / 2`): `exp`'s bound, (3 + 2 |x| log2 e)
/// ulp, at the larger of the two, e^|x|.
fn hyperbolic_error(x: f64) -> f64 {
    (3.0 + 2.0 * (x * std::f64::consts::LOG2_E).abs()) * ulp(x.abs().exp())
}

/// Named constants.
pub fn constant(name: &str) -> Option<f64> {
    match name {
        "PI" => Some(std::f64::consts::PI),
        "E" => Some(std::f64::consts::E),
        _ => None,
    }
}

/// Pure functions (WGSL built-ins plus `linstep`, `div_or`, `uv_width`). Everything about
/// one function is its [`Builtin`] descriptor (see [`Func::desc`]).
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
    /// Hyperbolic functions (WGSL `sinh`, `cosh`, `tanh`): exponential soft shadow
    /// mapping's warps written once (issue 51).
    Sinh,
    Cosh,
    Tanh,
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
    ToU32,
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
    /// `noise(x, y, k)`: a stated hash of the integers floor(x), floor(y), floor(k) to a
    /// float uniform in [0, 1) (PCG3D: Jarzynski & Olano 2020, "Hash functions for GPU
    /// rendering"), for per-pixel and per-frame random numbers: `noise(pixel.x, pixel.y,
    /// f32(frame))`.
    Noise,
    /// `if c { t } else { f }` (arguments `f`, `t`, `c`, as `select`): a real branch,
    /// whose arms the code generator emits inside an `if` (`back::expr`); evaluated,
    /// folded and bounded as `select`. Not callable by name: the parser reads `if`.
    Branch,
}

/// The WGSL of [`Func::Noise`], added to a module whose code calls it: PCG3D
/// (Jarzynski & Olano 2020, "Hash functions for GPU rendering", section 2) on the three
/// integers, the top 24 bits of the first word as a float in [0, 1).
pub const NOISE_WGSL: &str = "
fn sshc_noise(x: f32, y: f32, k: f32) -> f32 {
    var v = vec3<u32>(vec3<i32>(floor(vec3<f32>(x, y, k))));
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v ^= v >> vec3<u32>(16u);
    v.x += v.y * v.z;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    return f32(v.x >> 8u) * (1.0 / 16777216.0);
}
";

/// Everything the compiler knows about one built-in function. check types a call with
/// [`Builtin::sig`], lower coerces its arguments with it, the arena folds it with
/// [`Builtin::fold`] (through [`fold_call`]), analyse bounds it with [`Builtin::range`], codegen
/// writes it with [`Builtin::wgsl`], `interp` bounds its GPU error with [`Builtin::accuracy`].
pub struct Builtin {
    pub name: &'static str,
    pub arity: usize,
    pub sig: Sig,
    pub fold: Fold,
    /// The range of the result given the ranges of the arguments (interval analysis).
    pub range: fn(&[Interval]) -> Interval,
    pub wgsl: Wgsl,
    /// WGSL's accuracy of the function (what `interp::call_error` bounds a call with).
    pub accuracy: Accuracy,
}

/// WGSL's accuracy of a built-in function: how far the GPU's result may lie from the exact
/// value, beyond the f32 rounding of the result.
#[derive(Clone, Copy, Debug)]
pub enum Accuracy {
    /// Exact: one of its arguments, or an exact function of them.
    Exact,
    /// Rounded once, as any arithmetic result.
    Rounded,
    /// The error beyond the result's rounding, given the result's value and the arguments.
    Bound(fn(f64, &[f64]) -> f64),
}

/// One f32 ulp of `v` (relative 2^-23).
fn ulp(v: f64) -> f64 {
    v.abs() * 2f64.powi(-23)
}

/// Argument `i` of a call, 0 where it has none.
fn arg(x: &[f64], i: usize) -> f64 {
    x.get(i).copied().unwrap_or(0.0)
}

/// The typing rule of a function: which argument types it takes and what it returns,
/// with WGSL's rules for abstract integer literals and vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sig {
    /// f32 or vector arguments of one type (abstract integers become f32); the result
    /// has that type. Component-wise on vectors.
    Float,
    /// One number of any type (`abs`, `sign`); the result has its type and an abstract
    /// integer stays abstract.
    Numeric,
    /// Arguments of one numeric type (`min`, `max`, `clamp`); the result has that type
    /// and abstract integers stay abstract.
    SameNumeric,
    /// `select(f, t, cond)`: `f` and `t` of one type, `cond` a bool.
    Select,
    /// A conversion of a scalar (`f32`, `i32` or `bool`) to this type.
    Convert(Ty),
    /// A vector of this many f32 components.
    Construct(u8),
    /// f32 scalars only; the result is f32.
    Scalars,
    /// `length`: one vector (or f32); the result is f32.
    Length,
    /// `dot`: two vectors of one size; the result is f32.
    Dot,
    /// `div_or(num, den, eps, fallback)`: `num` and `den` f32 or vectors of one size, the
    /// result their type; `eps` and `fallback` that type or f32, which lowering splats.
    Guarded,
}

/// `select(f, t, c)` and `if c { t } else { f }` on constants: the operand the condition
/// picks.
fn pick(v: &[ConstValue]) -> Option<ConstValue> {
    match v[2] {
        ConstValue::Bool(true) => Some(v[1]),
        ConstValue::Bool(false) => Some(v[0]),
        ConstValue::Int(_) | ConstValue::Uint(_) | ConstValue::Float(_) => None,
    }
}

/// How a call on constants is evaluated at compile time.
#[derive(Clone, Copy)]
pub enum Fold {
    /// Never folded.
    Never,
    /// Never folded; the evaluators' leaf hook gives its value (`interp`): it reads the
    /// frame (`uv_width`), or is the GPU's integer hash (`noise`).
    Hook,
    /// On the arguments as f64 (integers converted; booleans are not folded), the result
    /// rounded to f32; `None` or a result that is not finite is not folded.
    Float(fn(&[f64]) -> Option<f64>),
    /// Integer arithmetic when every argument is an integer, else as [`Fold::Float`].
    IntOrFloat(fn(&[i64]) -> Option<i64>, fn(&[f64]) -> Option<f64>),
    /// Any other rule, on the constants as they are.
    Custom(fn(&[ConstValue]) -> Option<ConstValue>),
}

/// How a call is written in WGSL, given the WGSL expressions of its arguments.
#[derive(Clone, Copy)]
pub enum Wgsl {
    /// `name(args)`: the WGSL built-in of the same name.
    Same,
    /// `callee(args)` with another callee (a type constructor such as `vec2<f32>`).
    Callee(&'static str),
    /// Any other expression of the arguments.
    Expr(fn(&[String]) -> String),
    /// An expression of the arguments that depends on the result's type.
    Typed(fn(&[String], Ty) -> String),
}

impl fmt::Debug for Builtin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Builtin")
            .field("name", &self.name)
            .field("arity", &self.arity)
            .field("sig", &self.sig)
            .finish_non_exhaustive()
    }
}

impl Func {
    /// The WGSL of a call of this function on `args` (WGSL expressions), as its
    /// descriptor says: the same name, another callee, or an expression of its own.
    /// `ty` is the call's result type.
    pub fn wgsl_call(self, args: &[String], ty: Ty) -> String {
        let d = self.desc();
        match d.wgsl {
            Wgsl::Same => format!("{}({})", d.name, args.join(", ")),
            Wgsl::Callee(callee) => format!("{callee}({})", args.join(", ")),
            Wgsl::Expr(write) => write(args),
            Wgsl::Typed(write) => write(args, ty),
        }
    }

    pub const ALL: [Func; 45] = [
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
        Func::Sinh,
        Func::Cosh,
        Func::Tanh,
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
        Func::ToU32,
        Func::Vec2,
        Func::Vec3,
        Func::Vec4,
        Func::Length,
        Func::Dot,
        Func::DivOr,
        Func::UvWidth,
        Func::Noise,
        Func::Branch,
    ];

    /// The descriptor: adding a function means adding a variant, its entry in
    /// [`Func::ALL`] and its arm here.
    pub fn desc(self) -> &'static Builtin {
        use Accuracy::{Bound, Exact, Rounded};
        use Fold::{Custom, Float, Hook, IntOrFloat, Never};
        use Sig::{Construct, Convert, Dot, Length, Numeric, SameNumeric, Scalars};
        use Wgsl::{Callee, Expr, Same, Typed};
        match self {
            Func::Abs => &Builtin {
                name: "abs",
                arity: 1,
                sig: Numeric,
                fold: IntOrFloat(|a| a[0].checked_abs(), |x| Some(x[0].abs())),
                range: |v| {
                    let x = v[0];
                    if x.lo >= 0.0 {
                        x
                    } else if x.hi <= 0.0 {
                        Interval { lo: -x.hi, hi: -x.lo }
                    } else {
                        Interval {
                            lo: 0.0,
                            hi: x.magnitude(),
                        }
                    }
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Exp => &Builtin {
                name: "exp",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].exp())),
                range: |v| v[0].monotone(f64::exp),
                wgsl: Same,
                accuracy: Bound(|v, x| (3.0 + 2.0 * (arg(x, 0) * std::f64::consts::LOG2_E).abs()) * ulp(v)),
            },
            Func::Exp2 => &Builtin {
                name: "exp2",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].exp2())),
                range: |v| v[0].monotone(f64::exp2),
                wgsl: Same,
                accuracy: Bound(|v, x| (3.0 + 2.0 * arg(x, 0).abs()) * ulp(v)),
            },
            Func::Log => &Builtin {
                name: "log",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| x[0].ln())),
                range: |v| v[0].monotone(|t| if t <= 0.0 { f64::NEG_INFINITY } else { t.ln() }),
                wgsl: Same,
                accuracy: Bound(|v, _| (3.0 * ulp(v)).max(2f64.powi(-21))),
            },
            Func::Log2 => &Builtin {
                name: "log2",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| x[0].log2())),
                range: |v| v[0].monotone(|t| if t <= 0.0 { f64::NEG_INFINITY } else { t.log2() }),
                wgsl: Same,
                accuracy: Bound(|v, _| (3.0 * ulp(v)).max(2f64.powi(-21))),
            },
            Func::Sqrt => &Builtin {
                name: "sqrt",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] >= 0.0).then(|| x[0].sqrt())),
                range: |v| v[0].monotone(|t| t.max(0.0).sqrt()),
                wgsl: Same,
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::InverseSqrt => &Builtin {
                name: "inverseSqrt",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0] > 0.0).then(|| 1.0 / x[0].sqrt())),
                range: |v| {
                    let x = v[0];
                    if x.lo <= 0.0 {
                        Interval {
                            lo: if x.hi > 0.0 { 1.0 / x.hi.sqrt() } else { 0.0 },
                            hi: f64::INFINITY,
                        }
                    } else {
                        x.monotone(|t| 1.0 / t.sqrt())
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::Sin => &Builtin {
                name: "sin",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].sin())),
                range: |v| trig(v[0], 0.0),
                wgsl: Same,
                accuracy: Bound(|_, x| 2f64.powi(-11) + arg(x, 0).abs() * 2f64.powi(-22)),
            },
            Func::Cos => &Builtin {
                name: "cos",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].cos())),
                range: |v| trig(v[0], PI / 2.0),
                wgsl: Same,
                accuracy: Bound(|_, x| 2f64.powi(-11) + arg(x, 0).abs() * 2f64.powi(-22)),
            },
            Func::Tan => &Builtin {
                name: "tan",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].tan())),
                range: |v| {
                    let x = v[0];
                    if x.is_finite() && (x.hi - x.lo) < PI && (x.lo / PI + 0.5).floor() == (x.hi / PI + 0.5).floor() {
                        x.monotone(f64::tan)
                    } else {
                        Interval::UNBOUNDED
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 2f64.powi(-11) * (1.0 + v * v)),
            },
            // WGSL: accuracy "inherited from" (exp(x) - exp(-x)) / 2, (exp(x) + exp(-x)) / 2
            // and sinh(x) / cosh(x): two exps of |x| (exp's bound at e^|x|), the sum's and the
            // halving's rounding; tanh divides that by cosh (at least 1)
            Func::Sinh => &Builtin {
                name: "sinh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].sinh())),
                range: |v| v[0].monotone(f64::sinh),
                wgsl: Same,
                accuracy: Bound(|v, x| hyperbolic_error(arg(x, 0)) + 2.0 * ulp(v)),
            },
            Func::Cosh => &Builtin {
                name: "cosh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].cosh())),
                // even, least (1) at 0
                range: |v| {
                    let x = v[0];
                    let hi = x.lo.cosh().max(x.hi.cosh());
                    let lo = if x.lo <= 0.0 && x.hi >= 0.0 {
                        1.0
                    } else {
                        x.lo.cosh().min(x.hi.cosh())
                    };
                    Interval { lo, hi }
                },
                wgsl: Same,
                accuracy: Bound(|v, x| hyperbolic_error(arg(x, 0)) + 2.0 * ulp(v)),
            },
            Func::Tanh => &Builtin {
                name: "tanh",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].tanh())),
                range: |v| v[0].monotone(f64::tanh),
                wgsl: Same,
                accuracy: Bound(|v, x| 2.0 * hyperbolic_error(arg(x, 0)) / arg(x, 0).cosh().max(1.0) + 2.5 * ulp(v)),
            },
            Func::Asin => &Builtin {
                name: "asin",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0].abs() <= 1.0).then(|| x[0].asin())),
                range: |v| {
                    Interval {
                        lo: v[0].lo.max(-1.0),
                        hi: v[0].hi.min(1.0),
                    }
                    .monotone(f64::asin)
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Acos => &Builtin {
                name: "acos",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| (x[0].abs() <= 1.0).then(|| x[0].acos())),
                range: |v| {
                    Interval {
                        lo: v[0].lo.max(-1.0),
                        hi: v[0].hi.min(1.0),
                    }
                    .monotone(f64::acos)
                },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Atan => &Builtin {
                name: "atan",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].atan())),
                range: |v| v[0].monotone(f64::atan),
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Floor => &Builtin {
                name: "floor",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].floor())),
                range: |v| v[0].monotone(f64::floor),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Ceil => &Builtin {
                name: "ceil",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].ceil())),
                range: |v| v[0].monotone(f64::ceil),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Fract => &Builtin {
                name: "fract",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0] - x[0].floor())),
                range: |_| Interval { lo: 0.0, hi: 1.0 },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Round => &Builtin {
                name: "round",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(round_half_even(x[0]))),
                range: |v| v[0].monotone(round_half_even),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Trunc => &Builtin {
                name: "trunc",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].trunc())),
                range: |v| v[0].monotone(f64::trunc),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Sign => &Builtin {
                name: "sign",
                arity: 1,
                sig: Numeric,
                fold: IntOrFloat(|a| Some(a[0].signum()), |x| Some(x[0].signum() * (x[0] != 0.0) as i32 as f64)),
                range: |v| v[0].monotone(sign),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Saturate => &Builtin {
                name: "saturate",
                arity: 1,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].clamp(0.0, 1.0))),
                range: |v| Interval {
                    lo: v[0].lo.clamp(0.0, 1.0),
                    hi: v[0].hi.clamp(0.0, 1.0),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Pow => &Builtin {
                name: "pow",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| (x[0] >= 0.0).then(|| x[0].powf(x[1]))),
                range: |v| {
                    let (b, e) = (v[0], v[1]);
                    if b.lo >= 0.0 && b.is_finite() && e.is_finite() {
                        let corners = [b.lo.powf(e.lo), b.lo.powf(e.hi), b.hi.powf(e.lo), b.hi.powf(e.hi)];
                        let mut r = Interval::of(&corners);
                        if b.lo <= 1.0 && b.hi >= 1.0 {
                            r = Interval::hull(r, Interval::point(1.0));
                        }
                        r
                    } else {
                        Interval::UNBOUNDED
                    }
                },
                wgsl: Same,
                accuracy: Bound(|v, x| {
                    let y = arg(x, 1);
                    let e = y * arg(x, 0).abs().log2();
                    (3.0 + 2.0 * e.abs()) * ulp(v) + v.abs() * std::f64::consts::LN_2 * y.abs() * 2f64.powi(-21)
                }),
            },
            Func::Min => &Builtin {
                name: "min",
                arity: 2,
                sig: SameNumeric,
                fold: IntOrFloat(|a| Some(a[0].min(a[1])), |x| Some(x[0].min(x[1]))),
                range: |v| Interval {
                    lo: v[0].lo.min(v[1].lo),
                    hi: v[0].hi.min(v[1].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Max => &Builtin {
                name: "max",
                arity: 2,
                sig: SameNumeric,
                fold: IntOrFloat(|a| Some(a[0].max(a[1])), |x| Some(x[0].max(x[1]))),
                range: |v| Interval {
                    lo: v[0].lo.max(v[1].lo),
                    hi: v[0].hi.max(v[1].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Atan2 => &Builtin {
                name: "atan2",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0].atan2(x[1]))),
                range: |_| Interval { lo: -PI, hi: PI },
                wgsl: Same,
                accuracy: Bound(|v, _| 4096.0 * ulp(v) + 2f64.powi(-22)),
            },
            Func::Step => &Builtin {
                name: "step",
                arity: 2,
                sig: Sig::Float,
                fold: Float(|x| Some(if x[1] >= x[0] { 1.0 } else { 0.0 })),
                range: |_| Interval::UNIT,
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Clamp => &Builtin {
                name: "clamp",
                arity: 3,
                sig: SameNumeric,
                fold: IntOrFloat(
                    |a| Some(a[0].max(a[1]).min(a[2])),
                    |x| (x[1] <= x[2]).then(|| x[0].max(x[1]).min(x[2])),
                ),
                // min(max(x, lo), hi) grows with each argument
                range: |v| Interval {
                    lo: v[0].lo.max(v[1].lo).min(v[2].lo),
                    hi: v[0].hi.max(v[1].hi).min(v[2].hi),
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Mix => &Builtin {
                name: "mix",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| Some(x[0] * (1.0 - x[2]) + x[1] * x[2])),
                range: |v| {
                    let (a, b, t) = (v[0], v[1], v[2]);
                    let mut vals = Vec::new();
                    for ta in [t.lo, t.hi] {
                        for av in [a.lo, a.hi] {
                            for bv in [b.lo, b.hi] {
                                vals.push(av * (1.0 - ta) + bv * ta);
                            }
                        }
                    }
                    Interval::of(&vals)
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::Smoothstep => &Builtin {
                name: "smoothstep",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| {
                    (x[0] != x[1]).then(|| {
                        let t = ((x[2] - x[0]) / (x[1] - x[0])).clamp(0.0, 1.0);
                        t * t * (3.0 - 2.0 * t)
                    })
                }),
                range: |_| Interval::UNIT,
                wgsl: Same,
                accuracy: Bound(|v, _| 4.0 * ulp(v)),
            },
            Func::Linstep => &Builtin {
                name: "linstep",
                arity: 3,
                sig: Sig::Float,
                fold: Float(|x| (x[0] != x[1]).then(|| ((x[2] - x[0]) / (x[1] - x[0])).clamp(0.0, 1.0))),
                range: |_| Interval::UNIT,
                wgsl: Expr(|v| format!("saturate(({} - {}) / ({} - {}))", v[2], v[0], v[1], v[0])),
                accuracy: Bound(|v, _| 4.0 * ulp(v)),
            },
            Func::Select => &Builtin {
                name: "select",
                arity: 3,
                sig: Sig::Select,
                // the arena also folds a select with a constant condition and other operands
                fold: Custom(pick),
                range: |v| Interval::hull(v[0], v[1]),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::ToF32 => &Builtin {
                name: "f32",
                arity: 1,
                sig: Convert(Ty::F32),
                fold: Custom(|v| match v[0] {
                    ConstValue::Int(a) => Some(ConstValue::Float(a as f64)),
                    ConstValue::Uint(a) => finite_f32(a as f64),
                    ConstValue::Float(x) => finite_f32(x),
                    ConstValue::Bool(b) => finite_f32(b as i64 as f64),
                }),
                range: |v| v[0],
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::ToI32 => &Builtin {
                name: "i32",
                arity: 1,
                sig: Convert(Ty::I32),
                fold: Custom(|v| match v[0] {
                    ConstValue::Int(a) => Some(ConstValue::Int(a)),
                    // the same bits (WGSL's i32(u32))
                    ConstValue::Uint(a) => Some(ConstValue::Int(a as i32 as i64)),
                    ConstValue::Float(x) if x.is_finite() => {
                        Some(ConstValue::Int(x.trunc().clamp(i32::MIN as f64, i32::MAX as f64) as i64))
                    }
                    ConstValue::Float(_) => None,
                    ConstValue::Bool(b) => Some(ConstValue::Int(b as i64)),
                }),
                range: |v| v[0].monotone(f64::trunc),
                wgsl: Same,
                accuracy: Exact,
            },
            Func::ToU32 => &Builtin {
                name: "u32",
                arity: 1,
                sig: Convert(Ty::U32),
                fold: Custom(|v| match v[0] {
                    // the same bits (WGSL's u32(i32)): u32(-1) is 4294967295u
                    ConstValue::Int(a) => Some(ConstValue::Uint(a as i32 as u32)),
                    ConstValue::Uint(a) => Some(ConstValue::Uint(a)),
                    // rounded towards zero and clamped to the u32 range, as for i32
                    ConstValue::Float(x) if x.is_finite() => Some(ConstValue::Uint(x.trunc().clamp(0.0, u32::MAX as f64) as u32)),
                    ConstValue::Float(_) => None,
                    ConstValue::Bool(b) => Some(ConstValue::Uint(b as u32)),
                }),
                range: |v| {
                    let t = v[0].monotone(f64::trunc);
                    // a negative i32 becomes a large u32: anything
                    if t.lo < 0.0 { Interval::U32 } else { t.meet(Interval::U32) }
                },
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Vec2 => &Builtin {
                name: "vec2",
                arity: 2,
                sig: Construct(2),
                fold: Never,
                range: components,
                wgsl: Callee("vec2<f32>"),
                accuracy: Exact,
            },
            Func::Vec3 => &Builtin {
                name: "vec3",
                arity: 3,
                sig: Construct(3),
                fold: Never,
                range: components,
                wgsl: Callee("vec3<f32>"),
                accuracy: Exact,
            },
            Func::Vec4 => &Builtin {
                name: "vec4",
                arity: 4,
                sig: Construct(4),
                fold: Never,
                range: components,
                wgsl: Callee("vec4<f32>"),
                accuracy: Exact,
            },
            Func::Length => &Builtin {
                name: "length",
                arity: 1,
                sig: Length,
                fold: Never,
                range: |v| Interval {
                    lo: 0.0,
                    hi: (v.len() as f64).sqrt().max(2.0) * v[0].magnitude(),
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::Dot => &Builtin {
                name: "dot",
                arity: 2,
                sig: Dot,
                fold: Never,
                range: |v| {
                    let m = v[0].magnitude() * v[1].magnitude() * 4.0;
                    Interval { lo: -m, hi: m }
                },
                wgsl: Same,
                accuracy: Rounded,
            },
            Func::DivOr => &Builtin {
                name: "div_or",
                arity: 4,
                sig: Sig::Guarded,
                fold: Float(|x| Some(if x[1].abs() >= x[2] && x[1] != 0.0 { x[0] / x[1] } else { x[3] })),
                range: |v| {
                    // the quotient over the denominators at least eps away from 0, and the fallback
                    let (num, den, eps, fb) = (v[0], v[1], v[2], v[3]);
                    if eps.lo <= 0.0 {
                        return Interval::UNBOUNDED;
                    }
                    let mut r = fb;
                    for (lo, hi) in [(den.lo.max(eps.lo), den.hi), (den.lo, den.hi.min(-eps.lo))] {
                        if lo <= hi {
                            r = Interval::hull(r, Interval::of(&[num.lo / lo, num.lo / hi, num.hi / lo, num.hi / hi]));
                        }
                    }
                    r
                },
                // the denominator is replaced by 1 where it is refused, so that no
                // infinity or NaN is computed even in the branch select discards; on
                // vectors, component by component (lowering has splatted eps and fallback)
                wgsl: Typed(|v, ty| match ty {
                    Ty::Vec(k) => {
                        let ok = format!("(abs({d}) >= {e}) & ({d} != vec{k}<f32>(0.0))", d = v[1], e = v[2]);
                        format!(
                            "select({fb}, {n} / select(vec{k}<f32>(1.0), {d}, {ok}), {ok})",
                            n = v[0],
                            d = v[1],
                            fb = v[3]
                        )
                    }
                    Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => format!(
                        "select({fb}, {n} / select(1.0, {d}, abs({d}) >= {e} && {d} != 0.0), abs({d}) >= {e} && {d} != 0.0)",
                        n = v[0],
                        d = v[1],
                        e = v[2],
                        fb = v[3]
                    ),
                }),
                accuracy: Bound(|v, _| 2.5 * ulp(v)),
            },
            Func::Branch => &Builtin {
                name: "if",
                arity: 3,
                sig: Sig::Select,
                fold: Custom(pick),
                range: |v| Interval::hull(v[0], v[1]),
                // never a call: `back::expr` emits the arms inside an `if`
                wgsl: Same,
                accuracy: Exact,
            },
            Func::Noise => &Builtin {
                name: "noise",
                arity: 3,
                sig: Scalars,
                // a hash: the GPU's integer arithmetic, which `interp::noise` repeats
                fold: Hook,
                range: |_| Interval { lo: 0.0, hi: 1.0 },
                // the module defines `sshc_noise` where a body calls it (`NOISE_WGSL`)
                wgsl: Callee("sshc_noise"),
                accuracy: Exact,
            },
            Func::UvWidth => &Builtin {
                name: "uv_width",
                arity: 2,
                sig: Scalars,
                // scaled by the frame: unknown at compile time
                fold: Hook,
                // a length over a texel's world size: scaled by the frame, unknown here
                range: |v| Interval {
                    lo: if v[0].lo >= 0.0 { 0.0 } else { f64::NEG_INFINITY },
                    hi: if v[0].hi <= 0.0 { 0.0 } else { f64::INFINITY },
                },
                // one texel at distance D spans texel_world.x * D + texel_world.y world units
                wgsl: Expr(|v| {
                    format!(
                        "({} / ((frame.texel_world.x * {} + frame.texel_world.y) * frame.shadow_size.x))",
                        v[0], v[1]
                    )
                }),
                accuracy: Rounded,
            },
        }
    }

    pub fn name(self) -> &'static str {
        self.desc().name
    }

    pub fn from_name(n: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == n)
    }

    pub fn arity(self) -> usize {
        self.desc().arity
    }

    /// Result type for these argument types, or a message saying what was expected.
    pub fn result(self, args: &[Ty]) -> Result<Ty, String> {
        let d = self.desc();
        if args.len() != d.arity {
            return Err(format!("`{}` takes {} argument(s), found {}", d.name, d.arity, args.len()));
        }
        d.sig.result(d.name, args)
    }

    /// The type argument `i` is coerced to (abstract integer literals become it), given
    /// the argument types and the call's result type from [`Func::result`].
    pub fn arg_ty(self, i: usize, args: &[Ty], result: Ty) -> Ty {
        self.desc().sig.arg_ty(i, args, result)
    }

    /// Whether a call on abstract integers stays an abstract integer (`min(1, 2)`).
    pub fn keeps_abstract(self) -> bool {
        self.desc().sig.keeps_abstract()
    }
}

impl Sig {
    /// The call's shape in words, with `arity` parameters named as docs/language.md
    /// section 8.6 writes them (for diagnostics).
    pub fn describe(self, name: &str, arity: usize) -> String {
        let params = |names: &[&str]| format!("{name}({})", names[..arity.min(names.len())].join(", "));
        match self {
            Sig::Float => format!("{}: f32 or vectors of one size", params(&["x", "y", "z"])),
            Sig::Numeric => format!("{}: one number (f32, i32 or a vector)", params(&["x"])),
            Sig::SameNumeric => format!("{}: numbers of one type (f32, i32, u32 or vectors)", params(&["a", "b", "c"])),
            Sig::Select => "select(f, t, cond): `f` and `t` of one type, `cond` a bool".to_string(),
            Sig::Convert(_) => format!("{}: one scalar (f32, i32, u32 or bool)", params(&["x"])),
            Sig::Construct(n) => format!("{}: {n} f32 components", params(&["x", "y", "z", "w"])),
            Sig::Scalars => format!("{}: f32 scalars", params(&["a", "b", "c", "d"])),
            Sig::Length => format!("{}: one vector", params(&["v"])),
            Sig::Dot => format!("{}: two vectors of one size", params(&["a", "b"])),
            Sig::Guarded => format!(
                "{}: `num` and `den` f32 or vectors of one size; `eps` and `fallback` their type or f32",
                params(&["num", "den", "eps", "fallback"])
            ),
        }
    }

    /// Whether every argument must be a scalar (a vector is refused, not taken component
    /// by component): what the typer's help on a vector argument reads.
    pub fn takes_scalars(self) -> bool {
        match self {
            Sig::Scalars | Sig::Convert(_) | Sig::Construct(_) => true,
            Sig::Numeric | Sig::SameNumeric | Sig::Select | Sig::Length | Sig::Dot | Sig::Float | Sig::Guarded => false,
        }
    }

    fn result(self, name: &str, args: &[Ty]) -> Result<Ty, String> {
        let same = |tys: &[Ty]| -> Option<Ty> { tys.iter().try_fold(tys[0], |acc, t| unify(acc, *t)) };
        match self {
            Sig::Numeric => match args[0] {
                t if t.is_numeric() => Ok(t.concrete()),
                t => Err(format!("`{name}` expects a number, found {t}")),
            },
            Sig::SameNumeric => match same(args) {
                Some(t) if t.is_arithmetic() => Ok(t.concrete()),
                _ => Err(format!("`{name}` expects arguments of one numeric type, found {}", list(args))),
            },
            Sig::Select => match (unify(args[0], args[1]), args[2]) {
                (Some(t), Ty::Bool) => Ok(t.concrete()),
                (None, _) => Err(format!("`select(f, t, cond)` needs `f` and `t` of one type, found {}", list(args))),
                (_, c) => Err(format!("`select(f, t, cond)` needs a bool condition, found {c}")),
            },
            Sig::Convert(to) => match args[0] {
                Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt => Ok(to),
                t @ Ty::Vec(_) => Err(format!("`{name}` converts a scalar, found {t}")),
            },
            Sig::Construct(n) => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::Vec(n))
                } else {
                    Err(format!("`{name}` takes f32 components, found {}", list(args)))
                }
            }
            Sig::Length => match args[0] {
                Ty::Vec(_) | Ty::F32 | Ty::AbstractInt => Ok(Ty::F32),
                t @ (Ty::I32 | Ty::U32 | Ty::Bool) => Err(format!("`{name}` expects a vector, found {t}")),
            },
            Sig::Dot => match same(args) {
                Some(Ty::Vec(_)) => Ok(Ty::F32),
                Some(Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt) | None => {
                    Err(format!("`{name}` expects two vectors of one size, found {}", list(args)))
                }
            },
            Sig::Scalars => {
                if args.iter().all(|t| matches!(t, Ty::F32 | Ty::AbstractInt)) {
                    Ok(Ty::F32)
                } else {
                    Err(format!("`{name}` takes f32 arguments, found {}", list(args)))
                }
            }
            Sig::Float => match same(args) {
                Some(t) if t.is_float_like() => Ok(if t == Ty::AbstractInt { Ty::F32 } else { t }),
                _ => Err(format!("`{name}` expects f32 or vector arguments, found {}", list(args))),
            },
            Sig::Guarded => {
                let t = match same(&args[..2]) {
                    Some(t) if t.is_float_like() => {
                        if t == Ty::AbstractInt {
                            Ty::F32
                        } else {
                            t
                        }
                    }
                    _ => {
                        return Err(format!(
                            "`{name}` expects `num` and `den` of one type, f32 or a vector, found {}",
                            list(&args[..2])
                        ));
                    }
                };
                match args[2..].iter().find(|a| !matches!(a, Ty::F32 | Ty::AbstractInt) && **a != t) {
                    None => Ok(t),
                    Some(a) => Err(format!(
                        "`{name}` takes `eps` and `fallback` as f32 or the type of `num` ({t}), found {a}"
                    )),
                }
            }
        }
    }

    fn arg_ty(self, i: usize, args: &[Ty], result: Ty) -> Ty {
        match self {
            Sig::Convert(_) => Ty::I32,
            Sig::Select if i == 2 => Ty::Bool,
            Sig::Select | Sig::SameNumeric | Sig::Numeric => result,
            Sig::Length | Sig::Dot => args.iter().copied().find(|t| matches!(t, Ty::Vec(_))).unwrap_or(Ty::F32),
            Sig::Construct(_) => Ty::F32,
            Sig::Float | Sig::Scalars => {
                if matches!(result, Ty::Vec(_)) {
                    result
                } else {
                    Ty::F32
                }
            }
            // num and den the result's type; eps and fallback as given (f32 splatted later)
            Sig::Guarded => {
                if i < 2 || matches!(args.get(i), Some(Ty::Vec(_))) {
                    result
                } else {
                    Ty::F32
                }
            }
        }
    }

    fn keeps_abstract(self) -> bool {
        match self {
            Sig::Numeric | Sig::SameNumeric => true,
            Sig::Float | Sig::Select | Sig::Convert(_) | Sig::Construct(_) | Sig::Scalars | Sig::Length | Sig::Dot | Sig::Guarded => false,
        }
    }
}

/// Evaluate a pure function on constants with f32 results rounded as the GPU would store
/// them; `None` where it is not folded (no finite value, or not evaluated at compile time).
pub fn fold_call(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    fold_with(f, v, finite_f32)
}

/// [`fold_call`] without rounding float results to f32 and keeping infinities and NaNs:
/// the CPU evaluation of `sshc verify` (`interp`), which is exact where the GPU is not.
pub fn fold_call_exact(f: Func, v: &[ConstValue]) -> Option<ConstValue> {
    fold_with(f, v, |x| Some(ConstValue::Float(x)))
}

fn fold_with(f: Func, v: &[ConstValue], finish: fn(f64) -> Option<ConstValue>) -> Option<ConstValue> {
    let floats = || -> Option<Vec<f64>> {
        v.iter()
            .map(|c| match c {
                ConstValue::Float(x) => Some(*x),
                ConstValue::Int(x) => Some(*x as f64),
                ConstValue::Uint(x) => Some(*x as f64),
                ConstValue::Bool(_) => None,
            })
            .collect()
    };
    match f.desc().fold {
        Fold::Never | Fold::Hook => None,
        Fold::Float(g) => finish(g(&floats()?)?),
        Fold::IntOrFloat(int, g) => {
            // u32 arguments (`min`, `max`, `clamp` of u32): their result is one of them
            if let Some(a) = v
                .iter()
                .map(|c| match c {
                    ConstValue::Uint(a) => Some(*a as i64),
                    ConstValue::Int(_) | ConstValue::Float(_) | ConstValue::Bool(_) => None,
                })
                .collect::<Option<Vec<i64>>>()
            {
                return int(&a).and_then(|r| u32::try_from(r).ok()).map(ConstValue::Uint);
            }
            let ints: Option<Vec<i64>> = v
                .iter()
                .map(|c| match c {
                    ConstValue::Int(a) => Some(*a),
                    ConstValue::Uint(_) | ConstValue::Float(_) | ConstValue::Bool(_) => None,
                })
                .collect();
            match ints {
                Some(a) => int(&a).map(ConstValue::Int),
                None => finish(g(&floats()?)?),
            }
        }
        Fold::Custom(g) => g(v),
    }
}

/// `x` rounded to f32, if finite.
fn finite_f32(x: f64) -> Option<ConstValue> {
    x.is_finite().then_some(ConstValue::Float(x as f32 as f64))
}

/// WGSL's `round`: half to even.
fn round_half_even(x: f64) -> f64 {
    if (x - x.trunc()).abs() == 0.5 {
        2.0 * (x / 2.0).round()
    } else {
        x.round()
    }
}

/// WGSL's `sign`: -1, 0 or 1.
fn sign(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x.signum() }
}

/// Range of a vector constructor: the hull of its components.
fn components(v: &[Interval]) -> Interval {
    v.iter().copied().reduce(Interval::hull).unwrap_or(Interval::UNBOUNDED)
}

/// Range of sin(x + phase) over x.
fn trig(x: Interval, phase: f64) -> Interval {
    if !x.is_finite() || x.hi - x.lo >= 2.0 * PI {
        return Interval { lo: -1.0, hi: 1.0 };
    }
    let (a, b) = (x.lo + phase, x.hi + phase);
    let mut vals = vec![a.sin(), b.sin()];
    // extrema at pi/2 + n pi
    let mut n = ((a - PI / 2.0) / PI).ceil();
    while PI / 2.0 + n * PI <= b {
        vals.push((PI / 2.0 + n * PI).sin());
        n += 1.0;
    }
    Interval::of(&vals)
}

fn list(args: &[Ty]) -> String {
    args.iter().map(|t| format!("`{t}`")).collect::<Vec<_>>().join(", ")
}

/// How a Shade pass reads a channel (filtered lookups into channels). Everything about one
/// lookup function is its [`SampleDesc`] (see [`SampleFn::desc`]).
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
    /// `sample_at(ch, du, dv)`: hardware-filtered (bilinear) at `uv + (du, dv)`, level 0.
    SampleAt,
    /// `sample_box_at(ch, du, dv, wx, wy)`: [`SampleFn::Box`] centred at `uv + (du, dv)`:
    /// a region off the receiver (a sub-region of a filter kernel, a tile).
    BoxAt,
    /// `sample_width_at(ch, du, dv, w)`: [`SampleFn::SampleWidth`] centred at `uv + (du, dv)`.
    SampleWidthAt,
    /// `nearest_level(ch, level)`: the texel of mip level `level` (an i32, clamped to the
    /// chain) containing `uv`, unfiltered: a min or max mip read as it is.
    NearestLevel,
    /// `nearest_level_at(ch, level, du, dv)`: [`SampleFn::NearestLevel`] at `uv + (du, dv)`.
    NearestLevelAt,
    /// `sample_mip_box(ch, w)`: the mean over the box `w` wide (uv units, at least a texel)
    /// centred at `uv`, clipped to the map, of the piecewise-constant texels of the Mean mip
    /// level where the box spans one to two texels: at most 3 x 3 texel loads, equal to the
    /// coverage-weighted mean of the level-0 texels where the box's edges lie on that
    /// level's texel edges (docs/language.md 8.7).
    MipBox,
    /// `sample_mip_box_at(ch, du, dv, w)`: [`SampleFn::MipBox`] centred at `uv + (du, dv)`.
    MipBoxAt,
}

/// Everything the compiler knows about one lookup function.
#[derive(Debug)]
pub struct SampleDesc {
    /// The name on a channel (`sample`).
    pub name: &'static str,
    /// The name on an expansion (`expand`).
    pub expand_name: &'static str,
    /// Types of the arguments after the channel or expansion name.
    pub extra_args: &'static [Ty],
    pub wgsl: SampleWgsl,
}

/// How a lookup is written in WGSL.
#[derive(Clone, Copy)]
pub enum SampleWgsl {
    /// A texture read: `read(texture binding, layer, uv, base, extra argument
    /// expressions)`, where `uv` is the receiver's shadow-map coordinates and `base` the
    /// texel under them less half a texel (`vec2<i32>`), in the view being read; the module
    /// binds the filtering sampler `smp` when `sampler` is set.
    Texture {
        sampler: bool,
        read: fn(&str, &str, &str, &str, &[String]) -> String,
    },
    /// A box sum over a summed-area table, through the module's `box_<table>` function.
    SummedAreaTable,
}

impl fmt::Debug for SampleWgsl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SampleWgsl::Texture { sampler, .. } => f.debug_struct("Texture").field("sampler", sampler).finish_non_exhaustive(),
            SampleWgsl::SummedAreaTable => f.write_str("SummedAreaTable"),
        }
    }
}

impl SampleFn {
    pub const ALL: [SampleFn; 14] = [
        SampleFn::Sample,
        SampleFn::SampleLod,
        SampleFn::SampleWidth,
        SampleFn::Nearest,
        SampleFn::Fetch,
        SampleFn::Box,
        SampleFn::NearestAt,
        SampleFn::SampleAt,
        SampleFn::BoxAt,
        SampleFn::SampleWidthAt,
        SampleFn::NearestLevel,
        SampleFn::NearestLevelAt,
        SampleFn::MipBox,
        SampleFn::MipBoxAt,
    ];

    /// Every lookup function of the language (the names of [`SampleFn::ALL`], then their
    /// `expand` forms).
    pub const NAMES: [&'static str; 28] = [
        "sample",
        "sample_lod",
        "sample_width",
        "nearest",
        "fetch",
        "sample_box",
        "nearest_at",
        "sample_at",
        "sample_box_at",
        "sample_width_at",
        "nearest_level",
        "nearest_level_at",
        "sample_mip_box",
        "sample_mip_box_at",
        "expand",
        "expand_lod",
        "expand_width",
        "expand_nearest",
        "expand_fetch",
        "expand_box",
        "expand_nearest_at",
        "expand_at",
        "expand_box_at",
        "expand_width_at",
        "expand_nearest_level",
        "expand_nearest_level_at",
        "expand_mip_box",
        "expand_mip_box_at",
    ];

    /// Lookups that read a summed-area table: the box ones always, `nearest` and
    /// `nearest_at` where the resource read is a table (the texel's stored value).
    pub fn reads_table(self) -> bool {
        matches!(self, SampleFn::Box | SampleFn::BoxAt)
    }

    /// Lookups a summed-area table answers.
    pub fn table_may_answer(self) -> bool {
        matches!(self, SampleFn::Box | SampleFn::BoxAt | SampleFn::Nearest | SampleFn::NearestAt)
    }

    /// The descriptor: adding a lookup means adding a variant, its entries in
    /// [`SampleFn::ALL`] and [`SampleFn::NAMES`] and its arm here.
    pub fn desc(self) -> &'static SampleDesc {
        use SampleWgsl::{SummedAreaTable, Texture};
        match self {
            SampleFn::Sample => &SampleDesc {
                name: "sample",
                expand_name: "expand",
                extra_args: &[],
                wgsl: Texture {
                    sampler: true,
                    read: |tex, layer, uv, _base, _| format!("textureSample({tex}, smp, {uv}, {layer})"),
                },
            },
            SampleFn::SampleLod => &SampleDesc {
                name: "sample_lod",
                expand_name: "expand_lod",
                extra_args: &[Ty::F32],
                wgsl: Texture {
                    sampler: true,
                    read: |tex, layer, uv, _base, a| format!("textureSampleLevel({tex}, smp, {uv}, {layer}, {})", a[0]),
                },
            },
            SampleFn::SampleWidth => &SampleDesc {
                name: "sample_width",
                expand_name: "expand_width",
                extra_args: &[Ty::F32],
                wgsl: Texture {
                    sampler: true,
                    read: |tex, layer, uv, _base, a| {
                        format!(
                            "textureSampleLevel({tex}, smp, {uv}, {layer}, log2(max({} * frame.shadow_size.x, 1.0)))",
                            a[0]
                        )
                    },
                },
            },
            SampleFn::Nearest => &SampleDesc {
                name: "nearest",
                expand_name: "expand_nearest",
                extra_args: &[],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, _| {
                        format!(
                            "textureLoad({tex}, clamp(vec2<i32>(floor({uv} * frame.shadow_size.xy)), vec2<i32>(0i), vec2<i32>(frame.shadow_size.xy) - 1i), {layer}, 0i)"
                        )
                    },
                },
            },
            SampleFn::Fetch => &SampleDesc {
                name: "fetch",
                expand_name: "expand_fetch",
                extra_args: &[Ty::I32, Ty::I32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, _uv, base, a| {
                        format!(
                            "textureLoad({tex}, clamp({base} + vec2<i32>({}, {}), vec2<i32>(0i), vec2<i32>(frame.shadow_size.xy) - 1i), {layer}, 0i)",
                            a[0], a[1]
                        )
                    },
                },
            },
            SampleFn::NearestAt => &SampleDesc {
                name: "nearest_at",
                expand_name: "expand_nearest_at",
                extra_args: &[Ty::F32, Ty::F32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, a| {
                        format!(
                            "textureLoad({tex}, clamp(vec2<i32>(floor(({uv} + vec2<f32>({}, {})) * frame.shadow_size.xy)), vec2<i32>(0i), vec2<i32>(frame.shadow_size.xy) - 1i), {layer}, 0i)",
                            a[0], a[1]
                        )
                    },
                },
            },
            SampleFn::SampleAt => &SampleDesc {
                name: "sample_at",
                expand_name: "expand_at",
                extra_args: &[Ty::F32, Ty::F32],
                wgsl: Texture {
                    sampler: true,
                    read: |tex, layer, uv, _base, a| {
                        format!("textureSampleLevel({tex}, smp, {uv} + vec2<f32>({}, {}), {layer}, 0.0)", a[0], a[1])
                    },
                },
            },
            SampleFn::Box => &SampleDesc {
                name: "sample_box",
                expand_name: "expand_box",
                extra_args: &[Ty::F32, Ty::F32],
                wgsl: SummedAreaTable,
            },
            SampleFn::BoxAt => &SampleDesc {
                name: "sample_box_at",
                expand_name: "expand_box_at",
                extra_args: &[Ty::F32, Ty::F32, Ty::F32, Ty::F32],
                wgsl: SummedAreaTable,
            },
            SampleFn::SampleWidthAt => &SampleDesc {
                name: "sample_width_at",
                expand_name: "expand_width_at",
                extra_args: &[Ty::F32, Ty::F32, Ty::F32],
                wgsl: Texture {
                    sampler: true,
                    read: |tex, layer, uv, _base, a| {
                        format!(
                            "textureSampleLevel({tex}, smp, {uv} + vec2<f32>({}, {}), {layer}, log2(max({} * frame.shadow_size.x, 1.0)))",
                            a[0], a[1], a[2]
                        )
                    },
                },
            },
            SampleFn::NearestLevel => &SampleDesc {
                name: "nearest_level",
                expand_name: "expand_nearest_level",
                extra_args: &[Ty::I32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, a| level_read(tex, layer, uv, &a[0]),
                },
            },
            SampleFn::NearestLevelAt => &SampleDesc {
                name: "nearest_level_at",
                expand_name: "expand_nearest_level_at",
                extra_args: &[Ty::I32, Ty::F32, Ty::F32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, a| level_read(tex, layer, &format!("({uv} + vec2<f32>({}, {}))", a[1], a[2]), &a[0]),
                },
            },
            SampleFn::MipBox => &SampleDesc {
                name: "sample_mip_box",
                expand_name: "expand_mip_box",
                extra_args: &[Ty::F32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, a| format!("{MIP_BOX}({tex}, {layer}, {uv}, {})", a[0]),
                },
            },
            SampleFn::MipBoxAt => &SampleDesc {
                name: "sample_mip_box_at",
                expand_name: "expand_mip_box_at",
                extra_args: &[Ty::F32, Ty::F32, Ty::F32],
                wgsl: Texture {
                    sampler: false,
                    read: |tex, layer, uv, _base, a| format!("{MIP_BOX}({tex}, {layer}, {uv} + vec2<f32>({}, {}), {})", a[0], a[1], a[2]),
                },
            },
        }
    }

    /// The lookup a name denotes, and whether it is the `expand` form.
    pub fn from_name(n: &str) -> Option<(SampleFn, bool)> {
        SampleFn::ALL.into_iter().find_map(|s| {
            let d = s.desc();
            if d.name == n {
                Some((s, false))
            } else if d.expand_name == n {
                Some((s, true))
            } else {
                None
            }
        })
    }

    /// Arguments after the channel or expansion name.
    pub fn extra_args(self) -> &'static [Ty] {
        self.desc().extra_args
    }

    pub fn name(self, expand: bool) -> &'static str {
        if expand { self.desc().expand_name } else { self.desc().name }
    }
}

/// Whether a lookup needs a Mean mip chain (the box lookups on one).
impl SampleFn {
    pub fn needs_mean_chain(self) -> bool {
        matches!(self, SampleFn::MipBox | SampleFn::MipBoxAt)
    }
}

/// The WGSL function the mip-chain box lookups call (declared by [`MIP_BOX_WGSL`]).
pub const MIP_BOX: &str = "mip_box";

/// `sample_mip_box` in WGSL: the level where the box, `max(w N, 1)` level-0 texels wide,
/// spans one to two texels (`firstLeadingBit` of its whole width: exact, unlike `log2`),
/// the box in that level's texels (centre clamped to the map, clipped to it), and the
/// coverage-weighted sum of the at most 3 x 3 texels it touches over its area (a texel it
/// misses not read, as a non-finite one would poison the sum). The same arithmetic in f64
/// is `interp`'s `Texels::mip_box`.
pub const MIP_BOX_WGSL: &str = "
// the mean over the box `w` wide (uv units, one texel at least) centred at `uv`, clipped
// to the map, of the texels of the Mean mip level where it spans one to two texels
// (docs/language.md 8.7, sample_mip_box): at most 3 x 3 loads, one call of mip_box_texel
// each (so that the cost model counts each load). The level's size is level 0's shifted,
// not queried at the level: where neighbouring pixels chose different levels, lavapipe
// answered textureDimensions(t, level) wrongly for some of them (whole columns read 0).
fn mip_box(t: texture_2d_array<f32>, layer: i32, uv: vec2<f32>, w: f32) -> vec4<f32> {
    let base = vec2<i32>(textureDimensions(t, 0i));
    let n = vec2<f32>(base);
    let width = clamp(w * n.x, 1.0, 4294967040.0);
    let level = clamp(i32(firstLeadingBit(u32(width))), 0i, i32(textureNumLevels(t)) - 1i);
    let s = f32(1u << u32(level));
    let size = max(base >> vec2<u32>(u32(level)), vec2<i32>(1i));
    let c = clamp(uv * n, vec2<f32>(0.0), n);
    let lo = max((c - 0.5 * width) / s, vec2<f32>(0.0));
    let hi = min((c + 0.5 * width) / s, vec2<f32>(size));
    let first = vec2<i32>(floor(lo));
    let sum = mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 0i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 1i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(0i, 2i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(1i, 2i))
        + mip_box_texel(t, layer, level, first, size, lo, hi, vec2<i32>(2i, 2i));
    return sum / ((hi.x - lo.x) * (hi.y - lo.y));
}

// texel `first + o` of the level weighted by the area of it the box [lo, hi] covers; a
// texel the box misses is not read: 0 times an infinite or NaN texel is NaN
fn mip_box_texel(t: texture_2d_array<f32>, layer: i32, level: i32, first: vec2<i32>, size: vec2<i32>, lo: vec2<f32>, hi: vec2<f32>, o: vec2<i32>) -> vec4<f32> {
    let x = vec2<f32>(first + o);
    let cover = max(min(hi, x + 1.0) - max(lo, x), vec2<f32>(0.0));
    let weight = cover.x * cover.y;
    if (weight > 0.0) {
        return weight * textureLoad(t, min(first + o, size - 1i), layer, level);
    }
    return vec4<f32>(0.0);
}
";

/// WGSL of an unfiltered read of mip level `level` (an i32 expression, clamped to the
/// chain) at `uv`: the texel of that level containing it, clamped to the edge. The level's
/// size is level 0's shifted, not queried at the level, by the rule of [`MIP_BOX_WGSL`]
/// (where lavapipe answered the query wrongly for pixels whose neighbours chose another
/// level; here a GPU test with per-pixel levels passes either way).
fn level_read(tex: &str, layer: &str, uv: &str, level: &str) -> String {
    let level = format!("clamp({level}, 0i, i32(textureNumLevels({tex})) - 1i)");
    let size = format!("max(vec2<i32>(textureDimensions({tex}, 0i)) >> vec2<u32>(u32({level})), vec2<i32>(1i))");
    format!("textureLoad({tex}, clamp(vec2<i32>(floor({uv} * vec2<f32>({size}))), vec2<i32>(0i), {size} - 1i), {layer}, {level})")
}

/// Every name reserved by the language (declarations may not take them).
/// `neighbour(ch, dx, dy)`: on the map side, channel `ch` of the texel `(dx, dy)` texels
/// away, clamped to the map's edge; `dx`, `dy` integers known at compile time.
pub const NEIGHBOUR: &str = "neighbour";
/// The farthest a `neighbour` reads, in texels along each axis (the kernels' limit).
pub const MAX_NEIGHBOUR: i64 = 31;

pub fn is_reserved(name: &str) -> bool {
    Input::from_name(name).is_some()
        || constant(name).is_some()
        || Func::from_name(name).is_some()
        || SampleFn::from_name(name).is_some()
        || matches!(
            name,
            "let" | "sum" | "in" | "true" | "false" | "if" | "else" | "at_sample" | NEIGHBOUR
        )
        || name == crate::front::expr::COMPARE_AT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_round_trips_through_lookup() {
        for (i, f) in Func::ALL.into_iter().enumerate() {
            assert_eq!(f as usize, i, "Func::ALL out of declaration order at {f:?}");
            assert_eq!(Func::from_name(f.name()), Some(f));
            assert!(is_reserved(f.name()));
        }
        assert_eq!(Func::Branch as usize + 1, Func::ALL.len(), "a Func is missing from Func::ALL");
        for (i, input) in Input::ALL.into_iter().enumerate() {
            assert_eq!(input as usize, i, "Input::ALL out of declaration order at {input:?}");
            assert_eq!(Input::from_name(input.name()), Some(input));
            assert!(is_reserved(input.name()));
        }
        assert_eq!(Input::Frame as usize + 1, Input::ALL.len(), "an Input is missing from Input::ALL");
        let mut names: Vec<&str> = SampleFn::ALL.iter().map(|s| s.name(false)).collect();
        names.extend(SampleFn::ALL.iter().map(|s| s.name(true)));
        assert_eq!(names, SampleFn::NAMES, "SampleFn::NAMES disagrees with the descriptors");
        for s in SampleFn::ALL {
            for expand in [false, true] {
                assert_eq!(SampleFn::from_name(s.name(expand)), Some((s, expand)));
                assert!(is_reserved(s.name(expand)));
            }
        }
        let mut order: Vec<usize> = SampleFn::ALL.iter().map(|s| *s as usize).collect();
        order.sort_unstable();
        assert_eq!(order, (0..SampleFn::ALL.len()).collect::<Vec<_>>());
        assert_eq!(
            SampleFn::MipBoxAt as usize + 1,
            SampleFn::ALL.len(),
            "a SampleFn is missing from SampleFn::ALL"
        );
        // names are unique across all builtins
        let mut all: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
        all.extend(Input::ALL.iter().map(|i| i.name()));
        all.extend(SampleFn::NAMES);
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n, "two builtins share a name");
    }

    /// Argument types a call may take: every uniform choice the signature accepts.
    fn signatures(f: Func) -> Vec<Vec<Ty>> {
        let n = f.arity();
        let mut out: Vec<Vec<Ty>> = [Ty::F32, Ty::Vec(2), Ty::Vec(3), Ty::Vec(4), Ty::I32, Ty::U32, Ty::Bool]
            .into_iter()
            .map(|t| vec![t; n])
            .collect();
        if n == 3 {
            for t in [Ty::F32, Ty::Vec(2), Ty::I32, Ty::U32] {
                out.push(vec![t, t, Ty::Bool]);
            }
        }
        out.retain(|args| f.result(args).is_ok());
        out
    }

    #[test]
    fn every_function_has_a_signature_of_its_arity() {
        for f in Func::ALL {
            assert!(!signatures(f).is_empty(), "`{}` accepts no argument types", f.name());
            let wrong = vec![Ty::F32; f.arity() + 1];
            assert!(f.result(&wrong).is_err());
        }
    }

    /// Folding sample arguments gives a value inside the range rule's interval of any
    /// argument intervals that hold them.
    #[test]
    fn folding_lies_inside_the_range_rule() {
        let boxes: [(f64, f64); 11] = [
            // f32 values, so the sample points are the ends themselves
            (-3.0, -0.5),
            (-1.0, 1.0),
            (0.0, 1.0),
            (0.25, 4.0),
            (1.0, 100.0),
            (-100.0, 100.0),
            (0.0, 0.0),
            (0.5, 0.5),
            (2.5, 2.5),
            (-2.5, -2.5),
            (2.75, 2.75),
        ];
        let mut checked = 0;
        let mut failures = Vec::new();
        for f in Func::ALL {
            let d = f.desc();
            if matches!(d.fold, Fold::Never | Fold::Hook) {
                continue;
            }
            let scalar: Vec<Vec<Ty>> = signatures(f)
                .into_iter()
                .filter(|s| !s.iter().any(|t| matches!(t, Ty::Vec(_))))
                .collect();
            for sig in scalar {
                // every combination of argument boxes
                let k = sig.len();
                for combo in 0..boxes.len().pow(k as u32) {
                    let pick: Vec<(f64, f64)> = (0..k).map(|i| boxes[combo / boxes.len().pow(i as u32) % boxes.len()]).collect();
                    let ivs: Vec<Interval> = pick
                        .iter()
                        .zip(&sig)
                        .map(|(&(lo, hi), t)| if *t == Ty::Bool { Interval::UNIT } else { Interval { lo, hi } })
                        .collect();
                    let range = (d.range)(&ivs);
                    // sample points: ends and middle of each box (integers: rounded inward)
                    for p in 0..3usize.pow(k as u32) {
                        let args: Option<Vec<ConstValue>> = (0..k)
                            .map(|i| {
                                let (lo, hi) = pick[i];
                                let x = [lo, hi, 0.5 * (lo + hi)][p / 3usize.pow(i as u32) % 3];
                                match sig[i] {
                                    // integers: the point rounded, if still inside the box
                                    Ty::I32 => (lo..=hi).contains(&x.round()).then_some(ConstValue::Int(x.round() as i64)),
                                    Ty::U32 => (lo..=hi)
                                        .contains(&x.round())
                                        .then_some(x.round())
                                        .and_then(|v| (v >= 0.0).then_some(ConstValue::Uint(v as u32))),
                                    Ty::Bool => Some(ConstValue::Bool(x > lo)),
                                    Ty::F32 | Ty::Vec(_) | Ty::AbstractInt => Some(ConstValue::Float(x as f32 as f64)),
                                }
                            })
                            .collect();
                        let Some(args) = args else { continue };
                        let Some(v) = fold_call(f, &args) else { continue };
                        let r = v.as_f64();
                        // the fold rounds to f32, the range rule is exact
                        let tol = r.abs().max(1.0) * f32::EPSILON as f64;
                        let inside = range.lo - tol <= r && r <= range.hi + tol;
                        if !inside && !failures.iter().any(|m: &String| m.starts_with(d.name)) {
                            failures.push(format!(
                                "{}({args:?}) folds to {r}, outside its range rule's {range} for argument ranges {ivs:?}",
                                d.name
                            ));
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
        assert!(checked > 10_000, "only {checked} folds checked");
    }

    /// docs/language.md lists every function, input, lookup and light kind, inputs with
    /// their type and side.
    #[test]
    fn the_language_reference_lists_every_builtin() {
        let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/language.md")).unwrap();
        let section = |from: &str, to: &str| -> &str {
            let a = doc.find(from).unwrap_or_else(|| panic!("no `{from}` in docs/language.md"));
            let b = doc[a..].find(to).map_or(doc.len(), |b| a + b);
            &doc[a..b]
        };
        let functions = section("### 8.6 Functions", "### 8.7");
        // `if` is syntax (8.4), not a function
        assert!(section("### 8.4", "### 8.5").contains("if cond { a } else { b }"));
        for f in Func::ALL.into_iter().filter(|f| *f != Func::Branch) {
            assert!(
                functions.contains(&format!("`{}(", f.name())),
                "docs/language.md 8.6 lacks `{}`",
                f.name()
            );
        }
        let lookups = section("### 8.7 Sampling functions", "### 8.8");
        for name in SampleFn::NAMES {
            assert!(lookups.contains(&format!("`{name}(")), "docs/language.md 8.7 lacks `{name}`");
        }
        let inputs = section("**Built-in inputs.**", "**Channels**");
        for i in Input::ALL {
            let d = i.desc();
            let ty = match d.ty {
                Ty::Vec(n) => format!("vec{n}"),
                t @ (Ty::F32 | Ty::I32 | Ty::U32 | Ty::Bool | Ty::AbstractInt) => t.to_string(),
            };
            let side = match d.side {
                Side::Receiver => "receiver",
                Side::Map => "map",
                Side::Both => "both",
                Side::Geometry => "geometry",
            };
            let row = format!("| `{}` | {ty} | {side} |", d.name);
            assert!(inputs.contains(&row), "docs/language.md 8.5 lacks the row `{row}`");
        }
        let lights = section("## 4. Light models", "## 5.");
        for k in crate::front::ast::LightKind::ALL {
            assert!(
                lights.contains(&format!("| `{}", k.name())),
                "docs/language.md 4 lacks `{}`",
                k.name()
            );
        }
    }

    /// A module that calls every function (with every argument type its signature
    /// accepts), reads every input and every texture lookup, written by the code
    /// generator's own emission, must pass naga's validation.
    #[test]
    fn every_builtin_emits_valid_wgsl() {
        let mut body = String::new();
        let arg = |t: Ty| match t {
            Ty::F32 | Ty::AbstractInt => "a_f32".to_string(),
            Ty::I32 => "a_i32".to_string(),
            Ty::U32 => "a_u32".to_string(),
            Ty::Bool => "a_bool".to_string(),
            Ty::Vec(n) => format!("a_vec{n}"),
        };
        for i in Input::ALL {
            let d = i.desc();
            if matches!(d.side, Side::Receiver | Side::Geometry) {
                body.push_str(&format!("    let {}: {} = {};\n", d.wgsl, d.ty.wgsl(), arg(d.ty)));
            }
        }
        for (k, i) in Input::ALL.into_iter().enumerate() {
            body.push_str(&format!("    let input{k}: {} = {};\n", i.ty().wgsl(), i.desc().wgsl));
        }
        let mut k = 0;
        // a branch is never a call: the code generator writes an `if` (back::expr)
        for f in Func::ALL.into_iter().filter(|f| *f != Func::Branch) {
            for sig in signatures(f) {
                let ty = f.result(&sig).unwrap();
                let args: Vec<String> = sig.iter().map(|t| arg(*t)).collect();
                body.push_str(&format!("    let call{k}: {} = {};\n", ty.wgsl(), f.wgsl_call(&args, ty)));
                k += 1;
            }
        }
        for (k, s) in SampleFn::ALL.into_iter().enumerate() {
            let d = s.desc();
            match d.wgsl {
                SampleWgsl::Texture { read, .. } => {
                    let args: Vec<String> = d.extra_args.iter().map(|t| arg(*t)).collect();
                    body.push_str(&format!(
                        "    let lookup{k}: vec4<f32> = {};\n",
                        read("t_x", "1i", "in_uv", "in_base", &args)
                    ));
                }
                // the box function is written per table by the code generator
                SampleWgsl::SummedAreaTable => {}
            }
        }
        body.push_str("    let in_pixel_used = in_pixel;\n");
        let module = format!(
            "{}{}{}@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(2) var smp: sampler;
@group(1) @binding(0) var t_x: texture_2d_array<f32>;

@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {{
    let a_f32 = frame.shadow_size.z + pos.x;
    let a_vec2 = frame.shadow_size.xy;
    let a_vec3 = frame.shadow_size.xyz;
    let a_vec4 = frame.shadow_size;
    let a_i32 = i32(frame.shadow_size.x);
    let a_u32 = u32(frame.shadow_size.x);
    let a_bool = frame.shadow_size.x > 1.0;
    let in_base = vec2<i32>(floor(a_vec2));
{body}    return vec4<f32>(0.0);
}}
",
            crate::builtins::NOISE_WGSL,
            MIP_BOX_WGSL,
            sshc_graph::FRAME_WGSL
        );
        if let Err(e) = crate::back::validate(&module) {
            panic!("{e}\n{module}");
        }
    }
}
