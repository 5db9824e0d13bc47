//! What a run of verify takes: the map's size, the light's width, the reference's
//! tolerance and the cascades; checked before anything runs.

use super::plane::QueryPlane;

/// What `verify` runs.
#[derive(Clone, Debug)]
pub struct Options {
    /// The shadow map's size N (the cameras are 2N and N/2).
    pub shadow: u32,
    /// The width of the square light over the query plane (world units; the plane spans 2).
    pub light_width: f64,
    /// How far a reference may differ from the technique beyond what the conditioning of
    /// both f64 evaluations allows (constants written differently, guards such as `1e-12`).
    pub reference_tolerance: f64,
    /// Cascades of the query plane's light ([`QueryPlane::cascade`]; 1: none), split at
    /// `cascade_lambda` by the practical scheme and mixed over the last `cascade_band` of
    /// each slice, as `render --cascades` binds them.
    pub cascades: u32,
    pub cascade_lambda: f32,
    pub cascade_band: f32,
}

impl Options {
    /// Refuse sizes and widths the query plane cannot take.
    pub fn check(&self) -> Result<(), String> {
        let n = self.shadow;
        if !(4..=1024).contains(&n) || !n.is_power_of_two() {
            return Err(format!("the shadow map's size {n} must be a power of two in 4..=1024"));
        }
        if !(self.light_width.is_finite() && (0.0..=2.0).contains(&self.light_width)) {
            return Err(format!(
                "the light's width {} must lie in [0, 2] (the query plane spans 2 world units)",
                self.light_width
            ));
        }
        if !(self.reference_tolerance.is_finite() && self.reference_tolerance >= 0.0) {
            return Err(format!(
                "the reference tolerance {} must be finite and not negative",
                self.reference_tolerance
            ));
        }
        let max = sshc_runtime::light::MAX_CASCADES;
        if !(1..=max).contains(&self.cascades) {
            return Err(format!("{} cascades: a light has 1 to {max}", self.cascades));
        }
        if !(0.0..=1.0).contains(&self.cascade_lambda) {
            return Err(format!("cascade lambda {}: a weight in [0, 1]", self.cascade_lambda));
        }
        if !(0.0..1.0).contains(&self.cascade_band) {
            return Err(format!("cascade band {}: a fraction of a slice, in [0, 1)", self.cascade_band));
        }
        Ok(())
    }

    /// The view distances bounding the cascades (`cascades + 1` of them).
    pub fn splits(&self) -> Vec<f32> {
        let (near, far) = QueryPlane::view_depths();
        sshc_runtime::light::practical_splits(near, far, self.cascades, self.cascade_lambda).unwrap_or_else(|| vec![near, far])
    }
}

impl Default for Options {
    fn default() -> Options {
        Options {
            shadow: 32,
            light_width: 0.5,
            reference_tolerance: 1e-6,
            cascades: 1,
            cascade_lambda: 0.75,
            cascade_band: 0.1,
        }
    }
}
