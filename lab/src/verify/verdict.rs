//! A row's counts and its verdict: each receiver's GPU value against its allowance,
//! the reference's comparison, the debug outputs', and what an allowance too wide to tell
//! lit from shadowed ([`TELLS_APART`]) leaves unchecked.

use sshc::eval::Allowed;

/// The verdict of one (input, camera).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Every receiver within its allowance, and none whose agreement rests on an allowance
    /// too wide to have caught a real difference ([`TELLS_APART`]).
    Agrees,
    Differs,
    Lossy,
    /// Nothing outside its allowance and nothing lossy, but some receiver's GPU value is
    /// [`TELLS_APART`] or more from the CPU's, admitted only by an allowance of
    /// [`TELLS_APART`] or more: not a failure, never agreement.
    Unchecked,
}

impl Verdict {
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Differs => "DIFFERS",
            Verdict::Lossy => "LOSSY",
            Verdict::Unchecked => "UNCHECKED",
        }
    }

    /// Whether the verdict fails the command (DIFFERS, LOSSY): UNCHECKED does not by itself.
    pub fn fails(self) -> bool {
        matches!(self, Verdict::Differs | Verdict::Lossy)
    }
}

/// The allowance (half-width of the interval allowed about the CPU's visibility, in [0, 1])
/// from which a comparison can no longer tell a lit pixel from a shadowed one, and the
/// difference that is a real one: 1/2 of the visibility's range.
///
/// Derivation. The allowed interval `[lo, hi]` lies within `value -+ a`, of width at most
/// `2a`. A fully lit receiver reads 1 and a fully shadowed one 0, a distance of 1 apart:
/// an interval of width `2a < 1` never holds both, so wherever it lies, a GPU that reads
/// lit where the CPU reads shadowed (or the reverse) is caught; at `a >= 1/2` an interval
/// about `1/2` holds both, and a comparison under it can pass a pixel lit for one that is
/// shadowed. Conversely, two visibilities in [0, 1] that are 1/2 or more apart lie on
/// either side of 1/2 (if both were below it, or both above, they would be closer): one
/// reads more lit than shadowed, the other more shadowed than lit. So a receiver whose
/// GPU value is within its allowance but 1/2 or more from the CPU's, under an allowance
/// of 1/2 or more, is a real difference that only the allowance excuses: UNCHECKED.
/// A receiver under a wide allowance whose values are closer than 1/2 shows no such
/// difference, and one under an allowance below 1/2 would have been caught (DIFFERS), so
/// a row with neither kind of receiver AGREES. The same 1/2 is the `loose` count's.
pub const TELLS_APART: f64 = 0.5;

/// Whether the GPU's `got` is admitted by `e` only because `e`'s allowance is too wide to
/// tell lit from shadowed ([`TELLS_APART`]): within the allowance, but a real difference.
/// Judged on visibilities (and a reference's), whose range is [0, 1]; debug outputs, of
/// any range, are not.
pub fn unchecked(got: f64, e: &Allowed) -> bool {
    e.admits(got) && e.half_width() >= TELLS_APART && (got - e.value).abs() >= TELLS_APART
}

/// One receiver compared, kept for the worst of a row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Worst {
    pub pixel: (usize, usize),
    pub got: f64,
    pub expected: f64,
    pub allowance: f64,
}

impl Worst {
    /// |got - expected| over the allowance.
    pub fn ratio(&self) -> f64 {
        let diff = (self.got - self.expected).abs();
        if diff == 0.0 { 0.0 } else { diff / self.allowance }
    }
}

