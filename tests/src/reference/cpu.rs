//! The CPU reference: every pass after Depth in f64, without quantisation.
//!
//! [`prefilter`] runs the Map, Filter and Mipmap passes of a technique and keeps every
//! channel as a chain of f64 images; [`evaluate`] runs the Shade lookup for one receiver.
//! Both are public so that tests can derive tolerances from the same lookups (the texels a
//! filtered lookup blends, [`Chain::lookup`]). CSSM's summed-area tables are f64 prefix
//! sums ([`Table`]); the soft-shadow techniques expose their steps ([`cssm_trace`],
//! [`pcss_trace`]) so that the error model can propagate bounds through them.

use super::{DepthMap, Kind, LightFrame, Query, Resolved, StoredChannel, Technique, check_map, clamp_visibility, resolve};
use std::f64::consts::PI;

/// Visibility at every query, computed in f64 from the exact math of the papers.
pub fn cpu_visibility(t: &Technique, map: &DepthMap, queries: &[Query]) -> Result<Vec<f64>, String> {
    let pre = prefilter(t, map)?;
    Ok(queries.iter().map(|q| evaluate(&pre, q)).collect())
}

/// One square image of f64 texels, row-major, row 0 first.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub size: usize,
    pub texels: Vec<f64>,
}

impl Level {
    /// Texel `(x, y)`, clamped to the edge.
    pub fn at(&self, x: i64, y: i64) -> f64 {
        let last = self.size as i64 - 1;
        self.texels[(y.clamp(0, last) * (last + 1) + x.clamp(0, last)) as usize]
    }

    fn map(&self, f: impl Fn(f64) -> f64) -> Level {
        Level {
            size: self.size,
            texels: self.texels.iter().map(|&v| f(v)).collect(),
        }
    }

    /// Bilinear filtering at uv (texel centres at `(i + 0.5) / size`, clamp to edge): the
    /// value and the smallest and largest of the four texels it blends.
    pub fn bilinear(&self, uv: [f64; 2]) -> LevelLookup {
        let n = self.size as f64;
        let (sx, sy) = (uv[0] * n - 0.5, uv[1] * n - 0.5);
        let (x0, y0) = (sx.floor(), sy.floor());
        let (fx, fy) = (sx - x0, sy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t = [self.at(x0, y0), self.at(x0 + 1, y0), self.at(x0, y0 + 1), self.at(x0 + 1, y0 + 1)];
        let top = t[0] + fx * (t[1] - t[0]);
        let bottom = t[2] + fx * (t[3] - t[2]);
        LevelLookup {
            value: top + fy * (bottom - top),
            min: t.iter().copied().fold(f64::INFINITY, f64::min),
            max: t.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// What a bilinear lookup in one level blends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelLookup {
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

/// A filtered lookup: the value, the level(s) it blends and the weight of the upper level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    pub value: f64,
    /// The finer level used (`floor(lod)`, clamped to the chain).
    pub level: usize,
    pub lower: LevelLookup,
    /// The coarser level and its weight `fract(lod)`, when the lookup blends two levels.
    pub upper: Option<(f64, LevelLookup)>,
}

/// One channel: level 0 and, after a Mipmap pass, the coarser levels.
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    pub levels: Vec<Level>,
}

impl Chain {
    pub fn base(&self) -> &Level {
        &self.levels[0]
    }

    /// `nearest(ch)`: the level-0 texel containing uv.
    pub fn nearest(&self, uv: [f64; 2]) -> f64 {
        let n = self.base().size as f64;
        self.base().at((uv[0] * n).floor() as i64, (uv[1] * n).floor() as i64)
    }

    /// `fetch(ch, dx, dy)`: level-0 texel `floor(uv N - 0.5) + (dx, dy)`, clamped.
    pub fn fetch(&self, uv: [f64; 2], dx: i64, dy: i64) -> f64 {
        let n = self.base().size as f64;
        let (x, y) = ((uv[0] * n - 0.5).floor() as i64, (uv[1] * n - 0.5).floor() as i64);
        self.base().at(x + dx, y + dy)
    }

    /// `sample(ch)` at an explicit level of detail: bilinear within a level, linear between
    /// `floor(lod)` and the next level (trilinear), lod clamped to the chain.
    pub fn sample(&self, uv: [f64; 2], lod: f64) -> f64 {
        self.lookup(uv, lod).value
    }

    /// [`Chain::sample`] with what it blended.
    pub fn lookup(&self, uv: [f64; 2], lod: f64) -> Lookup {
        let last = self.levels.len() - 1;
        let lod = if lod.is_nan() { 0.0 } else { lod.clamp(0.0, last as f64) };
        let level = (lod.floor() as usize).min(last);
        let lambda = lod - level as f64;
        let lower = self.levels[level].bilinear(uv);
        if lambda > 0.0 && level < last {
            let up = self.levels[level + 1].bilinear(uv);
            Lookup {
                value: lower.value + lambda * (up.value - lower.value),
                level,
                lower,
                upper: Some((lambda, up)),
            }
        } else {
            Lookup {
                value: lower.value,
                level,
                lower,
                upper: None,
            }
        }
    }
}

/// A named channel after the technique's Map, Filter and Mipmap passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub name: String,
    pub chain: Chain,
}

/// The images a technique's Shade pass reads, in f64.
#[derive(Clone, Debug, PartialEq)]
pub struct Prefiltered {
    pub technique: Resolved,
    /// The depth map as written by the Depth pass (the Shade pass of hard and PCF reads it).
    pub depth: Chain,
    /// The stored channels, filtered (and mipmapped where the technique builds a mip chain),
    /// plus ESM's `zm` (the max-filtered depth).
    pub channels: Vec<Channel>,
    /// Summed-area tables of the filtered channels, by channel name (CSSM with filter = 1).
    pub tables: Vec<(String, Table)>,
    /// `technique.stored_channels()`, made once: the error models ask for a channel's
    /// range at every term of every query.
    pub stored: Vec<StoredChannel>,
    /// VSSM only, for its error model: the f32 summed-area tables the GPU builds
    /// ([`f32_table`]), by channel name.
    pub f32_tables: Vec<(String, Vec<f32>)>,
    /// MSSM only, for its error model: tables of the 16-bit codes the GPU sums (each
    /// texel's f32 channel value as `round(clamp(v, 0, 1) 65535) / 65535`), by channel name.
    pub fixed_tables: Vec<(String, Table)>,
}

impl Prefiltered {
    pub fn channel(&self, name: &str) -> Option<&Chain> {
        self.channels.iter().find(|c| c.name == name).map(|c| &c.chain)
    }

    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|(n, _)| n == name).map(|(_, t)| t)
    }

    fn chain(&self, name: &str) -> &Chain {
        // Only called with names that `prefilter` created for this technique.
        self.channel(name).unwrap_or(&self.depth)
    }
}

