//! Light kinds, the light models a technique assumes, and what a graph specialised for a
//! scene assumes of it.

use serde::{Deserialize, Serialize};

/// What a graph specialised for a scene assumes of it: the kind of its light,
/// from which the compiler folds the light inputs that are 0 for every light of that kind
/// ([`SceneFacts::zero_inputs`]), and the least depth its casters reach in the light's
/// view, from which it narrows the range of what the Depth pass writes (and so the
/// precision a channel left open takes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFacts {
    /// The scene file it was specialised for (for messages).
    pub scene: String,
    /// The kind of the scene's light.
    pub light: LightKind,
    /// The least normalised depth of the scene's casters in each light's view
    /// ([`caster_depth_floor`]): the Depth pass writes values in `[depth_floor, 1]`.
    /// Absent: `[0, 1]` (no caster, or facts from before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_floor: Option<f32>,
}

/// The least normalised linear depth, `(-(view p).z - near) / (far - near)` clamped to
/// [0, 1] (the Depth pass's), of the first `casting` vertices of `vertices` (interleaved
/// position and normal, 6 floats a vertex; `None`: all) under the column-major
/// `light_view`; `None` without a casting vertex. Depth is affine in position, so a
/// triangle's least depth inside the view is at least its vertices' least: a lower bound
/// of what the Depth pass writes where a caster covers a texel (elsewhere it writes 1).
/// One function for the facts a compilation assumes and the runtime's check of a scene
/// against them, so both compute the same value.
pub fn caster_depth_floor(vertices: &[f32], casting: Option<u32>, light_view: &[f32; 16], near: f32, far: f32) -> Option<f32> {
    let n = casting.map_or(vertices.len() / 6, |c| (c as usize).min(vertices.len() / 6));
    let span = far - near;
    if span.is_nan() || span <= 0.0 {
        return None;
    }
    vertices
        .chunks_exact(6)
        .take(n)
        .map(|v| {
            // row 2 of the column-major matrix: the view-space z
            let z = light_view[2] * v[0] + light_view[6] * v[1] + light_view[10] * v[2] + light_view[14];
            ((-z - near) / span).clamp(0.0, 1.0)
        })
        .reduce(f32::min)
}

impl SceneFacts {
    /// The light inputs (by their names in techniques) that are 0 for every light of the
    /// kind: a light's size, radius or half-extent and its width are 0 for a point, a
    /// directional light and a distant disk (whose extent is its angle); the spread is 0
    /// for every light but a distant disk.
    pub fn zero_inputs(&self) -> Vec<&'static str> {
        let k = self.light;
        [
            ("light_size", k.has_size()),
            ("light_width", k.has_width()),
            ("light_spread", k.has_spread()),
        ]
        .into_iter()
        .filter(|(_, has)| !has)
        .map(|(name, _)| name)
        .collect()
    }
}

/// The kinds of light. This is the one list: a technique's [`LightModel`] is `Any` or one
/// of these (the compiler parses `light:` through [`LightKind::from_name`]), and a scene's
/// light, which adds the geometry, says its kind with `Light::kind`. Adding a kind means
/// a variant here, its entry in [`LightKind::ALL`], and the arms the compiler then asks
/// for (names, [`LightModel`], the scene's geometry).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LightKind {
    Point,
    Directional,
    Sphere,
    Disk,
    Rectangle,
    /// A linear light; a technique renders one view per sample along it (Heidrich et al. 2000).
    Segment,
    /// A disk at infinity given by its angular diameter (Lawlor 2006).
    DistantDisk,
    /// A triangle; per-sample techniques take its edges as linear lights (Heidrich et al.
    /// 2000, section 4, figure 8).
    Triangle,
}

impl LightKind {
    pub const ALL: [LightKind; 8] = [
        LightKind::Point,
        LightKind::Directional,
        LightKind::Sphere,
        LightKind::Disk,
        LightKind::Rectangle,
        LightKind::Segment,
        LightKind::DistantDisk,
        LightKind::Triangle,
    ];

