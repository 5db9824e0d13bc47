//! The lookup functions a Shade pass reads channels and expansions with (`SampleFn`):
//! names, extra arguments and the WGSL of each read (`SampleFn::desc`).

use super::{MIP_BOX, Ty};
use std::fmt;

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

/// WGSL of an unfiltered read of mip level `level` (an i32 expression, clamped to the
/// chain) at `uv`: the texel of that level containing it, clamped to the edge. The level's
/// size is level 0's shifted, not queried at the level, by the rule of [`MIP_BOX_WGSL`](super::MIP_BOX_WGSL)
/// (where lavapipe answered the query wrongly for pixels whose neighbours chose another
/// level; here a GPU test with per-pixel levels passes either way).
fn level_read(tex: &str, layer: &str, uv: &str, level: &str) -> String {
    let level = format!("clamp({level}, 0i, i32(textureNumLevels({tex})) - 1i)");
    let size = format!("max(vec2<i32>(textureDimensions({tex}, 0i)) >> vec2<u32>(u32({level})), vec2<i32>(1i))");
    format!("textureLoad({tex}, clamp(vec2<i32>(floor({uv} * vec2<f32>({size}))), vec2<i32>(0i), {size} - 1i), {layer}, {level})")
}
