//! The tuner's search, apart from the GPU: candidates drawn from each technique's space
//! (seeded), successive halving over fidelities (cheap truths and one view first, then
//! more samples and every view), the budget's verdict with the timing noise, and a local
//! refinement of the best along each axis. [`search`] takes the measuring as a closure, so
//! that its rules are tested here on made-up measurements.

use crate::visibility::Rng;
use sshc::tune::{Axis, Domain, Space};

/// One configuration: a technique and its values on the axes that differ from the
/// technique's own (`shadow_map` absent: the scene's own size).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Candidate {
    pub technique: usize,
    /// (axis, RON literal), in the space's axis order.
    pub values: Vec<(String, String)>,
}

impl Candidate {
    /// `name=value ...`, or `defaults`.
    pub fn describe(&self) -> String {
        if self.values.is_empty() {
            return "defaults".into();
        }
        self.values.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")
    }

    pub fn value(&self, axis: &str) -> Option<&str> {
        self.values.iter().find(|(k, _)| k == axis).map(|(_, v)| v.as_str())
    }
}

/// A real value as the tuner writes it: three significant digits, read back as an f32.
fn real(x: f64) -> String {
    let rounded: f64 = format!("{x:.2e}").parse().unwrap_or(x);
    sshc::tune::real_literal(rounded)
}

/// Whether a real axis is searched on a log scale: non-negative, and spanning more than two
/// decades (a depth bias from 0 to 0.1, an exponent from 1 to 1e4).
fn log_scale(lo: f64, hi: f64) -> bool {
    lo >= 0.0 && hi > 0.0 && (lo == 0.0 || hi / lo >= 100.0)
}

/// A value of `axis` drawn at random. Log-scaled reals are drawn log-uniformly from
/// `hi * 1e-4` (or `lo`) to `hi`, and take `lo` itself one time in eight (a bias of 0).
fn draw(axis: &Axis, rng: &mut Rng) -> Option<String> {
    match &axis.domain {
        Domain::Real { lo, hi } if log_scale(*lo, *hi) => {
            if *lo == 0.0 && rng.next_u64().is_multiple_of(8) {
                return Some(real(0.0));
            }
            let a = lo.max(hi * 1e-4).ln();
            Some(real((a + (hi.ln() - a) * rng.next_f64()).exp().clamp(*lo, *hi)))
        }
        Domain::Real { lo, hi } => Some(real((lo + (hi - lo) * rng.next_f64()).clamp(*lo, *hi))),
        Domain::Int { lo, hi } if hi >= lo => {
            let n = (hi - lo + 1) as u64;
            Some((lo + (rng.next_u64() % n) as i64).to_string())
        }
        Domain::Choice(v) if !v.is_empty() => Some(v[(rng.next_u64() % v.len() as u64) as usize].clone()),
        Domain::Int { .. } | Domain::Choice(_) => None,
    }
}

/// The axes of `space` the search varies for these scenes: those not frozen, with more than
/// one value, and `cascades` only where every scene's light is at infinity.
pub fn varying(space: &Space, distant: bool) -> Vec<&Axis> {
    space
        .axes
        .iter()
        .filter(|a| a.varies() && (a.name != "cascades" || distant))
        .collect()
}

