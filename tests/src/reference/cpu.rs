//! The CPU reference: every pass after Depth in f64, without quantisation.
//!
//! [`prefilter`] runs the Map, Filter and Mipmap passes of a technique and keeps every
//! channel as a chain of f64 images; [`evaluate`] runs the Shade lookup for one receiver.
//! Both are public so that tests can derive tolerances from the same lookups (the texels a
//! filtered lookup blends, [`Chain::lookup`]).

use super::{DepthMap, Kind, Query, Resolved, Technique, check_map, clamp_visibility, resolve};
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
}

impl Prefiltered {
    pub fn channel(&self, name: &str) -> Option<&Chain> {
        self.channels.iter().find(|c| c.name == name).map(|c| &c.chain)
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
    let channels = match technique.kind {
        Kind::Hard | Kind::Pcf => Vec::new(),
        Kind::Vsm => {
            // Map: the moments (z, z^2); Filter: box of K; Mipmap: mean.
            let blur = box_weights(k);
            vec![
                channel("m1".into(), mip_chain(convolve(&z, &blur))),
                channel("m2".into(), mip_chain(convolve(&z.map(|z| z * z), &blur))),
            ]
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
    };
    Ok(Prefiltered {
        technique,
        depth: Chain { levels: vec![z] },
        channels,
    })
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
    let d_biased = d - t.get("bias");
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
    }
}

/// `saturate((x - lo) / (hi - lo))`.
pub fn linstep(lo: f64, hi: f64, x: f64) -> f64 {
    ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
}
