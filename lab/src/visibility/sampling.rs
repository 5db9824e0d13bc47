//! The ray caster's random numbers and its maps from the unit square: a small
//! deterministic generator (SplitMix64; the tuner draws its candidates with it too),
//! stratified jittered samples of the unit square, and the concentric map onto the disk.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

use glam::Vec2;

/// A small deterministic generator (SplitMix64).
#[derive(Clone, Debug)]
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Rng(mix(seed ^ 0x243f_6a88_85a3_08d3))
    }
    /// Uniform in [0, 1), 53 bits.
    pub(crate) fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix(self.0)
    }
    /// Uniform in [0, 1).
    pub(super) fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// SplitMix64's finaliser: a 64-bit mixing function.
pub(super) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Fraction of `n x n` jittered samples `(u, v)` of the unit square (one per cell) for
/// which `visible(u, v)` holds.
pub(super) fn stratified(n: u32, rng: &mut Rng, mut visible: impl FnMut(f32, f32) -> bool) -> f32 {
    let mut lit = 0u32;
    for i in 0..n {
        for j in 0..n {
            let u = (i as f32 + rng.next_f32()) / n as f32;
            let v = (j as f32 + rng.next_f32()) / n as f32;
            lit += u32::from(visible(u.min(1.0), v.min(1.0)));
        }
    }
    lit as f32 / (n * n) as f32
}

/// Shirley–Chiu concentric map from the unit square to the unit disk (area-preserving).
pub(super) fn concentric(u: f32, v: f32) -> Vec2 {
    let a = 2.0 * u - 1.0;
    let b = 2.0 * v - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    Vec2::new(r * phi.cos(), r * phi.sin())
}

#[cfg(test)]
mod tests {

    use super::*;

    #[test]
    fn concentric_map_stays_in_the_disk_and_keeps_halves() {
        for i in 0..=64 {
            for j in 0..=64 {
                let (u, v) = (i as f32 / 64.0, j as f32 / 64.0);
                let p = concentric(u, v);
                assert!(p.length() <= 1.0 + 1e-6);
                // Left half of the square -> left half of the disk (exact half splits).
                if u < 0.5 {
                    assert!(p.x <= 0.0, "{u} {v} -> {p}");
                }
                if u > 0.5 {
                    assert!(p.x >= 0.0, "{u} {v} -> {p}");
                }
            }
        }
    }
}
