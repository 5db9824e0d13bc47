//! The per-frame state a host owns and changes freely: the camera, the lights, the params
//! and the cascades' slices, as plain data ([`FrameState`]). [`crate::gpu::Targets::prepare`]
//! checks it and writes what changed since the frame before; nothing here touches the GPU.

use crate::device::{Result, RuntimeError};
use crate::frame::{Camera, LightInputs, SceneInputs};
use crate::lights::Slices;
use crate::technique::Technique;

/// A technique's runtime params as the `Params` uniform holds them (fixed params were
/// compiled in). Made with the technique's defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    technique: Technique,
    bytes: Vec<u8>,
}

impl Params {
    /// The technique's params at their defaults.
    pub fn new(technique: &Technique) -> Params {
        Params {
            technique: technique.clone(),
            bytes: technique.graph().default_params(),
        }
    }

    /// Set a runtime param, checked against its declared range; refused, with the reason,
    /// for a param the technique lacks or fixed at compile time.
    pub fn set(&mut self, name: &str, value: f64) -> Result<()> {
        let graph = self.technique.graph();
        let p = graph
            .params
            .iter()
            .find(|p| p.name == name)
            .ok_or_else(|| RuntimeError::Param(format!("the technique has no param `{name}`")))?;
        let Some(off) = p.offset else {
            return Err(RuntimeError::Param(format!(
                "param `{name}` is fixed at compile time; recompile with `--set {name}={value}`"
            )));
        };
        if let Some((lo, hi)) = p.range
            && !(lo..=hi).contains(&value)
        {
            return Err(RuntimeError::Param(format!(
                "param `{name}` = {value} is outside its range [{lo}, {hi}]"
            )));
        }
        let bytes = p.ty.bytes(value);
        self.bytes[off as usize..off as usize + 4].copy_from_slice(&bytes);
        Ok(())
    }

    /// The uniform's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Whether these are `technique`'s params.
    pub(crate) fn of(&self, technique: &Technique) -> bool {
        self.technique.same(technique)
    }
}

/// What a frame shows: plain data, owned by the host, changed between frames without
/// touching the GPU. The lights are as many as the targets were made for (their light `l`
/// is `lights[l]`); cascades of one light carry their `slices`.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameState {
    pub camera: Camera,
    pub lights: Vec<LightInputs>,
    pub params: Params,
    /// Cascades of one light: where they split the camera's view (`None` for lights).
    pub slices: Option<Slices>,
}

impl FrameState {
    /// The camera and lights of a frame of `technique`, its params at their defaults.
    pub fn new(technique: &Technique, camera: Camera, lights: Vec<LightInputs>) -> FrameState {
        FrameState {
            camera,
            lights,
            params: Params::new(technique),
            slices: None,
        }
    }

    /// The camera and light of a triangle-soup scene ([`SceneInputs`]).
    pub fn of_inputs(technique: &Technique, s: &SceneInputs) -> FrameState {
        FrameState::new(technique, s.camera(), vec![s.light_inputs()])
    }

    /// Cascades of one light: `lights[i]` is cascade `i`'s view ([`crate::light::cascade_views`]).
    pub fn cascades(technique: &Technique, camera: Camera, lights: Vec<LightInputs>, slices: Slices) -> FrameState {
        FrameState {
            slices: Some(slices),
            ..FrameState::new(technique, camera, lights)
        }
    }
}