    /// The name scene and technique files write.
    pub fn name(self) -> &'static str {
        match self {
            LightKind::Point => "Point",
            LightKind::Directional => "Directional",
            LightKind::Sphere => "Sphere",
            LightKind::Disk => "Disk",
            LightKind::Rectangle => "Rectangle",
            LightKind::Segment => "Segment",
            LightKind::DistantDisk => "DistantDisk",
            LightKind::Triangle => "Triangle",
        }
    }

    pub fn from_name(name: &str) -> Option<LightKind> {
        LightKind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Whether the light has a size in world units (`light_size`: a radius or half-extent):
    /// 0 for a point and a directional light, and for a distant disk, whose extent is its
    /// angle.
    pub fn has_size(self) -> bool {
        match self {
            LightKind::Sphere
            | LightKind::Disk
            | LightKind::Rectangle
            | LightKind::Segment
            | LightKind::Triangle
            | LightKind::DistantDisk => true,
            LightKind::Point | LightKind::Directional => false,
        }
    }

    /// Whether the light has a width across the shadow map (`light_width`); 0 for a point,
    /// a directional light and a distant disk.
    pub fn has_width(self) -> bool {
        match self {
            LightKind::Sphere | LightKind::Disk | LightKind::Rectangle | LightKind::Segment | LightKind::Triangle => true,
            LightKind::Point | LightKind::Directional | LightKind::DistantDisk => false,
        }
    }

    /// Whether the light has an angular spread (`light_spread`): a distant disk only.
    pub fn has_spread(self) -> bool {
        match self {
            LightKind::DistantDisk => true,
            LightKind::Point
            | LightKind::Directional
            | LightKind::Sphere
            | LightKind::Disk
            | LightKind::Rectangle
            | LightKind::Segment
            | LightKind::Triangle => false,
        }
    }

    /// Whether a technique's model of it says how many views it renders along the light
    /// (`Segment(samples: N)`: one view per sample, Heidrich et al. 2000).
    pub fn takes_samples(self) -> bool {
        match self {
            LightKind::Segment => true,
            LightKind::Point
            | LightKind::Directional
            | LightKind::Sphere
            | LightKind::Disk
            | LightKind::Rectangle
            | LightKind::DistantDisk
            | LightKind::Triangle => false,
        }
    }

    /// True for lights at infinity (orthographic light views).
    pub fn is_distant(self) -> bool {
        match self {
            LightKind::Directional | LightKind::DistantDisk => true,
            LightKind::Point | LightKind::Sphere | LightKind::Disk | LightKind::Rectangle | LightKind::Segment | LightKind::Triangle => {
                false
            }
        }
    }
}

/// The light a technique assumes: any, or a [`LightKind`] (with the number of views
/// along a segment light).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum LightModel {
    Any,
    Point,
    Directional,
    Sphere,
    Disk,
    Rectangle,
    Segment { samples: u32 },
    DistantDisk,
    Triangle,
}

impl LightModel {
    /// The kind assumed; `None` for `Any`.
    pub fn kind(self) -> Option<LightKind> {
        match self {
            LightModel::Any => None,
            LightModel::Point => Some(LightKind::Point),
            LightModel::Directional => Some(LightKind::Directional),
            LightModel::Sphere => Some(LightKind::Sphere),
            LightModel::Disk => Some(LightKind::Disk),
            LightModel::Rectangle => Some(LightKind::Rectangle),
            LightModel::Segment { .. } => Some(LightKind::Segment),
            LightModel::DistantDisk => Some(LightKind::DistantDisk),
            LightModel::Triangle => Some(LightKind::Triangle),
        }
    }

    /// The model assuming `kind`; `samples` is the number of views along a segment light
    /// (ignored for the other kinds).
    pub fn of(kind: LightKind, samples: u32) -> LightModel {
        match kind {
            LightKind::Point => LightModel::Point,
            LightKind::Directional => LightModel::Directional,
            LightKind::Sphere => LightModel::Sphere,
            LightKind::Disk => LightModel::Disk,
            LightKind::Rectangle => LightModel::Rectangle,
            LightKind::Segment => LightModel::Segment { samples },
            LightKind::DistantDisk => LightModel::DistantDisk,
            LightKind::Triangle => LightModel::Triangle,
        }
    }

    /// Whether a technique assuming this model is meant for a light of `kind`.
    pub fn accepts(self, kind: LightKind) -> bool {
        self.kind().is_none_or(|k| k == kind)
    }
}