/// Weights of a box filter of width `k` texels.
pub fn box_weights(k: usize) -> Vec<f64> {
    vec![1.0 / k as f64; k]
}

/// Weights of a Gaussian of width `k` texels centred on the texel:
/// `exp(-x^2 / (2 sigma^2))`, normalised to sum 1 over the `k` taps.
pub fn gaussian_weights(k: usize, sigma: f64) -> Vec<f64> {
    let r = (k / 2) as f64;
    let w: Vec<f64> = (0..k)
        .map(|i| {
            let x = i as f64 - r;
            (-x * x / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let sum: f64 = w.iter().sum();
    w.into_iter().map(|v| v / sum).collect()
}

/// A separable convolution (Annen eq. 5.2) with `weights` (odd count, centred) along x then
/// y, reads outside the image clamped to the edge.
pub fn convolve(img: &Level, weights: &[f64]) -> Level {
    let r = (weights.len() / 2) as i64;
    let n = img.size as i64;
    let pass = |src: &Level, axis: (i64, i64)| -> Level {
        let mut texels = Vec::with_capacity(src.texels.len());
        for y in 0..n {
            for x in 0..n {
                let mut sum = 0.0;
                for (t, w) in weights.iter().enumerate() {
                    let o = t as i64 - r;
                    sum += w * src.at(x + o * axis.0, y + o * axis.1);
                }
                texels.push(sum);
            }
        }
        Level { size: src.size, texels }
    };
    pass(&pass(img, (1, 0)), (0, 1))
}

/// The maximum over a `k x k` window centred on each texel, clamped to the edge.
pub fn max_filter(img: &Level, k: usize) -> Level {
    let r = (k / 2) as i64;
    let n = img.size as i64;
    let mut texels = Vec::with_capacity(img.texels.len());
    for y in 0..n {
        for x in 0..n {
            let mut m = f64::NEG_INFINITY;
            for dy in -r..=r {
                for dx in -r..=r {
                    m = m.max(img.at(x + dx, y + dy));
                }
            }
            texels.push(m);
        }
    }
    Level { size: img.size, texels }
}

/// A mean mip chain down to 1 x 1: level `l` has size `max(1, N >> l)`, each texel the mean
/// of the 2 x 2 texels below it (clamped at the edge of an odd-sized level).
pub fn mip_chain(base: Level) -> Chain {
    let mut levels = vec![base];
    while let Some(prev) = levels.last().filter(|l| l.size > 1) {
        let size = (prev.size / 2).max(1);
        let mut texels = Vec::with_capacity(size * size);
        for y in 0..size as i64 {
            for x in 0..size as i64 {
                let (px, py) = (2 * x, 2 * y);
                let sum = prev.at(px, py) + prev.at(px + 1, py) + prev.at(px, py + 1) + prev.at(px + 1, py + 1);
                texels.push(0.25 * sum);
            }
        }
        levels.push(Level { size, texels });
    }
    Chain { levels }
}

/// A summed-area table (Crow 1984; Annen 2008, 8.3.1) of one f64 image, read by
/// `sample_box` (docs/language.md 8.7).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub size: usize,
    /// `(size + 1)^2` prefix sums: entry `(x, y)` sums the texels `i < x`, `j < y`.
    sums: Vec<f64>,
}

/// One axis of a box: up to three runs of texels `[start, end)` with the fraction of each
/// texel the box covers (a partial first texel, whole texels, a partial last texel).
pub type BoxRuns = [(i64, i64, f64); 3];

/// The runs of one axis of `sample_box` in texel units: the box of width
/// `max(w * size, 1)` texels ("at least one texel each way") centred at `c * size`, clipped
/// to `[0, size]`, and its clipped length. Reading of docs/language.md for a centre outside
/// the map (not specified there): the centre is clamped to the map first, so the clipped box
/// is never empty (at least half a texel).
pub fn box_runs(size: usize, c: f64, w: f64) -> (BoxRuns, f64) {
    let n = size as f64;
    let wt = (w * n).max(1.0);
    let centre = (c * n).clamp(0.0, n);
    let centre = if centre.is_nan() { 0.0 } else { centre };
    let (x0, x1) = ((centre - 0.5 * wt).max(0.0), (centre + 0.5 * wt).min(n));
    let last = size as i64 - 1;
    let a = (x0.floor() as i64).clamp(0, last);
    let b = (x1.ceil() as i64 - 1).clamp(0, last);
    let runs = if a == b {
        [(a, a + 1, x1 - x0), (0, 0, 0.0), (0, 0, 0.0)]
    } else {
        [(a, a + 1, (a + 1) as f64 - x0), (a + 1, b, 1.0), (b, b + 1, x1 - b as f64)]
    };
    (runs, x1 - x0)
}

impl Table {
    pub fn new(level: &Level) -> Table {
        let n = level.size;
        let mut sums = vec![0.0; (n + 1) * (n + 1)];
        for y in 0..n {
            for x in 0..n {
                sums[(y + 1) * (n + 1) + x + 1] =
                    level.texels[y * n + x] + sums[y * (n + 1) + x + 1] + sums[(y + 1) * (n + 1) + x] - sums[y * (n + 1) + x];
            }
        }
        Table { size: n, sums }
    }

    /// The sum of texels `[x0, x1) x [y0, y1)` (0 for an empty block).
    pub fn block(&self, x: (i64, i64), y: (i64, i64)) -> f64 {
        if x.1 <= x.0 || y.1 <= y.0 {
            return 0.0;
        }
        let row = self.size as i64 + 1;
        let s = |x: i64, y: i64| self.sums[(y * row + x) as usize];
        s(x.1, y.1) - s(x.0, y.1) - s(x.1, y.0) + s(x.0, y.0)
    }

    /// `sample_box(ch, wx, wy)`: the mean over the box `wx x wy` (uv units, at least one
    /// texel each way) centred at uv, clipped to the map, integrating the piecewise-constant
    /// texels exactly (so a one-texel box is bilinear interpolation).
    pub fn box_mean(&self, uv: [f64; 2], w: [f64; 2]) -> f64 {
        let (rx, lx) = box_runs(self.size, uv[0], w[0]);
        let (ry, ly) = box_runs(self.size, uv[1], w[1]);
        let mut sum = 0.0;
        for &(y0, y1, wy) in &ry {
            for &(x0, x1, wx) in &rx {
                sum += wx * wy * self.block((x0, x1), (y0, y1));
            }
        }
        sum / (lx * ly)
    }
}

/// Run the Map, Filter and Mipmap passes of the technique on a depth map.
pub fn prefilter(t: &Technique, map: &DepthMap) -> Result<Prefiltered, String> {
    let technique = resolve(t)?;
    check_map(map)?;
    let z = Level {
        size: map.size as usize,
        texels: map.z.iter().map(|&v| v as f64).collect(),
    };
    let k = technique.int("K").max(1) as usize;
    let channel = |name: String, chain: Chain| Channel { name, chain };
    let mut tables = Vec::new();
    let channels = match technique.kind {
        Kind::Hard | Kind::Pcf | Kind::Pcss => Vec::new(),
        Kind::Vsm => {
            // Map: the moments (z, z^2); Filter: box of K; Mipmap: mean.
            let blur = box_weights(k);
            vec![
                channel("m1".into(), mip_chain(convolve(&z, &blur))),
                channel("m2".into(), mip_chain(convolve(&z.map(|z| z * z), &blur))),
            ]
        }
        Kind::Evsm => {
            // Map: the warps of t = 2z - 1, w+ = e^{c+ t}, w- = -e^{-c- t}, and their squares
            // (Lauritzen & McCool 2008); Filter: box of K; Mipmap: mean.
            let blur = box_weights(k);
            let (cp, cn) = (technique.get("c_pos"), technique.get("c_neg"));
            [("p1", 1.0, cp), ("p2", 1.0, 2.0 * cp), ("n1", -1.0, -cn), ("n2", 1.0, -2.0 * cn)]
                .into_iter()
                .map(|(name, sign, c)| {
                    channel(
                        name.into(),
                        mip_chain(convolve(&z.map(|z| sign * (c * (2.0 * z - 1.0)).exp()), &blur)),
                    )
                })
                .collect()
        }
        Kind::Msm | Kind::MsmHausdorff => {
            // Map: the moments b_k = z^k, k = 1..4 (Peters & Klein 2015); Filter: box of K;
            // Mipmap: mean.
            let blur = box_weights(k);
            (1..=4)
                .map(|p| channel(format!("b{p}"), mip_chain(convolve(&z.map(|z| z.powi(p)), &blur))))
                .collect()
        }
        Kind::Esm => {
            // Map: the basis e^{cz} of eq. 7.1; Filter: box of K (eq. 7.2: filtering the
            // basis filters the test). No mip chain.
            let c = technique.get("c");
            let e = convolve(&z.map(|z| (c * z).exp()), &box_weights(k));
            // z-max (7.3.1): the maximum depth over the blur and bilinear footprint, K + 2.
            let zm = max_filter(&z, k + 2);
            vec![
                channel("e_t0_k1".into(), Chain { levels: vec![e] }),
                channel("zm".into(), Chain { levels: vec![zm] }),
            ]
        }
        Kind::Csm => {
            // Map: B_(2k-1)(z) = sin(c_k z), B_(2k)(z) = cos(c_k z) (eq. 6.6) with
            // c_k = pi (2k - 1); Filter: Gaussian of K, sigma; Mipmap: mean.
            let blur = gaussian_weights(k, technique.get("sigma"));
            let mut out = Vec::new();
            for kk in 1..=technique.int("M") {
                let ck = PI * (2 * kk - 1) as f64;
                out.push(channel(
                    format!("f_t0_k{kk}"),
                    mip_chain(convolve(&z.map(|z| (ck * z).sin()), &blur)),
                ));
                out.push(channel(
                    format!("f_t1_k{kk}"),
                    mip_chain(convolve(&z.map(|z| (ck * z).cos()), &blur)),
                ));
            }
            out
        }
        Kind::Cssm => {
            // Map: the CSM basis sin(c_k z), cos(c_k z) (eq. 6.6), the z-weighted basis
            // z sin(c_k z), z cos(c_k z) and z/2 (eq. 8.8); Filter: Gaussian of K, sigma;
            // then a mean mip chain (filter = 0) or a summed-area table (filter = 1, 8.3.1).
            let blur = gaussian_weights(k, technique.get("sigma"));
            let sat = technique.int("filter") == 1;
            let mut out = Vec::new();
            for c in technique.stored_channels() {
                let blurred = convolve(&z.map(|z| cssm_basis(&c.name, z)), &blur);
                if sat {
                    tables.push((c.name.clone(), Table::new(&blurred)));
                    out.push(channel(c.name, Chain { levels: vec![blurred] }));
                } else {
                    out.push(channel(c.name, mip_chain(blurred)));
                }
            }
            out
        }
        Kind::Vssm | Kind::Mssm => {
            // Map: VSSM's (z, z^2) (Yang et al. 2010), or MSSM's q1..q4 (the sparse
            // quantisation of the signed-depth powers, or z^k); no Filter; a summed-area
            // table of each, exact in f64 (the GPU's f32 or fixed-point rounding is the
            // error model's).
            let values: Vec<(String, Level)> = if technique.kind == Kind::Vssm {
                vec![("m1".into(), z.clone()), ("m2".into(), z.map(|z| z * z))]
            } else {
                let quantise = technique.int("quantise") != 0;
                (0..4)
                    .map(|k| (format!("q{}", k + 1), z.map(|z| super::moments::mssm_channels(quantise, z)[k])))
                    .collect()
            };
            let mut out = Vec::new();
            for (name, level) in values {
                tables.push((name.clone(), Table::new(&level)));
                out.push(channel(name, Chain { levels: vec![level] }));
            }
            out
        }
    };
    let f32_tables = if technique.kind == Kind::Vssm {
        // the Map pass's values in f32 (z, and z * z rounded once), summed less 1/2
        let n = map.size as usize;
        vec![
            ("m1".to_string(), f32_table(&map.z, n, 0.5)),
            (
                "m2".to_string(),
                f32_table(&map.z.iter().map(|z| z * z).collect::<Vec<f32>>(), n, 0.5),
            ),
        ]
    } else {
        Vec::new()
    };
    let fixed_tables = if technique.kind == Kind::Mssm {
        let quantise = technique.int("quantise") != 0;
        (0..4)
            .map(|k| {
                let codes = Level {
                    size: z.size,
                    texels: map
                        .z
                        .iter()
                        .map(|&v| {
                            let q = super::moments::mssm_channels_f32(quantise, v)[k];
                            (q.clamp(0.0, 1.0) as f64 * 65535.0).round() / 65535.0
                        })
                        .collect(),
                };
                (format!("q{}", k + 1), Table::new(&codes))
            })
            .collect()
    } else {
        Vec::new()
    };
    Ok(Prefiltered {
        stored: technique.stored_channels(),
        technique,
        depth: Chain { levels: vec![z] },
        channels,
        tables,
        f32_tables,
        fixed_tables,
    })
}

/// An f32 summed-area table as docs/language.md 8.7 ("Tables over float channels")
/// describes the GPU's: `v - centre` summed along each row in order, then each column of
/// those in order, every addition rounded to f32. Entry `(x, y)` (row-major, `n x n`)
/// covers the texels `i <= x`, `j <= y`.
pub fn f32_table(values: &[f32], n: usize, centre: f32) -> Vec<f32> {
    let mut t = vec![0.0f32; n * n];
    for y in 0..n {
        let mut acc = 0.0f32;
        for x in 0..n {
            acc += values[y * n + x] - centre;
            t[y * n + x] = acc;
        }
    }
    for x in 0..n {
        let mut acc = 0.0f32;
        for y in 0..n {
            acc += t[y * n + x];
            t[y * n + x] = acc;
        }
    }
    t
}

/// The value of a CSSM channel at depth z, by its name: `<set>_t<term>_k<order>` with
/// term 0 the sine and term 1 the cosine of c_k z = pi (2k - 1) z, times z for the
/// z-weighted sets `g`, `gs` (eq. 8.8); `zh`, `zhs` are z / 2.
pub fn cssm_basis(name: &str, z: f64) -> f64 {
    let parts: Vec<&str> = name.split('_').collect();
    match parts.as_slice() {
        [set, term, order] => {
            let k: i64 = order.trim_start_matches('k').parse().unwrap_or(0);
            let ck = PI * (2 * k - 1) as f64;
            let b = if *term == "t0" { (ck * z).sin() } else { (ck * z).cos() };
            if set.starts_with('g') { z * b } else { b }
        }
        _ => 0.5 * z,
    }
}

/// The Shade lookup for one receiver: the visibility, clamped to `[0, 1]` (NaN reads as 1).
pub fn evaluate(pre: &Prefiltered, q: &Query) -> f64 {
    clamp_visibility(shade(pre, q))
}

/// The Shade lookup before the final clamp.
pub fn shade(pre: &Prefiltered, q: &Query) -> f64 {
    let t = &pre.technique;
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let d = q.d as f64;
    let lod = q.lod as f64;
    // The slope-scaled bias is `slope_bias * depth_slope` with depth_slope taken as 0.
    let d_biased = d - t.bias();
    match t.kind {
        Kind::Hard => {
            // eq. 3.2: s = 1 if d <= z, 0 otherwise.
            if d_biased <= pre.depth.nearest(uv) { 1.0 } else { 0.0 }
        }
        Kind::Pcf => {
            // Reeves et al. 1987 (Annen 4.1): the mean of N x N bilinearly weighted binary
            // tests, i.e. (N + 1) x (N + 1) texels with weights (1 - tf, 1, ..., 1, tf) per axis.
            let n = t.int("N");
            let r = n / 2;
            let size = pre.depth.base().size as f64;
            let (sx, sy) = (uv[0] * size - 0.5, uv[1] * size - 0.5);
            let tf = [sx - sx.floor(), sy - sy.floor()];
            let axis_weight = |i: i64, f: f64| {
                let lo = if i == 0 { 1.0 - f } else { 1.0 };
                let hi = if i == n { f } else { 1.0 };
                lo * hi
            };
            let mut sum = 0.0;
            for j in 0..=n {
                for i in 0..=n {
                    let lit = d_biased <= pre.depth.fetch(uv, i - r, j - r);
                    if lit {
                        sum += axis_weight(i, tf[0]) * axis_weight(j, tf[1]);
                    }
                }
            }
            sum / (n * n) as f64
        }
        Kind::Vsm => {
            // Donnelly & Lauritzen 2006 (Annen 4.1): Chebyshev's one-tailed bound on the
            // filtered moments, p_max = var / (var + (d - mean)^2) for d > mean.
            let mean = pre.chain("m1").sample(uv, lod);
            let variance = (pre.chain("m2").sample(uv, lod) - mean * mean).max(t.get("min_variance"));
            let delta = d_biased - mean;
            let p = if d_biased > mean {
                variance / (variance + delta * delta)
            } else {
                1.0
            };
            linstep(t.get("bleed"), 1.0, p)
        }
        Kind::Evsm => {
            // Lauritzen & McCool 2008: Chebyshev's bound in each warped space, the minimum
            // variance scaled by the warp's derivative (c w)^2, the smaller bound kept.
            let tr = 2.0 * d_biased - 1.0;
            let bound = |c: f64, w: f64, first: &str, second: &str| {
                let least = t.get("min_variance") * (c * w) * (c * w);
                chebyshev(pre.chain(first).sample(uv, lod), pre.chain(second).sample(uv, lod), w, least)
            };
            let (cp, cn) = (t.get("c_pos"), t.get("c_neg"));
            let vp = bound(cp, (cp * tr).exp(), "p1", "p2");
            let vn = bound(cn, -(-cn * tr).exp(), "n1", "n2");
            linstep(t.get("bleed"), 1.0, vp.min(vn))
        }
        Kind::Msm => 1.0 - msm_intensity(msm_biased(t, msm_moments(pre, uv, lod)), d_biased),
        Kind::MsmHausdorff => {
            // Peters & Klein 2015, the Hausdorff variant: the bound over distributions of
            // depths in [0, 1] (super::moments::hausdorff_intensity), clamped
            let b = msm_biased(t, msm_moments(pre, uv, lod));
            let g = super::moments::hausdorff_intensity([b[0], b[1], b[1], b[2], b[3]], b, d_biased);
            1.0 - g.clamp(0.0, 1.0)
        }
        Kind::Vssm => super::moments::vssm_trace(pre, q).value,
        Kind::Mssm => super::moments::mssm_trace(pre, q).value,
        Kind::Esm => {
            let c = t.get("c");
            let e = pre.chain("e_t0_k1");
            // eq. 7.2: s_f = e^{-c d} [w * e^{cz}]
            let decay = (-c * d_biased).exp();
            let s = decay * e.sample(uv, 0.0);
            let fails = match t.int("classify") {
                // 7.3.2: threshold classification
                1 => s > 1.0 + t.get("eps"),
                // 7.3.1: z-max classification, d offset so that lit surfaces pass
                2 => d + t.get("zmax_offset") < pre.chain("zm").nearest(uv),
                _ => false,
            };
            if fails {
                // 7.3: the ESM evaluated at the four nearest texels, each clamped to [0, 1],
                // interpolated bilinearly.
                let size = e.base().size as f64;
                let (sx, sy) = (uv[0] * size - 0.5, uv[1] * size - 0.5);
                let (fx, fy) = (sx - sx.floor(), sy - sy.floor());
                let f = |dx, dy| (decay * e.fetch(uv, dx, dy)).clamp(0.0, 1.0);
                let top = f(0, 0) + fx * (f(1, 0) - f(0, 0));
                let bottom = f(0, 1) + fx * (f(1, 1) - f(0, 1));
                top + fy * (bottom - top)
            } else {
                s.clamp(0.0, 1.0)
            }
        }
        Kind::Csm => {
            // eq. 6.5-6.6 with c_k = pi (2k - 1), attenuation a_k = exp(-alpha (k/M)^2)
            // (6.1.1), and one of the two fixes of fig. 6.3: offset d by 1/(2M), or scale by 2.
            let m = t.int("M");
            let fix = t.int("fix");
            let dr = d_biased - if fix == 1 { 0.5 / m as f64 } else { 0.0 };
            let alpha = t.get("alpha");
            let mut s = 0.5;
            for k in 1..=m {
                let ck = PI * (2 * k - 1) as f64;
                let ak = (-alpha * (k as f64 / m as f64).powi(2)).exp();
                let sin_z = pre.chain(&format!("f_t0_k{k}")).sample(uv, lod);
                let cos_z = pre.chain(&format!("f_t1_k{k}")).sample(uv, lod);
                s += 2.0 * ak / ck * ((ck * dr).cos() * sin_z - (ck * dr).sin() * cos_z);
            }
            if fix == 2 { 2.0 * s } else { s }
        }
        Kind::Cssm => cssm_trace(pre, q).value,
        Kind::Pcss => pcss_trace(pre, q).value,
    }
}

/// Chebyshev's one-sided inequality (Donnelly & Lauritzen 2006): of a distribution with
/// mean `mean` and second moment `second`, at most `var / (var + (t - mean)^2)` lies at or
/// behind `t > mean`, the variance `second - mean^2` clamped below by `least`; 1 for
/// `t <= mean`.
pub fn chebyshev(mean: f64, second: f64, t: f64, least: f64) -> f64 {
    if t <= mean {
        return 1.0;
    }
    let variance = (second - mean * mean).max(least);
    let delta = t - mean;
    variance / (variance + delta * delta)
}

/// MSM's filtered moments `(b1, b2, b3, b4)` at uv and a level of detail.
pub fn msm_moments(pre: &Prefiltered, uv: [f64; 2], lod: f64) -> [f64; 4] {
    ["b1", "b2", "b3", "b4"].map(|name| pre.chain(name).sample(uv, lod))
}

/// Peters & Klein 2015, Algorithm 2, step 1: `b' = (1 - alpha) b + alpha (1/2, 1/2, 1/2, 1/2)`.
pub fn msm_biased(t: &Resolved, b: [f64; 4]) -> [f64; 4] {
    let alpha = t.get("alpha");
    b.map(|b| (1.0 - alpha) * b + alpha * 0.5)
}

/// The smallest Cholesky pivot (squared) of MSM's Hankel matrix: a positive-definite matrix
/// has positive pivots; at its boundary (all filtered depths 0 or all 1) the last pivot is
/// 0 in exact arithmetic and the bound is the limit as it tends to 0 from above.
pub const MSM_PIVOT: f64 = 1e-12;

/// Peters & Klein 2015, Algorithm 2, steps 2-4: the lower bound `G` of the shadow intensity
/// (the fraction of the filter region in front of `zf`) over every distribution whose
/// moments are the biased `b`. Not clamped.
pub fn msm_intensity(b: [f64; 4], zf: f64) -> f64 {
    let [b1, b2, b3, b4] = b;
    msm_bound([b1, b2, b2, b3, b4], b1, b2, zf)
}

/// [`msm_intensity`] with the entries of the matrix given apart from the moments of the
/// last step: `a = (a12, a13, a22, a23, a33)` of the symmetric matrix `[1 a12 a13; a12 a22
/// a23; a13 a23 a33]` (the Hankel matrix has `a12 = b1`, `a13 = a22 = b2`, `a23 = b3`,
/// `a33 = b4`), so that the error model can perturb the entries independently, as the
/// backward error of a Cholesky solve does.
pub fn msm_bound(a: [f64; 5], b1: f64, b2: f64, zf: f64) -> f64 {
    // the Cholesky solve and the roots z2 <= z3 of c3 z^2 + c2 z + c1 = 0
    let (z2, z3) = super::moments::hamburger_roots(a, zf);
    if zf <= z2 {
        0.0
    } else if zf <= z3 {
        (zf * z3 - b1 * (zf + z3) + b2) / ((z3 - z2) * (zf - z2))
    } else {
        1.0 - (z2 * z3 - b1 * (z2 + z3) + b2) / ((zf - z2) * (zf - z3))
    }
}

/// [`msm_intensity`] in f32 arithmetic, the same steps: the error model's estimate of what
/// the f32 solve does to the bound.
pub fn msm_intensity_f32(b: [f32; 4], zf: f32) -> f32 {
    let [b1, b2, _, _] = b;
    let (z2, z3) = super::moments::hamburger_roots_f32(b, zf);
    if zf <= z2 {
        0.0
    } else if zf <= z3 {
        (zf * z3 - b1 * (zf + z3) + b2) / ((z3 - z2) * (zf - z2))
    } else {
        1.0 - (z2 * z3 - b1 * (z2 + z3) + b2) / ((zf - z2) * (zf - z3))
    }
}

/// `div_or(num, den, eps, fallback)` (docs/language.md 8.6): `num / den` where
/// `|den| >= eps` and `den != 0`, else `fallback`.
pub fn div_or(num: f64, den: f64, eps: f64, fallback: f64) -> f64 {
    if den.abs() >= eps && den != 0.0 { num / den } else { fallback }
}

/// `sample_width`'s level of detail (docs/language.md 8.7): `log2(max(w * size, 1))`.
pub fn lod_of_width(size: usize, w: f64) -> f64 {
    (w * size as f64).max(1.0).log2()
}

// ---------------------------------------------------------------------------------------
// CSSM (Annen 2008, chapter 8; techniques/cssm.ron)

/// Where a CSSM lookup of a kernel reads: a mip level of detail (filter = 0) or a box
/// (filter = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Footprint {
    Lod(f64),
    Box([f64; 2]),
}

/// 1 / sqrt(3): a trilinear lookup at level log2(w n) spreads like a box sqrt(3) times
/// wider (variance 4^L / 4 against w^2 / 12 texels^2), so the mip path asks for w / sqrt(3)
/// (cssm.ron writes it as the f32 literal 0.57735026).
pub const INV_SQRT3: f64 = 0.577_350_269_189_625_8;

/// The footprint of a kernel `u` wide (uv units per axis): the mip path reads
/// `expand_width(f, max(u.x, u.y) / sqrt(3))`, the table path `expand_box(fs, u.x, u.y)`.
pub fn cssm_footprint(pre: &Prefiltered, u: [f64; 2]) -> Footprint {
    if pre.technique.int("filter") == 1 {
        Footprint::Box(u)
    } else {
        Footprint::Lod(lod_of_width(pre.depth.base().size, INV_SQRT3 * u[0].max(u[1])))
    }
}

/// One CSSM channel read at a footprint (NaN where the channel is missing).
pub fn cssm_lookup(pre: &Prefiltered, name: &str, uv: [f64; 2], at: Footprint) -> f64 {
    match at {
        Footprint::Lod(lod) => pre.channel(name).map_or(f64::NAN, |c| c.sample(uv, lod)),
        Footprint::Box(w) => pre.table(name).map_or(f64::NAN, |t| t.box_mean(uv, w)),
    }
}

/// `2 a_k / c_k` with a_k = exp(-alpha (k/M)^2) (6.1.1) and c_k = pi (2k - 1).
pub fn cssm_amplitude(t: &Resolved, k: i64) -> f64 {
    let m = t.int("M") as f64;
    let ck = PI * (2 * k - 1) as f64;
    2.0 * (-t.get("alpha") * (k as f64 / m).powi(2)).exp() / ck
}

/// The names of the CSM basis, the z-weighted basis and z/2 of the filter's path.
pub fn cssm_sets(t: &Resolved) -> (&'static str, &'static str, &'static str) {
    if t.int("filter") == 1 {
        ("fs", "gs", "zhs")
    } else {
        ("f", "g", "zh")
    }
}

/// Eq. 8.1 with the CSM series (eq. 6.5-6.6): s_f = 1/2 + sum_k (2 a_k / c_k)
/// [cos(c_k dr) S_k - sin(c_k dr) C_k], S_k, C_k the filtered sin(c_k z), cos(c_k z) and dr
/// the biased receiver depth (with the 1/(2M) offset of fix = 1).
pub fn cssm_series(pre: &Prefiltered, uv: [f64; 2], at: Footprint, dr: f64) -> f64 {
    let t = &pre.technique;
    let (f, _, _) = cssm_sets(t);
    let mut s = 0.5;
    for k in 1..=t.int("M") {
        let ck = PI * (2 * k - 1) as f64;
        let sin_z = cssm_lookup(pre, &format!("{f}_t0_k{k}"), uv, at);
        let cos_z = cssm_lookup(pre, &format!("{f}_t1_k{k}"), uv, at);
        s += cssm_amplitude(t, k) * ((ck * dr).cos() * sin_z - (ck * dr).sin() * cos_z);
    }
    s
}

/// The numerator of eq. 8.6 by eq. 8.8: [w * z/2] + sum_k (2 a_k / c_k)
/// [sin(c_k dr) [w * z cos(c_k z)] - cos(c_k dr) [w * z sin(c_k z)]], the complementary
/// series with the CSM series' attenuation and biased depth (cssm.ron), so that
/// f_bar = 1 - f term by term.
pub fn cssm_weighted(pre: &Prefiltered, uv: [f64; 2], at: Footprint, dr: f64) -> f64 {
    let t = &pre.technique;
    let (_, g, zh) = cssm_sets(t);
    let mut s = cssm_lookup(pre, zh, uv, at);
    for k in 1..=t.int("M") {
        let ck = PI * (2 * k - 1) as f64;
        let z_sin = cssm_lookup(pre, &format!("{g}_t0_k{k}"), uv, at);
        let z_cos = cssm_lookup(pre, &format!("{g}_t1_k{k}"), uv, at);
        s += cssm_amplitude(t, k) * ((ck * dr).sin() * z_cos - (ck * dr).cos() * z_sin);
    }
    s
}

/// Eq. 8.4 / 8.6: whether there is no blocker (1 - s_f below `min_blocker`) and z_avg, the
/// guarded quotient num / (1 - s_f) (fallback: the receiver's depth) clamped to
/// `[0, max(db, 0)]`.
pub fn cssm_blocker_depth(t: &Resolved, sf: f64, num: f64, db: f64) -> (bool, f64) {
    let blockers = 1.0 - sf;
    let min_blocker = t.get("min_blocker");
    let no_blocker = blockers < min_blocker;
    let zavg = div_or(num, blockers, min_blocker, db).max(0.0).min(db.max(0.0));
    (no_blocker, zavg)
}

/// 8.3.1: the final kernel f_w = (light_width / d) ((d - z_avg) / z_avg) near with d and
/// z_avg light-space distances (`dist`, and z_avg mapped to `near + z_avg (far - near)`), in
/// uv per axis at the near plane.
pub fn cssm_final_width(light: &LightFrame, dist: f64, zavg: f64) -> [f64; 2] {
    let zw = light.near + zavg * (light.far - light.near);
    let ratio = div_or(light.near * (dist - zw).max(0.0), dist * zw, 1e-30, 0.0);
    light.width.map(|w| light.uv_width(w * ratio, light.near))
}

/// 8.2.2: the initial kernel, the pyramid from the receiver (at `dist`) to the light cut by
/// the near plane, `light_width (dist - near) / dist` there, in uv per axis.
pub fn cssm_initial_width(light: &LightFrame, dist: f64) -> [f64; 2] {
    light.width.map(|w| light.uv_width(w * ((dist - light.near) / dist), light.near))
}

/// 6.1.1 (fix = 2 scales by 2) and 8.2.3 (shift by -ring, scale by 1 / (1 - 2 ring), clamp).
pub fn cssm_ringing(t: &Resolved, s: f64) -> f64 {
    let s = if t.int("fix") == 2 { 2.0 * s } else { s };
    let ring = t.get("ring");
    ((s - ring) / (1.0 - 2.0 * ring)).clamp(0.0, 1.0)
}

/// Eq. 8.9: p = 1 + A exp(-B (d - z_avg)), d - z_avg in normalised depth, at least 0.
pub fn cssm_sharpening(t: &Resolved, db: f64, zavg: f64) -> f64 {
    1.0 + t.get("A") * (-t.get("B") * (db - zavg).max(0.0)).exp()
}

/// The steps of CSSM's Shade pass for one receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CssmTrace {
    /// d - bias (depth_slope = 0), and the series' depth (less 1/(2M) for fix = 1).
    pub db: f64,
    pub dr: f64,
    /// max(d_world, near)
    pub dist: f64,
    /// the initial kernel (uv), s_f there and the numerator of eq. 8.8
    pub u0: [f64; 2],
    pub sf: f64,
    pub num: f64,
    pub no_blocker: bool,
    pub zavg: f64,
    /// the final kernel (uv) and the series there
    pub u1: [f64; 2],
    pub s1: f64,
    pub p: f64,
    /// before the final clamp
    pub value: f64,
}