/// `n` candidates of technique `t`: its defaults first, then random draws (each axis
/// independently), without repeats, from a generator seeded with `seed` and `t`.
pub fn draw_candidates(t: usize, axes: &[&Axis], n: usize, seed: u64) -> Vec<Candidate> {
    let mut rng = Rng::new(seed ^ (t as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let mut out = vec![Candidate {
        technique: t,
        values: vec![],
    }];
    let mut tries = 0;
    while out.len() < n && tries < n * 20 && !axes.is_empty() {
        tries += 1;
        let values: Vec<(String, String)> = axes
            .iter()
            .filter_map(|a| Some((a.name.clone(), draw(a, &mut rng)?)))
            .filter(|(k, v)| axes.iter().find(|a| a.name == *k).and_then(|a| a.default.as_ref()) != Some(v))
            .collect();
        let c = Candidate { technique: t, values };
        if !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

/// The values of `axis` an exhaustive grid takes: every choice, every integer up to five of
/// them (else five spread evenly), five reals (log-spaced on a log-scaled axis, with `lo`).
pub fn grid_values(axis: &Axis) -> Vec<String> {
    match &axis.domain {
        Domain::Choice(v) => v.clone(),
        Domain::Int { lo, hi } if hi - lo < 5 => (*lo..=*hi).map(|i| i.to_string()).collect(),
        Domain::Int { lo, hi } => {
            let mut v: Vec<String> = (0..5).map(|k| (lo + (hi - lo) * k / 4).to_string()).collect();
            v.dedup();
            v
        }
        Domain::Real { lo, hi } if log_scale(*lo, *hi) => {
            let a = lo.max(hi * 1e-4);
            let mut v = if *lo == 0.0 { vec![real(0.0)] } else { vec![] };
            let n = if *lo == 0.0 { 4 } else { 5 };
            v.extend((0..n).map(|k| real(a * (hi / a).powf(k as f64 / (n - 1) as f64))));
            v
        }
        Domain::Real { lo, hi } => (0..5).map(|k| real(lo + (hi - lo) * k as f64 / 4.0)).collect(),
    }
}

/// Every combination of the axes' [`grid_values`] (the technique's own values written as
/// absent): what `sshc tune --grid` measures, as an exhaustive sweep would.
pub fn grid(t: usize, axes: &[&Axis]) -> Vec<Candidate> {
    let mut out: Vec<Vec<(String, String)>> = vec![vec![]];
    for a in axes {
        let values = grid_values(a);
        out = out
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    if a.default.as_ref() != Some(v) {
                        c.push((a.name.clone(), v.clone()));
                    }
                    c
                })
            })
            .collect();
    }
    out.into_iter().map(|values| Candidate { technique: t, values }).collect()
}

/// The most values of a choice or an integer axis the refinement tries all of (a line
/// search along the axis: error is not convex in a sample count or a map size, so the next
/// value either side can hide the best one); longer axes step to the next value either side.
const LINE_SEARCH: usize = 5;

/// The neighbours of `c` along each axis: a real value halved and doubled (log scale) or
/// moved by a tenth of its range; every other value of a choice or integer axis of at most
/// [`LINE_SEARCH`] values, else the next value either side.
pub fn neighbours(c: &Candidate, axes: &[&Axis]) -> Vec<Candidate> {
    let mut out = Vec::new();
    for a in axes {
        let current = c.value(&a.name).map(str::to_string).or_else(|| a.default.clone());
        let options: Vec<String> = match (&a.domain, current.as_deref()) {
            (Domain::Real { lo, hi }, Some(v)) => {
                let Ok(x) = v.parse::<f64>() else { continue };
                let steps = if log_scale(*lo, *hi) {
                    let floor = lo.max(hi * 1e-4);
                    if x <= 0.0 { vec![floor] } else { vec![x * 0.5, x * 2.0] }
                } else {
                    vec![x - (hi - lo) * 0.1, x + (hi - lo) * 0.1]
                };
                steps.into_iter().map(|y| real(y.clamp(*lo, *hi))).collect()
            }
            (Domain::Int { lo, hi }, Some(_)) if hi - lo < LINE_SEARCH as i64 => (*lo..=*hi).map(|y| y.to_string()).collect(),
            (Domain::Int { lo, hi }, Some(v)) => {
                let Ok(x) = v.parse::<i64>() else { continue };
                [x - 1, x + 1]
                    .into_iter()
                    .filter(|y| (lo..=hi).contains(&y))
                    .map(|y| y.to_string())
                    .collect()
            }
            (Domain::Choice(v), _) if v.len() <= LINE_SEARCH => v.clone(),
            (Domain::Choice(v), cur) => {
                let i = cur.and_then(|c| v.iter().position(|x| x == c));
                match i {
                    Some(i) => [i.checked_sub(1), Some(i + 1)]
                        .into_iter()
                        .flatten()
                        .filter_map(|j| v.get(j).cloned())
                        .collect(),
                    None => v.clone(),
                }
            }
            _ => continue,
        };
        for o in options {
            if Some(&o) == current.as_ref() {
                continue;
            }
            let mut values = c.values.clone();
            let is_default = a.default.as_ref() == Some(&o);
            match values.iter().position(|(k, _)| *k == a.name) {
                Some(p) if is_default => {
                    values.remove(p);
                }
                Some(p) => values[p].1 = o,
                None if is_default => {}
                None => {
                    values.push((a.name.clone(), o));
                    let order = |k: &str| axes.iter().position(|a| a.name == k).unwrap_or(usize::MAX);
                    values.sort_by_key(|(k, _)| order(k));
                }
            }
            let n = Candidate {
                technique: c.technique,
                values,
            };
            if n != *c && !out.contains(&n) {
                out.push(n);
            }
        }
    }
    out
}

