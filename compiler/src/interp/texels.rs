//! A stored channel's texels (`Texels`: its levels, with each texel's allowance) and the
//! lookups on them as the GPU performs them: nearest, filtered, box, mip box and a table's
//! texel, each with the allowance of what it reads.

use super::table::{Table, TableModel};
use super::{Model, half_step};
use crate::front::ast::Precision;
use crate::ir::PlacedSlot;

/// One level of one stored channel: values and their allowances, row-major.
#[derive(Clone, Debug)]
pub(super) struct Level {
    pub(super) size: usize,
    pub(super) v: Vec<f64>,
    pub(super) a: Vec<f64>,
}

impl Level {
    pub(super) fn at(&self, x: i64, y: i64) -> (f64, f64) {
        let last = self.size as i64 - 1;
        let k = (y.clamp(0, last) * (last + 1) + x.clamp(0, last)) as usize;
        (self.v[k], self.a[k])
    }

    /// The texel containing texel-space point `p` (`floor(p)`, clamped to the edge), with its
    /// allowance; where `p` lies within `margin` (the GPU's coordinate error, in this
    /// level's texels) of a texel boundary the neighbour across it may be read instead,
    /// so the difference is allowed too.
    fn nearest(&self, p: [f64; 2], margin: f64) -> (f64, f64) {
        let (x, y) = (p[0].floor() as i64, p[1].floor() as i64);
        let (v, mut a) = self.at(x, y);
        for (axis, c) in p.into_iter().enumerate() {
            let f = c - c.floor();
            let across = if f < margin {
                Some(-1)
            } else if f > 1.0 - margin {
                Some(1)
            } else {
                None
            };
            if let Some(o) = across {
                let (dx, dy) = if axis == 0 { (o, 0) } else { (0, o) };
                a += (self.at(x + dx, y + dy).0 - v).abs();
            }
        }
        (v, a)
    }

    /// Bilinear at uv: the value and the allowance of the blend.
    fn bilinear(&self, uv: [f64; 2]) -> (f64, f64) {
        let n = self.size as f64;
        let (sx, sy) = (uv[0] * n - 0.5, uv[1] * n - 0.5);
        let (x0, y0) = (sx.floor(), sy.floor());
        let (fx, fy) = (sx - x0, sy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t = [self.at(x0, y0), self.at(x0 + 1, y0), self.at(x0, y0 + 1), self.at(x0 + 1, y0 + 1)];
        let w = [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy];
        t.iter()
            .zip(w)
            .fold((0.0, 0.0), |(v, a), ((tv, ta), wk)| (v + wk * tv, a + wk * ta))
    }
}

/// A stored channel: its levels (one without mips) and, read by the box lookups and
/// `nearest` on a table, the table over level 0.
#[derive(Clone, Debug)]
pub(super) struct Texels {
    pub(super) levels: Vec<Level>,
    pub(super) sat: Option<Table>,
    /// What a filtered lookup's result may be off by beyond its texels' allowance: one code
    /// of an 8- or 16-bit unorm format, which a device may filter in fixed point and round
    /// to a code (lavapipe filters 8-bit formats so: tests/tests/lookups.rs measures its
    /// bilinear result within 2^-8 + 1/255 of the exact blend); 0 for float formats.
    pub(super) code: f64,
}

impl Texels {
    pub(super) fn new(levels: Vec<Level>, slot: &PlacedSlot) -> Texels {
        Texels {
            levels,
            sat: None,
            code: match slot.precision {
                Precision::Unorm8 | Precision::Unorm16 => 2.0 * half_step(slot, 0.0),
                Precision::F16 | Precision::F32 => 0.0,
            },
        }
    }
}

impl Texels {
    pub(super) fn base(&self) -> &Level {
        &self.levels[0]
    }

    pub(super) fn texel(&self, x: i64, y: i64) -> (f64, f64) {
        self.base().at(x, y)
    }

    /// The level-0 texel containing texel-space point `p` (`floor(p)`), with its
    /// allowance; where `p` lies within the GPU's coordinate error of a texel boundary the
    /// neighbour across it may be read instead, so the difference is allowed too.
    pub(super) fn nearest(&self, p: [f64; 2], margin: f64) -> (f64, f64) {
        self.base().nearest(p, margin)
    }

    /// `nearest_level`: the texel of level `level` (truncated toward 0 as the GPU's i32 is,
    /// clamped to the chain) containing uv, with [`Texels::nearest`]'s allowance at a
    /// texel boundary (`margin` in level-0 texels, scaled to the level's).
    pub(super) fn nearest_level(&self, uv: [f64; 2], level: f64, margin: f64) -> (f64, f64) {
        let last = self.levels.len() - 1;
        let l = if level.is_nan() {
            0
        } else {
            (level.trunc().max(0.0) as usize).min(last)
        };
        let lv = &self.levels[l];
        let size = lv.size as f64;
        lv.nearest([uv[0] * size, uv[1] * size], margin * size / self.base().size as f64)
    }