/// The comparison of one (input, camera).
#[derive(Clone, Debug)]
pub struct Row {
    pub input: String,
    pub camera: u32,
    /// Receivers compared.
    pub receivers: usize,
    /// Receivers whose allowance is at least 1/2 ([`TELLS_APART`]): a site there jumps (a
    /// tie), and a GPU value 1/2 or more from the CPU's there leaves the row UNCHECKED.
    pub loose: usize,
    /// Receivers outside their allowance.
    pub outside: usize,
    /// Receivers within their allowance only because it is too wide to tell lit from
    /// shadowed ([`unchecked`]; with a reference, its comparisons counted too).
    pub unchecked: usize,
    /// The unchecked receiver with the largest difference.
    pub unchecked_worst: Option<Worst>,
    pub max_diff: f64,
    pub median_allowance: f64,
    /// The receiver with the largest difference over its allowance.
    pub worst: Option<Worst>,
    /// The 99th percentile over receivers of what storage rounding alone does.
    pub storage: f64,
    /// The reference's comparison: receivers outside, largest difference and its worst.
    pub reference: Option<(usize, f64, Option<Worst>)>,
    pub verdict: Verdict,
    /// Every receiver compared: its pixel index, the GPU's value, the CPU's, and the
    /// difference over the allowance (above 1: outside).
    pub compared: Vec<(usize, f64, f64, f64)>,
    /// Channels with a declared range (`range: (lo, hi)`) whose stored values it clamped,
    /// and at how many texels (every cascade's summed).
    pub clamped: Vec<(String, usize)>,
    /// The Shade's debug outputs (a build with them, `--debug`), each compared as the
    /// visibility is: every component at every receiver, each cascade's own.
    pub debug: Vec<DebugRow>,
}

/// One debug output's comparison over a row's receivers: the GPU's value (read back from
/// its texture) against the CPU's f64 evaluation of the same expression, within the same
/// running error bound as the visibility's, without the clamp.
#[derive(Clone, Debug, PartialEq)]
pub struct DebugRow {
    pub name: String,
    /// Values compared (receivers x components x cascades).
    pub values: usize,
    /// Values outside their allowance.
    pub outside: usize,
    pub max_diff: f64,
    /// The value with the largest difference over its allowance.
    pub worst: Option<Worst>,
}

impl DebugRow {
    /// Compare the GPU's `got` with the CPU's allowed value `e` at `pixel` (two NaNs agree:
    /// the expression is undefined there on both).
    pub(super) fn add(&mut self, pixel: (usize, usize), got: f64, e: &Allowed) {
        self.values += 1;
        if got.is_nan() && e.value.is_nan() {
            return;
        }
        tally((&mut self.outside, &mut self.max_diff, &mut self.worst), pixel, got, e);
    }
}

/// Count one receiver's `got` against its allowed `e` into a row's (outside, largest
/// difference, worst): whether it lies outside, and the difference kept where largest.
fn tally((outside, max_diff, worst): (&mut usize, &mut f64, &mut Option<Worst>), pixel: (usize, usize), got: f64, e: &Allowed) -> Worst {
    let w = Worst {
        pixel,
        got,
        expected: e.value,
        allowance: e.half_width(),
    };
    let diff = (got - e.value).abs();
    *max_diff = if diff.is_nan() { f64::NAN } else { max_diff.max(diff) };
    if !e.admits(got) {
        *outside += 1;
    }
    if worst.is_none_or(|x| w.ratio() > x.ratio() || w.ratio().is_nan()) {
        *worst = Some(w);
    }
    w
}

impl Row {
    /// An empty row of `input` under `camera` (nothing compared yet: it agrees).
    pub fn new(input: &str, camera: u32, reference: bool) -> Row {
        Row {
            input: input.to_string(),
            camera,
            receivers: 0,
            loose: 0,
            outside: 0,
            unchecked: 0,
            unchecked_worst: None,
            max_diff: 0.0,
            median_allowance: 0.0,
            worst: None,
            storage: 0.0,
            reference: reference.then_some((0, 0.0, None)),
            verdict: Verdict::Agrees,
            compared: Vec::new(),
            clamped: Vec::new(),
            debug: Vec::new(),
        }
    }