/// What a budget says of one configuration's time or memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Verdict {
    /// Within the budget, even at the slow end of its repeated timings.
    Within,
    /// The budget lies inside the spread of its repeated timings: the median decides, and
    /// the row is marked.
    Noise,
    /// Over the budget, even at the fast end of its timings.
    Over,
}

/// The budget's verdict on a figure measured as `samples` (repeated timings, or one exact
/// byte count): within where all are at most `limit`, over where all are above, else noise.
pub fn verdict(samples: &[f64], limit: f64) -> Verdict {
    if samples.iter().all(|&s| s <= limit) {
        Verdict::Within
    } else if samples.iter().all(|&s| s > limit) {
        Verdict::Over
    } else {
        Verdict::Noise
    }
}

/// The median of `v` (NaN for none).
pub fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The fastest and the slowest of `v`, where it holds two or more timings (the charts'
/// error bars).
pub fn spread(v: &[f64]) -> Option<(f64, f64)> {
    if v.len() < 2 {
        return None;
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some((lo, hi))
}

/// A configuration measured at one fidelity, over the scenes and views of that fidelity.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Measured {
    /// The error the search ranks by (the `--metric`), averaged over scenes and views.
    pub error: f64,
    /// The budget figure of each timing: GPU ms, or the ratio to the reference timed beside
    /// it (the largest over the scenes, per repeat).
    pub times: Vec<f64>,
    /// Texture and buffer bytes (the largest over the scenes).
    pub bytes: u64,
}

/// How the search runs.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Fidelities, cheapest first; the last is the final one.
    pub rungs: usize,
    /// Candidates kept after each rung: 1 in `eta`.
    pub eta: usize,
    /// The time limit (ms or ratio) and the byte limit.
    pub time_limit: f64,
    pub memory_limit: Option<u64>,
    /// Rounds of refinement around the best at the final fidelity (0: none).
    pub refine: usize,
    /// How far above the time limit a single timing must lie to count as over it before
    /// the final rung (where timings are repeated and their spread decides): the spread of
    /// one configuration's timings against itself on a shared machine (issue 51 saw 0.53 to
    /// 1.22 on lavapipe; `--noise`).
    pub noise: f64,
}

/// One measurement the search made: the candidate, the rung (fidelity) and the result, or
/// why it was not measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub candidate: Candidate,
    pub rung: usize,
    pub outcome: Outcome,
}

#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    Measured(Measured),
    /// Not run: what it could not meet, known before running (its exact bytes).
    Skipped(String),
    /// It does not compile or bind with these values (the reason).
    Failed(String),
}