    /// Filtered at uv and level of detail `lod` (clamped to the chain): value and allowance.
    pub(super) fn filtered(&self, uv: [f64; 2], lod: f64) -> (f64, f64) {
        let last = self.levels.len() - 1;
        let lod = if lod.is_nan() { 0.0 } else { lod.clamp(0.0, last as f64) };
        let level = (lod.floor() as usize).min(last);
        let lambda = lod - level as f64;
        let (v0, a0) = self.levels[level].bilinear(uv);
        if lambda > 0.0 && level < last {
            let (v1, a1) = self.levels[level + 1].bilinear(uv);
            // each level's blend and the blend between them may be rounded to a code
            (v0 + lambda * (v1 - v0), a0 + lambda * (a1 - a0) + 2.0 * self.code)
        } else {
            (v0, a0 + self.code)
        }
    }

    /// `sample_box`: the mean over a box `w` (uv units, at least a texel each way) centred
    /// at uv, clipped to the map (the centre clamped to it first).
    pub(super) fn boxed(&self, uv: [f64; 2], w: [f64; 2], model: Model) -> (f64, f64) {
        let Some(Table { sums, asums, kind }) = &self.sat else {
            return (f64::NAN, 0.0);
        };
        let n = self.base().size;
        let runs = |c: f64, w: f64| {
            let nf = n as f64;
            let width = (w * nf).max(1.0);
            let centre = if c.is_nan() { 0.0 } else { (c * nf).clamp(0.0, nf) };
            ((centre - 0.5 * width).max(0.0), (centre + 0.5 * width).min(nf))
        };
        let ((x0, x1), (y0, y1)) = (runs(uv[0], w[0]), runs(uv[1], w[1]));
        // the integral of the piecewise-constant texels over [0, x] x [0, y]
        let integral = |s: &[f64], x: f64, y: f64| {
            let row = n + 1;
            let at = |i: usize, j: usize| s[j * row + i];
            let (i, j) = ((x.floor() as usize).min(n), (y.floor() as usize).min(n));
            let (fx, fy) = (x - i as f64, y - j as f64);
            let (i1, j1) = ((i + 1).min(n), (j + 1).min(n));
            // bilinear in the prefix sums is exact for piecewise-constant texels
            let a = at(i, j) + fx * (at(i1, j) - at(i, j));
            let b = at(i, j1) + fx * (at(i1, j1) - at(i, j1));
            a + fy * (b - a)
        };
        let area = (x1 - x0) * (y1 - y0);
        let mean = |s: &[f64]| (integral(s, x1, y1) - integral(s, x0, y1) - integral(s, x1, y0) + integral(s, x0, y0)) / area;
        let v = mean(sums);
        // the GPU weighs exact integer sums in f32
        let weighing = 32.0 * model.ulp(v);
        let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
        let table = match kind {
            TableModel::Codes => 0.0,
            // the mean code is weighed in f32 (relative to the codes' scale), then decoded
            TableModel::Fixed { lo } => 32.0 * model.ulp(v - lo) + 2.0 * model.ulp(v),
            // each corner's entries' rounding, and the lookup's f32 arithmetic on entries as
            // large as the largest it reads (nine rectangles of four entries, weighed and
            // added: 512 roundings of that magnitude bound it, docs/language.md)
            TableModel::Float { err, csums, .. } => {
                let row = n + 1;
                let near = |x: f64, y: f64, s: &[f64]| {
                    let (i, j) = ((x.floor() as usize).min(n), (y.floor() as usize).min(n));
                    let (i1, j1) = ((i + 1).min(n), (j + 1).min(n));
                    [(i, j), (i1, j), (i, j1), (i1, j1)]
                        .iter()
                        .map(|&(a, b)| s[b * row + a].abs())
                        .fold(0.0, f64::max)
                };
                let entries: f64 = corners.iter().map(|&(x, y)| near(x, y, err)).sum();
                let largest = corners.iter().map(|&(x, y)| near(x, y, csums)).fold(0.0, f64::max);
                (entries + 256.0 * model.ulp(largest)) / area + 4.0 * model.ulp(v)
            }
        };
        (v, mean(asums) + weighing + table)
    }

