//! Cascades on the CPU: a receiver evaluated as the GPU's combining step mixes the cascade
//! whose slice holds its view distance and the next, with the hull over the distance's f32
//! rounding.

use super::plane::QueryPlane;
use sshc::eval::{Allowed, Evaluation, Scratch};
use sshc_runtime::gpu::SampleView;

/// One cascade of the query plane and its evaluations: the technique's (exact and as
/// stored) and, with a reference, both f64 evaluations.
pub(super) struct Cascade<'p> {
    pub(super) plane: QueryPlane,
    pub(super) exact: Evaluation<'p>,
    pub(super) rounded: Evaluation<'p>,
    pub(super) pair: Option<(Evaluation<'p>, Evaluation<'p>)>,
}

/// What one cascade gives a receiver: the allowed visibility, the stored-rounding value
/// and the pair's allowed visibilities.
type Evaluated = (Allowed, f64, Option<(Allowed, Allowed)>);

/// The receiver at camera pixel `i` (world position `p`) evaluated as the GPU shades it:
/// one cascade's evaluations, or with several the combining step's mixture
/// (`CASCADES_WGSL` in runtime/src/lights.rs) of the cascade whose slice holds its view
/// distance and the next. The GPU measures that distance in f32, so the allowance is the
/// hull of the mixtures over every distance within its rounding (`D_ROUNDING`), the slices'
/// kinks included: where the band is 0 the mixture jumps at a split, and both sides are
/// allowed there.
pub(super) fn evaluate(
    cascades: &[Cascade],
    splits: &[f32],
    band: f64,
    i: usize,
    p: [f32; 3],
    samples: &[SampleView],
    scratch: &mut Scratch,
) -> Evaluated {
    let one = |k: usize, scratch: &mut Scratch| -> Evaluated {
        let c = &cascades[k];
        let r = c.plane.receiver(i, p, samples);
        (
            c.exact.visibility(&r, scratch),
            c.rounded.value(&r, scratch),
            c.pair.as_ref().map(|(t, x)| (t.visibility(&r, scratch), x.visibility(&r, scratch))),
        )
    };
    if cascades.len() == 1 {
        return one(0, scratch);
    }
    let (eye, forward) = QueryPlane::camera_axis();
    let d: f64 = (0..3).map(|a| (p[a] as f64 - eye[a] as f64) * forward[a] as f64).sum();
    let last = splits.last().copied().unwrap_or(0.0) as f64;
    let dd = D_ROUNDING * (d.abs() + last);
    let mut seen: [Option<Evaluated>; sshc_runtime::light::MAX_CASCADES as usize] = Default::default();
    let mut at = |k: usize, scratch: &mut Scratch| *seen[k].get_or_insert_with(|| one(k, scratch));
    let (k, t) = cascade_at(d, splits, band);
    let next = (k + 1).min(cascades.len() - 1);
    let (a, b) = (at(k, scratch), at(next, scratch));
    let mut e = mixed(&a.0, &b.0, t);
    // the distances the GPU may have measured: either end of the rounding, and every split
    // and band start between them
    let kinks = splits.windows(2).flat_map(|w| {
        let (near, far) = (w[0] as f64, w[1] as f64);
        [far, far - band * (far - near)]
    });
    for x in [d - dd, d + dd].into_iter().chain(kinks.filter(|x| (x - d).abs() <= dd)) {
        let (k, t) = cascade_at(x, splits, band);
        let next = (k + 1).min(cascades.len() - 1);
        let m = mixed(&at(k, scratch).0, &at(next, scratch).0, t);
        (e.lo, e.hi) = (e.lo.min(m.lo), e.hi.max(m.hi));
    }
    e.allowance = (e.hi - e.value).max(e.value - e.lo);
    let s = a.1 * (1.0 - t) + b.1 * t;
    let f = a.2.zip(b.2).map(|((ta, xa), (tb, xb))| (mixed(&ta, &tb, t), mixed(&xa, &xb, t)));
    (e, s, f)
}

/// The relative rounding of the view distance the combining step measures in f32 (a
/// subtraction and a three-term dot product, each rounding at most 2^-24 of a term no larger
/// than the distance plus the last split), with a factor of 4 to spare.
const D_ROUNDING: f64 = 16.0 * f32::EPSILON as f64 / 2.0;

/// The rounding of WGSL's `mix(a, b, t)` in f32 with a, b in [0, 1] and t itself rounded
/// (a quotient of f32 differences): a few units of 2^-24, four on either side.
const MIX_ROUNDING: f64 = 8.0 * f32::EPSILON as f64 / 2.0;

/// The cascade the combining step takes at view distance `d` and how far it mixes into the
/// next (`CASCADES_WGSL`): the first slice whose far split is at or beyond `d` (the last
/// beyond every split), and the fraction of the band at its far end that `d` has crossed.
fn cascade_at(d: f64, splits: &[f32], band: f64) -> (usize, f64) {
    let n = splits.len().saturating_sub(1).max(1);
    let split = |i: usize| splits.get(i).copied().unwrap_or(f32::MAX) as f64;
    let k = (0..n - 1).find(|&i| d <= split(i + 1)).unwrap_or(n - 1);
    if k + 1 >= n {
        return (k, 0.0);
    }
    let far = split(k + 1);
    let start = far - band * (far - split(k));
    (k, ((d - start) / (far - start).max(1e-30)).clamp(0.0, 1.0))
}

/// Two cascades' allowed values mixed at `t` as the combining step mixes them, with the
/// mixture's f32 rounding.
fn mixed(a: &Allowed, b: &Allowed, t: f64) -> Allowed {
    let m = |x: f64, y: f64| x * (1.0 - t) + y * t;
    let value = m(a.value, b.value);
    let (lo, hi) = (m(a.lo, b.lo) - MIX_ROUNDING, m(a.hi, b.hi) + MIX_ROUNDING);
    Allowed {
        value,
        lo,
        hi,
        raw: value,
        allowance: (hi - value).max(value - lo),
    }
}