/// CSSM (cssm.ron's Shade pass, Annen 2008 eq. 8.1-8.9) for one receiver.
pub fn cssm_trace(pre: &Prefiltered, q: &Query) -> CssmTrace {
    let t = &pre.technique;
    let light = t.light();
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let d = q.d as f64;
    let db = d - t.bias();
    let dr = db - if t.int("fix") == 1 { 0.5 / t.get("M") } else { 0.0 };
    let dist = light.d_world(d).max(light.near);
    let u0 = cssm_initial_width(&light, dist);
    let at0 = cssm_footprint(pre, u0);
    let sf = cssm_series(pre, uv, at0, dr);
    let num = cssm_weighted(pre, uv, at0, dr);
    let (no_blocker, zavg) = cssm_blocker_depth(t, sf, num, db);
    let u1 = cssm_final_width(&light, dist, zavg);
    let s1 = cssm_series(pre, uv, cssm_footprint(pre, u1), dr);
    let p = cssm_sharpening(t, db, zavg);
    let value = if no_blocker {
        cssm_ringing(t, sf)
    } else {
        cssm_ringing(t, s1).powf(p)
    };
    CssmTrace {
        db,
        dr,
        dist,
        u0,
        sf,
        num,
        no_blocker,
        zavg,
        u1,
        s1,
        p,
        value,
    }
}