impl Step {
    pub fn measured(&self) -> Option<&Measured> {
        match &self.outcome {
            Outcome::Measured(m) => Some(m),
            _ => None,
        }
    }
}

impl Plan {
    /// The budget's verdict on a measurement: the worse of time and memory.
    pub fn verdict(&self, m: &Measured) -> Verdict {
        let t = verdict(&m.times, self.time_limit);
        let mem = self.memory_limit.map_or(Verdict::Within, |l| verdict(&[m.bytes as f64], l as f64));
        match (t, mem) {
            (Verdict::Over, _) | (_, Verdict::Over) => Verdict::Over,
            (Verdict::Noise, _) | (_, Verdict::Noise) => Verdict::Noise,
            _ => Verdict::Within,
        }
    }

    /// Over the time limit beyond the noise allowed a single timing, or over the memory
    /// limit (exact): what drops a configuration before the final rung.
    pub fn surely_over(&self, m: &Measured) -> bool {
        m.times.iter().all(|&t| t > self.time_limit * self.noise) || self.memory_limit.is_some_and(|l| m.bytes > l)
    }

    /// Admitted: within the budget, or within its noise with the median inside it.
    pub fn admits(&self, m: &Measured) -> bool {
        match self.verdict(m) {
            Verdict::Within => true,
            Verdict::Noise => median(&m.times) <= self.time_limit && self.memory_limit.is_none_or(|l| m.bytes <= l),
            Verdict::Over => false,
        }
    }
}

/// What the search found.
#[derive(Clone, Debug)]
pub struct Found {
    /// Every measurement in order.
    pub steps: Vec<Step>,
    /// The best admitted configuration at the final fidelity, if any.
    pub best: Option<(Candidate, Measured)>,
}

impl Found {
    /// Measurements made (skipped and failed ones not counted).
    pub fn evaluations(&self) -> usize {
        self.steps.iter().filter(|s| s.measured().is_some()).count()
    }

    /// The final-fidelity measurements, best first among the admitted, then the rest.
    pub fn finals(&self, plan: &Plan) -> Vec<(&Candidate, &Measured)> {
        let last = plan.rungs - 1;
        let mut v: Vec<(&Candidate, &Measured)> = self
            .steps
            .iter()
            .filter(|s| s.rung == last)
            .filter_map(|s| Some((&s.candidate, s.measured()?)))
            .collect();
        v.sort_by(|a, b| plan.admits(b.1).cmp(&plan.admits(a.1)).then(a.1.error.total_cmp(&b.1.error)));
        v
    }
}

