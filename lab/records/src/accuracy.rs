//! Error figures of one image against the truth (the lab's `metrics` computes them): what
//! a sweep's rows store.

use serde::{Deserialize, Serialize};

/// Error figures over one set of pixels, in 0..255 units.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// Root-mean-square error.
    pub rms: f64,
    /// Largest absolute error.
    pub max: f64,
    /// Mean signed error (positive: the technique is too bright on average).
    pub mean: f64,
    /// Pixels the figures are over.
    pub pixels: usize,
    /// Of those, pixels whose visibility was not finite (each counted as an error of 255).
    pub non_finite: usize,
}

/// Accuracy of one image: over the pixels that face the light, and over the penumbra
/// pixels among them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Accuracy {
    /// Pixels whose surface faces the light.
    pub facing: ErrorStats,
    /// Facing pixels with `0 < truth < 1`.
    pub penumbra: ErrorStats,
    /// Facing pixels the truth says are lit (`truth = 1`): a negative mean there is acne
    /// or over-darkening, what a too small depth bias shows (the lab's `metrics::regions`).
    #[serde(default)]
    pub lit: ErrorStats,
    /// Facing pixels in umbra (`truth = 0`): a positive mean there is light leaking or
    /// peter-panning, what a too large bias shows.
    #[serde(default)]
    pub umbra: ErrorStats,
    /// The shadow on the ground (the lab's `metrics::shadow_on_ground`), where the scene has objects that
    /// cast no shadow (`None` otherwise; the lab's `metrics::accuracy` leaves it `None`).
    pub ground: Option<ErrorStats>,
    /// Mean FLIP (the lab's `metrics::flip`) over the facing pixels, 0..1 (`None` where not computed;
    /// the lab's `metrics::accuracy` leaves it `None`; records written before FLIP read as `None`).
    #[serde(default)]
    pub flip: Option<f64>,
}