// ---------------------------------------------------------------------------------------
// PCSS (Fernando 2005; Annen 2008, 4.2; techniques/pcss.ron)

/// Sample (i, j) of PCSS's n x n lattice in [-1/2, 1/2]^2: ((i n + j + 1/2) / n^2,
/// (j n + i + 1/2) / n^2) - 1/2, one sample per cell of an n x n grid and per row and column
/// of an n^2 x n^2 grid.
pub fn pcss_lattice(n: i64, i: i64, j: i64) -> [f64; 2] {
    let nn = (n * n) as f64;
    [((i * n + j) as f64 + 0.5) / nn - 0.5, ((j * n + i) as f64 + 0.5) / nn - 0.5]
}

/// One `nearest_at` read: the offset (uv), the continuous texel position `(uv + o) size`,
/// and the depth read there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcssSample {
    pub offset: [f64; 2],
    pub position: [f64; 2],
    pub z: f64,
}

/// The steps of PCSS's Shade pass for one receiver.
#[derive(Clone, Debug, PartialEq)]
pub struct PcssTrace {
    pub db: f64,
    pub dist: f64,
    /// the search region (uv) and its N x N reads
    pub su: [f64; 2],
    pub search: Vec<PcssSample>,
    /// blockers found, and their mean depth (the receiver's without any)
    pub count: usize,
    pub zb: f64,
    /// the filter region (uv) and its M x M reads
    pub pu: [f64; 2],
    pub filter: Vec<PcssSample>,
    pub value: f64,
}