    /// Count the GPU's `got` at camera pixel `i` against the CPU's allowed `e`: outside,
    /// loose (allowance of 1/2 or more), unchecked ([`unchecked`]), and the largest
    /// difference and worst receiver.
    pub fn compare(&mut self, i: usize, got: f64, e: &Allowed) {
        let camera = self.camera.max(1) as usize;
        let at = (i % camera, i / camera);
        let w = tally((&mut self.outside, &mut self.max_diff, &mut self.worst), at, got, e);
        let ratio = if e.admits(got) {
            w.ratio().min(1.0)
        } else {
            w.ratio().max(1.0 + f64::EPSILON)
        };
        self.compared.push((i, got, e.value, ratio));
        if e.half_width() >= TELLS_APART {
            self.loose += 1;
        }
        if unchecked(got, e) {
            self.note_unchecked(w);
        }
    }

    /// Count the reference's f64 evaluation `f` against the technique's `t` at camera pixel
    /// `i`, their intervals widened by `tol`: outside where they do not meet, unchecked where
    /// they meet only because they are wide ([`TELLS_APART`] or more apart).
    pub fn compare_reference(&mut self, i: usize, t: &Allowed, f: &Allowed, tol: f64) {
        let camera = self.camera.max(1) as usize;
        let w = Worst {
            pixel: (i % camera, i / camera),
            got: f.value,
            expected: t.value,
            allowance: t.half_width() + f.half_width() + tol,
        };
        let Some((out, max, worst)) = self.reference.as_mut() else { return };
        let diff = (f.value - t.value).abs();
        *max = max.max(diff);
        let met = overlap(t, f, tol);
        if !met {
            *out += 1;
        }
        if worst.is_none_or(|x| w.ratio() > x.ratio()) {
            *worst = Some(w);
        }
        // intervals that meet across a difference of 1/2 or more are together that wide
        if met && diff >= TELLS_APART {
            self.note_unchecked(w);
        }
    }

    fn note_unchecked(&mut self, w: Worst) {
        self.unchecked += 1;
        let diff = |w: &Worst| (w.got - w.expected).abs();
        if self.unchecked_worst.is_none_or(|x| diff(&w) > diff(&x)) {
            self.unchecked_worst = Some(w);
        }
    }

    /// The row's verdict from what it counted: DIFFERS where anything (the visibility, the
    /// reference, a debug output) lies outside its allowance; LOSSY where storage rounding
    /// alone moves the visibility by more than [`sshc::eval::WARN_ABOVE`] at
    /// [`LOSSY_SHARE`] of the receivers; UNCHECKED where some receiver agrees only under an
    /// allowance too wide to tell lit from shadowed; agrees otherwise.
    pub fn judge(&self) -> Verdict {
        if self.outside > 0 || self.reference.is_some_and(|r| r.0 > 0) || self.debug.iter().any(|d| d.outside > 0) {
            Verdict::Differs
        } else if self.storage > sshc::eval::WARN_ABOVE {
            Verdict::Lossy
        } else if self.unchecked > 0 {
            Verdict::Unchecked
        } else {
            Verdict::Agrees
        }
    }
}

/// Receivers at or past this share of storage error make a row lossy.
pub const LOSSY_SHARE: f64 = 0.01;

