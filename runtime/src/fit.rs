//! A light's view computed by the runtime, from what a host knows: the light
//! ([`Light`]: its kind, position or direction, and size) and where the objects are
//! ([`Boxes`]: world-space bounding boxes, which a bound [`crate::gpu::Geometry`] gives
//! under its current transforms). [`LightInputs::fit`] makes the [`LightInputs`] a frame
//! needs (matrices, near and far, extents, and the per-sample views of linear and area
//! lights); [`crate::gpu::Targets::fit_light`] does it every frame for the bound
//! geometry. Explicit matrices remain possible: a host's [`crate::gpu::FrameState`] takes
//! any [`LightInputs`].
//!
//! The math is the crate `sshc-light`, which the lab's scenes use too: a scene's `Scene`
//! and `Casters` fits are these, over its vertices rather than its objects' boxes. Boxes
//! hold their objects, so a fit to them holds them too and is at most as tight; the lab's
//! `View` fit, which clips every triangle to the camera's frustum, stays in the lab.

use crate::error::{Result, RuntimeError};
use crate::frame::{LightInputs, SampleView};
use crate::graph::MAX_LIGHT_SAMPLES;
use sshc_light::glam::Vec3;
use sshc_light::{Light, LightView, Occluders, SampleFit};

/// What a light's view is fitted to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Fit {
    /// Every object's box ([`Light::view`] of their bounds).
    #[default]
    Scene,
    /// The casters' boxes, padded by their penumbra's reach and one guard texel
    /// ([`sshc_light::casters_view`]); the whole scene in depth. Every object's box when
    /// nothing casts.
    Casters,
}

/// World-space axis-aligned boxes (`[min, max]`) of a scene's objects: those that cast
/// shadows and the others.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Boxes {
    pub casters: Vec<[[f32; 3]; 2]>,
    pub others: Vec<[[f32; 3]; 2]>,
}

fn box_corners(b: &[[f32; 3]; 2]) -> [Vec3; 8] {
    sshc_light::corners((Vec3::from_array(b[0]), Vec3::from_array(b[1])))
}

impl Occluders for Boxes {
    fn casters(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.casters.iter().flat_map(box_corners)
    }
    fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.casters.iter().chain(&self.others).flat_map(box_corners)
    }
    fn bounds(&self) -> (Vec3, Vec3) {
        sshc_light::bounds_of(self.points())
    }
    fn has_casters(&self) -> bool {
        !self.casters.is_empty()
    }
}

/// [`Boxes`] with their bounds computed once (each fit asks for them several times).
struct Bounded<'a> {
    boxes: &'a Boxes,
    bounds: (Vec3, Vec3),
}

impl Occluders for Bounded<'_> {
    fn casters(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.boxes.casters()
    }
    fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.boxes.points()
    }
    fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
    fn has_casters(&self) -> bool {
        self.boxes.has_casters()
    }
}

impl Boxes {
    /// Refuse a box that is not finite or whose minimum exceeds its maximum.
    pub fn check(&self) -> Result<()> {
        for (which, list) in [("caster", &self.casters), ("other", &self.others)] {
            for (i, b) in list.iter().enumerate() {
                let finite = b.iter().flatten().all(|c| c.is_finite());
                if !finite || (0..3).any(|a| b[0][a] > b[1][a]) {
                    return Err(RuntimeError::Param(format!(
                        "{which} box {i} is not a box: {b:?} (write finite [min, max] corners)"
                    )));
                }
            }
        }
        Ok(())
    }
}

impl SampleView {
    /// A sample view fitted by `sshc-light` ([`sshc_light::sample_views`]).
    pub fn from_fit(s: &SampleFit) -> SampleView {
        SampleView {
            light_view: s.view.view.to_cols_array(),
            light_view_proj: s.view.view_proj.to_cols_array(),
            position: s.position.to_array(),
            near: s.view.near,
            far: s.view.far,
            light_proj_y: s.view.proj.y_axis.y,
            weights: s.weights,
        }
    }
}

impl LightInputs {
    /// The inputs of `light` seen through view `v`, with its sample views.
    pub fn from_view(light: &Light, v: &LightView, samples: &[SampleFit], samples_closed: bool) -> LightInputs {
        LightInputs {
            view: v.view.to_cols_array(),
            view_proj: v.view_proj.to_cols_array(),
            position: v.position_or_direction.to_array(),
            near: v.near,
            far: v.far,
            size: v.size,
            half_extents: v.half_extents.to_array(),
            angle: v.angle,
            proj_y: v.proj.y_axis.y,
            orthographic: v.orthographic,
            samples: samples.iter().map(SampleView::from_fit).collect(),
            samples_closed,
            kind: Some(light.kind()),
        }
    }

    /// The inputs of `light` with its view fitted to `boxes` as `fit` says, for a shadow
    /// map of `shadow_size` texels a side, and `samples` sample views (0 for graphs that
    /// render none: [`crate::graph::PassGraph::samples`] where a pass renders per light
    /// sample), each fitted as the centre is. Refused: a light that is not finite or has a
    /// negative size, boxes that are not boxes, and samples the light cannot give (see
    /// [`Light::sample_chain`]).
    pub fn fit(light: &Light, boxes: &Boxes, fit: Fit, shadow_size: u32, samples: u32) -> Result<LightInputs> {
        light
            .check()
            .map_err(|e| RuntimeError::Param(format!("the light ({}): {e}", light.kind_name())))?;
        boxes.check()?;
        // the bounds walked once for the centre's fit and every sample's
        let scene = Bounded {
            boxes,
            bounds: sshc_light::bounds_of(boxes.points()),
        };
        let view_of = |l: &Light| match fit {
            Fit::Scene => l.view(scene.bounds),
            Fit::Casters => sshc_light::casters_view(l, &scene, shadow_size),
        };
        let v = view_of(light);
        let (fits, closed) = sshc_light::sample_views(light, samples, MAX_LIGHT_SAMPLES, view_of)
            .map_err(|e| RuntimeError::Param(format!("the light ({}): {e}", light.kind_name())))?;
        Ok(LightInputs::from_view(light, &v, &fits, closed))
    }
}