/// PCSS (pcss.ron's Shade pass) for one receiver: blocker search over the near-plane cut of
/// the light pyramid, the penumbra width w = (d_r - d_b) light_width / d_b projected to the
/// near plane, PCF of M x M binary tests (eq. 3.2) at `nearest_at` reads.
pub fn pcss_trace(pre: &Prefiltered, q: &Query) -> PcssTrace {
    let t = &pre.technique;
    let light = t.light();
    let uv = [q.uv[0] as f64, q.uv[1] as f64];
    let d = q.d as f64;
    // depth_slope = 0: the slope term sb (1 + |o| shadow_size) vanishes
    let db = d - t.get("bias");
    let dist = light.d_world(d).max(light.near);
    let size = pre.depth.base().size as f64;
    let read = |o: [f64; 2]| {
        let at = [uv[0] + o[0], uv[1] + o[1]];
        PcssSample {
            offset: o,
            position: [at[0] * size, at[1] * size],
            z: pre.depth.nearest(at),
        }
    };
    let lattice = |n: i64, region: [f64; 2]| -> Vec<PcssSample> {
        (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| {
                let c = pcss_lattice(n, i, j);
                read([c[0] * region[0], c[1] * region[1]])
            })
            .collect()
    };
    // 1. blocker search over the near-plane cut of the pyramid to the light
    let su = light.width.map(|w| light.uv_width(w * ((dist - light.near) / dist), light.near));
    let search = lattice(t.int("N"), su);
    let blockers: Vec<f64> = search.iter().map(|s| s.z).filter(|&z| z < db).collect();
    let count = blockers.len();
    let zb = div_or(blockers.iter().sum(), count as f64, 0.5, db);
    // 2. penumbra width (light-space distances), projected to the near plane
    let zbw = light.near + zb * (light.far - light.near);
    let wp = div_or((dist - zbw).max(0.0), zbw, 1e-30, 0.0);
    let pu = light.width.map(|w| light.uv_width(w * wp * (light.near / dist), light.near));
    // 3. PCF over it
    let filter = lattice(t.int("M"), pu);
    let lit = filter.iter().filter(|s| db <= s.z).count() as f64 / filter.len() as f64;
    PcssTrace {
        db,
        dist,
        su,
        search,
        count,
        zb,
        pu,
        filter,
        value: if count == 0 { 1.0 } else { lit },
    }
}

/// `saturate((x - lo) / (hi - lo))`.
pub fn linstep(lo: f64, hi: f64, x: f64) -> f64 {
    ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
}
