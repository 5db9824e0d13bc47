//! The built-in inputs (`Input`): every fact of one input in its descriptor (`Input::desc`),
//! the side of a separable expansion it belongs to, how a light sample's view sees it, and
//! the Geometry primitives whose fragments have it.

use super::Ty;
use crate::front::ast::Primitive;

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