/// Whether two evaluations' intervals meet once widened by `tol`.
fn overlap(a: &Allowed, b: &Allowed, tol: f64) -> bool {
    a.lo - tol <= b.hi && b.lo - tol <= a.hi
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verify::{Summary, table, unchecked_note};

    /// An allowed value as the Shade's evaluation gives it: `raw -+ allowance`, clamped to
    /// [0, 1] with the value.
    fn allowed(raw: f64, allowance: f64) -> Allowed {
        let value = raw.clamp(0.0, 1.0);
        Allowed {
            value,
            lo: (raw - allowance).clamp(0.0, 1.0),
            hi: (raw + allowance).clamp(0.0, 1.0),
            raw,
            allowance,
        }
    }

    /// Issue 51: GPU 0.040 against CPU 0.967 within an allowance of 0.967 was reported as
    /// agreement. It is UNCHECKED now, counted as such, and no failure; the receivers beside
    /// it, under tight allowances, still decide the rest.
    #[test]
    fn an_allowance_too_wide_to_tell_lit_from_shadowed_leaves_the_row_unchecked() {
        let mut row = Row::new("essm", 64, false);
        row.compare(0, 0.62, &allowed(0.62, 1e-3));
        row.compare(1, 0.040, &allowed(0.967, 0.967));
        assert_eq!(row.outside, 0, "the GPU value lies within the allowance");
        assert_eq!((row.loose, row.unchecked), (1, 1));
        assert_eq!(row.judge(), Verdict::Unchecked);
        let w = row.unchecked_worst.expect("the unchecked receiver");
        assert_eq!((w.pixel, w.got, w.expected), ((1, 0), 0.040, 0.967));
        // a wide allowance whose values are close shows no real difference
        let mut close = Row::new("tie", 64, false);
        close.compare(0, 0.9, &allowed(0.95, 0.95));
        assert_eq!((close.loose, close.unchecked, close.judge()), (1, 0, Verdict::Agrees));
        // just under 1/2 either way: a tight allowance decides, a close value shows nothing
        let mut edge = Row::new("edge", 64, false);
        edge.compare(0, 0.0, &allowed(0.49, 0.49));
        edge.compare(1, 1.0, &allowed(0.501, 0.5));
        assert_eq!((edge.unchecked, edge.judge()), (0, Verdict::Agrees));
        edge.compare(2, 0.0, &allowed(0.5, 0.5));
        assert_eq!((edge.unchecked, edge.judge()), (1, Verdict::Unchecked));
        // outside its allowance: DIFFERS, whatever else
        row.compare(2, 0.5, &allowed(0.62, 1e-3));
        assert_eq!(row.judge(), Verdict::Differs);
        assert!(Verdict::Differs.fails() && Verdict::Lossy.fails() && !Verdict::Unchecked.fails());

        // a reference that meets the technique only because both are wide
        let mut r = Row::new("reference", 16, true);
        r.compare(0, 0.5, &allowed(0.5, 1e-6));
        r.compare_reference(0, &allowed(0.9, 0.6), &allowed(0.1, 0.2), 1e-6);
        assert_eq!((r.reference.map(|x| x.0), r.unchecked, r.judge()), (Some(0), 1, Verdict::Unchecked));

        // the summary counts it, and says no agreement on every input
        let mut agreeing = Row::new("ramp", 64, false);
        agreeing.compare(0, 0.3, &allowed(0.3, 1e-3));
        let rows: Vec<Row> = [row.clone(), close, agreeing, {
            let mut u = Row::new("essm", 16, false);
            u.compare(0, 0.040, &allowed(0.967, 0.967));
            u
        }]
        .into_iter()
        .map(|mut r| {
            r.verdict = r.judge();
            r
        })
        .collect();
        let s = Summary::of(&rows);
        assert_eq!(
            s,
            Summary {
                agree: 2,
                unchecked: 1,
                differ: 1,
                lossy: 0
            }
        );
        assert_eq!(s.counts(), "2 agree, 1 UNCHECKED, 1 DIFFER, 0 LOSSY (4 rows)");
        let only = Summary::of(&rows[1..]);
        assert!(
            only.line().contains("1 row is UNCHECKED") && !only.line().contains("agrees on every input"),
            "{}",
            only.line()
        );
        assert!(Summary::of(&rows[1..3]).line().starts_with("verdict: agrees on every input"));
        let note = unchecked_note(&rows[3]).expect("a note");
        assert!(
            note.contains("essm (camera 16): UNCHECKED at 1 receiver") && note.contains("0.040000 against 0.967000"),
            "{note}"
        );
        assert!(table(&rows).contains("| UNCHECKED |"));
    }
}