/// Successive halving: every candidate at rung 0; at each rung those over the budget
/// beyond its noise are dropped, and the best `1/eta` of the rest (fewest error) go on to
/// the next rung; at the last rung, `refine` rounds measure the neighbours of the best
/// admitted one. `skip` says before measuring why a candidate cannot meet the budget (its
/// bytes known from the graph); `measure` runs one at a rung. `batch` is told, before each
/// rung and each round of refinement, every configuration about to be measured there (none
/// of whose measurements decide another's skip within the batch): where shards share the
/// work, each measures its part of the batch and waits for the others'. The best admitted
/// one at the final rung is returned: no admitted configuration measured there has a lower
/// error. Where no finalist is admitted, the survivors of the rung before that were not
/// promoted follow in turn, as many at a time, until one is or none is left.
#[allow(clippy::too_many_arguments)]
pub fn search(
    plan: &Plan,
    candidates: Vec<Candidate>,
    axes: &[Vec<&Axis>],
    mut skip: impl FnMut(&Candidate) -> Option<String>,
    mut measure: impl FnMut(&Candidate, usize) -> Result<Measured, String>,
    mut batch: impl FnMut(&[Candidate], usize),
    mut progress: impl FnMut(&str, Option<(&Candidate, &Measured)>),
) -> Found {
    let mut steps: Vec<Step> = Vec::new();
    let mut alive = candidates;
    let last = plan.rungs.max(1) - 1;
    let best_so_far = |steps: &[Step], rung: usize| -> Option<(Candidate, Measured)> {
        steps
            .iter()
            .filter(|s| s.rung == rung)
            .filter_map(|s| Some((s.candidate.clone(), s.measured()?.clone())))
            .filter(|(_, m)| plan.admits(m))
            .min_by(|a, b| a.1.error.total_cmp(&b.1.error))
    };
    let mut run = |c: &Candidate, rung: usize, steps: &mut Vec<Step>| -> Option<Measured> {
        if let Some(s) = steps.iter().find(|s| s.rung == rung && s.candidate == *c) {
            return s.measured().cloned();
        }
        let outcome = match skip(c) {
            Some(why) => Outcome::Skipped(why),
            None => match measure(c, rung) {
                Ok(m) => Outcome::Measured(m),
                Err(e) => Outcome::Failed(e),
            },
        };
        steps.push(Step {
            candidate: c.clone(),
            rung,
            outcome: outcome.clone(),
        });
        match outcome {
            Outcome::Measured(m) => Some(m),
            _ => None,
        }
    };
    // the survivors of the rung before the last that were not promoted, fewest error first:
    // where every finalist turns out over the budget at the final fidelity (one cheap
    // timing read low), the next ones in line are promoted in turn, so that a budget some
    // measured configuration may meet is not reported unmet because the cheap rung's
    // ranking, which knows nothing of the time, sent only slow ones on
    let mut reserve: Vec<Candidate> = Vec::new();
    let mut keep = 1;
    for rung in 0..=last {
        batch(&alive, rung);
        let mut scored: Vec<(Candidate, Measured)> = Vec::new();
        for c in &alive {
            if let Some(m) = run(c, rung, &mut steps) {
                scored.push((c.clone(), m));
            }
            let best = best_so_far(&steps, rung);
            progress(&format!("rung {}/{}", rung + 1, last + 1), best.as_ref().map(|(c, m)| (c, m)));
        }
        if rung == last {
            break;
        }
        // over the budget beyond the noise: out, whatever its error
        scored.retain(|(_, m)| !plan.surely_over(m));
        scored.sort_by(|a, b| a.1.error.total_cmp(&b.1.error));
        keep = scored.len().div_ceil(plan.eta.max(2)).max(1);
        let mut ranked: Vec<Candidate> = scored.into_iter().map(|(c, _)| c).collect();
        reserve = ranked.split_off(keep.min(ranked.len()));
        alive = ranked;
    }
    while best_so_far(&steps, last).is_none() && !reserve.is_empty() {
        let rest = reserve.split_off(keep.min(reserve.len()));
        let next = std::mem::replace(&mut reserve, rest);
        batch(&next, last);
        for c in &next {
            run(c, last, &mut steps);
            let best = best_so_far(&steps, last);
            progress(
                &format!("rung {}/{} (next in line: the finalists are over the budget)", last + 1, last + 1),
                best.as_ref().map(|(c, m)| (c, m)),
            );
        }
    }
    for _ in 0..plan.refine {
        let Some((best, _)) = best_so_far(&steps, last) else { break };
        let before = best_so_far(&steps, last).map(|(_, m)| m.error);
        let round = neighbours(&best, &axes[best.technique]);
        batch(&round, last);
        for n in round {
            run(&n, last, &mut steps);
            let b = best_so_far(&steps, last);
            progress("refining", b.as_ref().map(|(c, m)| (c, m)));
        }
        if best_so_far(&steps, last).map(|(_, m)| m.error) == before {
            break;
        }
    }
    let best = best_so_far(&steps, last);
    Found { steps, best }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn space() -> Space {
        sshc::tune::space(
            r#"Technique(name: "t",
                params: {
                    "bias": Param(ty: F32, default: 0.001, range: (0.0, 0.1)),
                    "N": Param(ty: I32, default: 4, range: (1, 8), fixed: true),
                },
                channels: { "z": Channel(precision: F32) },
                passes: [
                    Depth(name: "depth", writes: "shadow", channel: "z"),
                    Shade(name: "shade", reads: ["shadow"], visibility: "select(0.0, 1.0, d - bias <= sample(z))"),
                ])"#,
        )
        .unwrap()
    }

    #[test]
    fn draws_are_seeded_in_range_and_start_with_the_defaults() {
        let s = space();
        let axes = varying(&s, false);
        assert!(!axes.iter().any(|a| a.name == "cascades"));
        let a = draw_candidates(0, &axes, 30, 7);
        assert_eq!(a, draw_candidates(0, &axes, 30, 7));
        assert_ne!(a, draw_candidates(0, &axes, 30, 8));
        assert_eq!(a.len(), 30);
        assert!(a[0].values.is_empty());
        for c in &a {
            if let Some(b) = c.value("bias") {
                let b: f64 = b.parse().unwrap();
                assert!((0.0..=0.1).contains(&b), "{b}");
            }
            if let Some(n) = c.value("N") {
                assert!((1..=8).contains(&n.parse::<i64>().unwrap()));
            }
            if let Some(m) = c.value("shadow_map") {
                assert!(sshc::tune::SHADOW_MAPS.contains(&m.parse().unwrap()));
            }
        }
        // the log scale reaches small biases: some draw below 0.001
        assert!(a.iter().filter_map(|c| c.value("bias")).any(|b| b.parse::<f64>().unwrap() < 1e-3));
    }

    #[test]
    fn neighbours_step_each_axis_and_stay_in_range() {
        let s = space();
        let axes = varying(&s, false);
        let c = Candidate {
            technique: 0,
            values: vec![("N".into(), "8".into()), ("shadow_map".into(), "256".into())],
        };
        let n = neighbours(&c, &axes);
        let descr: Vec<String> = n.iter().map(Candidate::describe).collect();
        assert!(descr.contains(&"bias=0.0005 N=8 shadow_map=256".to_string()), "{descr:?}");
        assert!(descr.contains(&"bias=0.002 N=8 shadow_map=256".to_string()), "{descr:?}");
        assert!(descr.contains(&"N=7 shadow_map=256".to_string()), "{descr:?}");
        // N = 9 is outside the range; 256 has no smaller neighbour
        assert!(!descr.iter().any(|d| d.contains("N=9")));
        assert!(descr.contains(&"N=8 shadow_map=512".to_string()), "{descr:?}");
        // a choice of five values is searched along its whole line, not only next door
        assert!(descr.contains(&"N=8 shadow_map=4096".to_string()), "{descr:?}");
        assert_eq!(descr.iter().filter(|d| d.contains("shadow_map")).count(), descr.len());
    }

    #[test]
    fn the_grid_is_every_combination_of_each_axis_values() {
        let s = sshc::tune::space(
            r#"Technique(name: "t",
                params: {
                    "bias": Param(ty: F32, default: 0.001, range: (0.0, 0.1)),
                    "N": Param(ty: I32, default: 4, range: (1, 8), fixed: true),
                },
                channels: { "z": Channel(precision: F32) },
                passes: [
                    Depth(name: "depth", writes: "shadow", channel: "z"),
                    Shade(name: "shade", reads: ["shadow"], visibility: "select(0.0, 1.0, d - bias <= sample(z))"),
                ],
                tune: { "precision:z": Frozen, "schedule:shade": Frozen, "shadow_map": [256, 512] })"#,
        )
        .unwrap();
        let axes = varying(&s, false);
        let names: Vec<&str> = axes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["bias", "N", "shadow_map"]);
        assert_eq!(
            grid_values(axes[0]),
            // 0, then four log-spaced from hi * 1e-4 to hi
            ["0.0", "1e-5", "0.000215", "0.00464", "0.1"]
        );
        assert_eq!(grid_values(axes[1]), ["1", "2", "4", "6", "8"]);
        let g = grid(0, &axes);
        assert_eq!(g.len(), 5 * 5 * 2);
        let mut unique = g.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), g.len());
        // the technique's own values are written as absent: its defaults are one of them
        assert!(
            g.iter()
                .any(|c| c.value("N").is_none() && c.value("bias") == Some("0.0") && c.value("shadow_map") == Some("256"))
        );
    }

    #[test]
    fn verdicts_mark_the_noise() {
        assert_eq!(verdict(&[0.9, 1.0, 0.95], 1.0), Verdict::Within);
        assert_eq!(verdict(&[0.9, 1.1], 1.0), Verdict::Noise);
        assert_eq!(verdict(&[1.2, 1.1], 1.0), Verdict::Over);
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(spread(&[0.9, 0.53, 1.22]), Some((0.53, 1.22)));
        assert_eq!(spread(&[0.9]), None);
    }

    /// A made-up world: error falls and time grows with N and the map size, so that the
    /// best configuration under the budget is known; the search must return a configuration
    /// inside the budget, and none it measured at the final rung inside the budget may beat it.
    #[test]
    fn the_search_respects_the_budget_and_returns_the_best_it_measured() {
        let s = space();
        let axes = varying(&s, false);
        let cands = draw_candidates(0, &axes, 27, 3);
        let world = |c: &Candidate| -> (f64, f64, u64) {
            let n: f64 = c.value("N").unwrap_or("4").parse().unwrap();
            let m: f64 = c.value("shadow_map").unwrap_or("512").parse().unwrap();
            let bias: f64 = c.value("bias").unwrap_or("0.001").parse().unwrap();
            let error = 10.0 / n + 2000.0 / m + (bias.max(1e-6).log10() + 3.0).abs();
            (error, 0.2 * n + m / 1024.0, (m * m * 4.0) as u64)
        };
        for (limit, memory) in [(1.5, None), (3.0, Some(4u64 << 20)), (100.0, None)] {
            let plan = Plan {
                rungs: 3,
                eta: 3,
                time_limit: limit,
                memory_limit: memory,
                refine: 2,
                noise: 1.25,
            };
            let found = search(
                &plan,
                cands.clone(),
                std::slice::from_ref(&axes),
                |c| {
                    let (_, _, b) = world(c);
                    memory.filter(|&l| b > l).map(|l| format!("{b} bytes > {l}"))
                },
                |c, rung| {
                    let (e, t, b) = world(c);
                    // lower rungs see the error with a bias, as few truth samples do
                    Ok(Measured {
                        error: e + 0.1 * (2 - rung) as f64,
                        times: vec![t * 0.98, t, t * 1.02],
                        bytes: b,
                    })
                },
                |_, _| {},
                |_, _| {},
            );
            let (best, m) = found.best.clone().expect("something fits");
            assert!(plan.admits(&m), "{limit}: {best:?} {m:?}");
            assert!(median(&m.times) <= limit);
            if let Some(l) = memory {
                assert!(m.bytes <= l);
            }
            for (c, other) in found.finals(&plan) {
                if plan.admits(other) {
                    assert!(m.error <= other.error, "{c:?} {other:?} beats {best:?} {m:?}");
                }
            }
            // nothing over the memory limit was run
            for st in &found.steps {
                if let Some(me) = st.measured() {
                    assert!(memory.is_none_or(|l| me.bytes <= l), "{st:?}");
                }
            }
            assert!(found.evaluations() < cands.len() * 3, "{}", found.evaluations());
        }
    }

    /// One timing a little over the budget before the final rung is noise, not a verdict:
    /// the configuration goes on, and its repeated final timings decide.
    #[test]
    fn a_single_timing_within_the_noise_does_not_drop_a_configuration() {
        let s = space();
        let axes = varying(&s, false);
        let cands = draw_candidates(0, &axes, 6, 5);
        let best = cands[3].clone();
        let plan = Plan {
            rungs: 2,
            eta: 3,
            time_limit: 1.0,
            memory_limit: None,
            refine: 0,
            noise: 1.25,
        };
        let found = search(
            &plan,
            cands.clone(),
            std::slice::from_ref(&axes),
            |_| None,
            |c, rung| {
                let good = *c == best;
                Ok(Measured {
                    error: if good { 0.1 } else { 1.0 },
                    // the best one reads 1.2 once at rung 0 (a noisy machine), 0.9 after
                    times: if rung == 0 {
                        vec![if good { 1.2 } else { 0.5 }]
                    } else {
                        vec![if good { 0.9 } else { 0.5 }; 3]
                    },
                    bytes: 1,
                })
            },
            |_, _| {},
            |_, _| {},
        );
        assert_eq!(found.best.map(|(c, _)| c), Some(best.clone()));
        // beyond the noise it is dropped at rung 0
        let strict = Plan { noise: 1.1, ..plan };
        let found = search(
            &strict,
            cands,
            std::slice::from_ref(&axes),
            |_| None,
            |c, rung| {
                let good = *c == best;
                Ok(Measured {
                    error: if good { 0.1 } else { 1.0 },
                    times: if rung == 0 {
                        vec![if good { 1.2 } else { 0.5 }]
                    } else {
                        vec![0.5; 3]
                    },
                    bytes: 1,
                })
            },
            |_, _| {},
            |_, _| {},
        );
        assert_ne!(found.best.map(|(c, _)| c), Some(best));
    }

    /// The cheap rung ranks by error alone: where every finalist is over the budget at the
    /// final fidelity, the next in line are promoted until one meets it (the CI run of
    /// session 22 reported a budget unmet while a candidate it had timed at half the budget
    /// waited at rung 0).
    #[test]
    fn finalists_over_the_budget_make_way_for_the_next_in_line() {
        let s = space();
        let axes = varying(&s, false);
        let cands = draw_candidates(0, &axes, 9, 3);
        let plan = Plan {
            rungs: 2,
            eta: 3,
            time_limit: 1.0,
            memory_limit: None,
            refine: 0,
            noise: 1.25,
        };
        // error falls with the index; the three most accurate are over the budget at the
        // final fidelity, the others within it
        let rank = |c: &Candidate| cands.iter().position(|x| x == c).unwrap();
        let mut batches = Vec::new();
        let found = search(
            &plan,
            cands.clone(),
            std::slice::from_ref(&axes),
            |_| None,
            |c, rung| {
                let i = rank(c);
                Ok(Measured {
                    error: 1.0 / (i + 1) as f64,
                    times: if rung == 0 || i < 6 { vec![0.5; 3] } else { vec![1.5; 3] },
                    bytes: 1,
                })
            },
            |b, rung| batches.push((b.len(), rung)),
            |_, _| {},
        );
        // rung 0 keeps 3 of 9 (8, 7, 6): all over; the next three (5, 4, 3) follow, and
        // the best of them is chosen
        assert_eq!(batches, vec![(9, 0), (3, 1), (3, 1)]);
        assert_eq!(found.best.map(|(c, _)| rank(&c)), Some(5));
    }

    #[test]
    fn no_configuration_fits_a_budget_none_meets() {
        let s = space();
        let axes = varying(&s, false);
        let plan = Plan {
            rungs: 2,
            eta: 3,
            time_limit: 0.5,
            memory_limit: None,
            refine: 1,
            noise: 1.25,
        };
        let found = search(
            &plan,
            draw_candidates(0, &axes, 9, 1),
            std::slice::from_ref(&axes),
            |_| None,
            |_, _| {
                Ok(Measured {
                    error: 1.0,
                    times: vec![1.0],
                    bytes: 1,
                })
            },
            |_, _| {},
            |_, _| {},
        );
        assert!(found.best.is_none());
    }
}