    /// `sample_mip_box`: the mean over the box `w` wide (uv units, a texel at least) centred
    /// at uv (clamped to the map), clipped to the map, of the piecewise-constant texels of
    /// the level where the box spans one to two texels, as WGSL's `mip_box`
    /// (`builtins::MIP_BOX_WGSL`) computes it, in f64. The allowance: the covered texels'
    /// allowances weighed as their values are; what the GPU's coordinate error can do, the
    /// box moved by `margin` (level-0 texels: the receiver's uv error, and a few f32
    /// roundings of coordinates as large as the map) either way along each axis and widened
    /// or narrowed by twice that (which takes a jump to the next level where the width
    /// crosses a power of two); and the f32 weighing of nine texels and the division, 16
    /// roundings of the largest texel read.
    pub(super) fn mip_box(&self, uv: [f64; 2], w: f64, margin: f64, model: Model) -> (f64, f64) {
        let Some((v, a, big)) = self.mip_box_exact(uv, w) else {
            return (f64::NAN, 0.0);
        };
        let n = self.base().size as f64;
        let shift = margin + 4.0 * model.ulp(n);
        let mut moved = 0.0;
        if shift > 0.0 {
            let d = shift / n;
            for moves in [
                [([d, 0.0], 0.0), ([-d, 0.0], 0.0)],
                [([0.0, d], 0.0), ([0.0, -d], 0.0)],
                [([0.0, 0.0], 2.0 * d), ([0.0, 0.0], -2.0 * d)],
            ] {
                let mut worst = 0.0f64;
                for (duv, dw) in moves {
                    let m = self
                        .mip_box_exact([uv[0] + duv[0], uv[1] + duv[1]], w + dw)
                        .map_or(f64::INFINITY, |m| (m.0 - v).abs());
                    worst = worst.max(m);
                }
                moved += worst;
            }
        }
        (v, a + moved + 16.0 * model.ulp(big))
    }

    /// [`Texels::mip_box`]'s value, its texels' weighed allowance and the largest magnitude
    /// among the texels it read (`None` for a width or centre that is not a number).
    fn mip_box_exact(&self, uv: [f64; 2], w: f64) -> Option<(f64, f64, f64)> {
        let n = self.base().size as f64;
        let width = (w * n).clamp(1.0, 4294967040.0);
        if width.is_nan() || uv.iter().any(|c| c.is_nan()) {
            return None;
        }
        let level = ((width as u64).ilog2() as usize).min(self.levels.len() - 1);
        let s = (1u64 << level) as f64;
        let lv = &self.levels[level];
        let size = lv.size as f64;
        let c = [(uv[0] * n).clamp(0.0, n), (uv[1] * n).clamp(0.0, n)];
        let lo = [((c[0] - 0.5 * width) / s).max(0.0), ((c[1] - 0.5 * width) / s).max(0.0)];
        let hi = [((c[0] + 0.5 * width) / s).min(size), ((c[1] + 0.5 * width) / s).min(size)];
        let first = [lo[0].floor(), lo[1].floor()];
        let cover = |k: usize, t: f64| (hi[k].min(t + 1.0) - lo[k].max(t)).max(0.0);
        let (mut v, mut a, mut big) = (0.0, 0.0, 0.0f64);
        for j in 0..3 {
            let y = first[1] + j as f64;
            let wy = cover(1, y);
            for i in 0..3 {
                let x = first[0] + i as f64;
                let wxy = cover(0, x) * wy;
                let (tv, ta) = lv.at((x as i64).min(lv.size as i64 - 1), (y as i64).min(lv.size as i64 - 1));
                if wxy > 0.0 {
                    v += wxy * tv;
                    a += wxy * ta;
                    big = big.max(tv.abs());
                }
            }
        }
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        Some((v / area, a / area, big))
    }

    /// `nearest` on a table: the texel's value from four entries, with what the table's
    /// storage adds (an f32 table's four entries' rounding and three f32 subtractions of
    /// entries that large; a fixed-point table's decode).
    pub(super) fn table_texel(&self, p: [f64; 2], margin: f64, model: Model) -> (f64, f64) {
        let (v, a) = self.nearest(p, margin);
        let extra = match self.sat.as_ref().map(|t| &t.kind) {
            None | Some(TableModel::Codes) => 0.0,
            Some(TableModel::Fixed { lo }) => 4.0 * model.ulp(v - lo) + 2.0 * model.ulp(v),
            Some(TableModel::Float { err, csums, .. }) => {
                let n = self.base().size;
                let row = n + 1;
                // the texel (i, j) is entries (i + 1, j + 1) less its left and upper neighbours
                let (i, j) = (
                    p[0].floor().clamp(0.0, n as f64 - 1.0) as usize,
                    p[1].floor().clamp(0.0, n as f64 - 1.0) as usize,
                );
                // within `margin` of a boundary the neighbour may be read: take the worse
                let (i1, j1) = ((i + 2).min(n), (j + 2).min(n));
                let (mut e, mut big) = (0.0f64, 0.0f64);
                for b in j.saturating_sub(1)..=j1 {
                    for a in i.saturating_sub(1)..=i1 {
                        e = e.max(err[b * row + a]);
                        big = big.max(csums[b * row + a].abs());
                    }
                }
                4.0 * e + 8.0 * model.ulp(big) + 2.0 * model.ulp(v)
            }
        };
        (v, a + extra)
    }
}
