//! Accuracy and stability of a technique's visibility against the ground truth
//! (docs/truth.md: RMS and max error over facing and penumbra pixels, signed error images,
//! temporal stability).
//!
//! - Errors are in 0..255 units, as in Lawlor 2006, figure 10: `255 * (estimate - truth)`
//!   with visibility in 0..1.
//! - [`accuracy`] gives RMS and max error over the pixels whose surface faces the light
//!   ([`facing_light`]: `n . l > 0` with `l` towards the light's centre, or the direction
//!   of a light at infinity), and separately over the penumbra pixels among them
//!   ([`penumbra`]: `0 < truth < 1`), since lit floor in frame dilutes the first figure.
//!   Pixels that face away receive no light whatever their visibility, so they are left
//!   out of both.
//! - [`shadow_on_ground`]: Lawlor 2006's pixel set for figure 10, "the shadow cast on the
//!   ground plane": facing pixels on objects that cast no shadow (`casts: false`, the
//!   ground) whose truth is below 1, or lies within the penumbra's reach `R` (world
//!   distance) of such a pixel. `R` is the scene's largest penumbra reach
//!   (`Scene::penumbra_reach`: for a distant disk, the casters' height above the lowest
//!   receiver times tan(angle / 2)): the farthest a true penumbra extends past the shadow's
//!   outline, so the set holds the whole shadow plus a band as wide as the widest penumbra
//!   around it, where a technique that spreads its penumbra too far shows its error.
//!   [`Accuracy::ground`] gives the error over it where the scene has such objects.
//! - A visibility that is not finite counts as the largest error, 255, and is counted.
//! - [`error_image`] draws the signed error `estimate - truth` with the diverging
//!   red-blue colour map of `colorous` (d3's continuous RdBu, a B-spline through
//!   ColorBrewer's 11 classes): red where the technique lets through more light than the
//!   truth (light leaking, too bright), blue where it lets through less (over-darkening),
//!   near white at 0 (RdBu's centre, RGB (241, 239, 237)), dark red and dark blue at
//!   `+range` and `-range` and beyond. Pixels outside the mask are mid grey.
//! - [`flip`]: NVIDIA's FLIP (LDR, `nv-flip`) of the image shaded with the estimate
//!   ([`shaded`]) against it shaded with the truth, averaged over the facing pixels, at
//!   [`FLIP_PIXELS_PER_DEGREE`] (docs/truth.md).
//! - [`mean_frame_change`]: temporal stability, the mean absolute change of visibility from
//!   one frame to the next (0..255 units), over the masked pixels and all consecutive
//!   pairs of frames.

use std::fmt;

use glam::Vec3;

use crate::scene::Light;

/// 0..1 visibility to the 0..255 units of the figures.
pub const UNITS: f64 = 255.0;

/// The colour of pixels left out of an error image.
pub const MASKED_GREY: [u8; 3] = [128, 128, 128];

/// Why a metric could not be computed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MetricsError(pub String);

impl fmt::Display for MetricsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MetricsError {}

/// The figures (in `sshc-records`: a sweep's rows hold them, and the fuzz target `shard`
/// reads them).
pub use sshc_records::accuracy::{Accuracy, ErrorStats};

fn same_len(what: &str, a: usize, b: usize) -> Result<(), MetricsError> {
    if a == b {
        Ok(())
    } else {
        Err(MetricsError(format!(
            "{what}: {a} values against {b}; the images must have the same size"
        )))
    }
}

/// The signed error of one pixel in 0..1 units (a non-finite estimate counts as 1).
fn signed_error(estimate: f32, truth: f32) -> Option<f64> {
    let e = f64::from(estimate) - f64::from(truth);
    e.is_finite().then_some(e)
}

/// Visibility values a technique may hand to the metrics: the runtime's own rule for what
/// a Shade pass may write, [0, 1] within `VISIBILITY_EPSILON` (one rule for both; anything
/// beyond is a broken shader, not an error to average).
pub const VISIBILITY_RANGE: (f32, f32) = (-sshc_runtime::gpu::VISIBILITY_EPSILON, 1.0 + sshc_runtime::gpu::VISIBILITY_EPSILON);

/// Refuses a visibility buffer with a non-finite value, or one outside
/// [`VISIBILITY_RANGE`], at a pixel of `mask`: the error names `what`, the first such
/// pixel and value, and how many there are. `compare` and `sweep` call it before any
/// figure, so a NaN or 1e30 never becomes an RMS.
pub fn check_visibility(what: &str, values: &[f32], mask: &[bool]) -> Result<(), MetricsError> {
    same_len("visibility and mask", values.len(), mask.len())?;
    let (lo, hi) = VISIBILITY_RANGE;
    let bad = |v: f32| !(v.is_finite() && v >= lo && v <= hi);
    let mut count = 0usize;
    let mut first = None;
    for (i, (&v, &m)) in values.iter().zip(mask).enumerate() {
        if m && bad(v) {
            count += 1;
            first.get_or_insert((i, v));
        }
    }
    match first {
        None => Ok(()),
        Some((i, v)) => Err(MetricsError(format!(
            "{what}: {count} pixel(s) hold a visibility that is not finite or outside [{lo}, {hi}] (first: pixel {i}, value {v}); the technique's shader is broken"
        ))),
    }
}

/// True for each pixel whose surface faces the light: a finite position and normal with
/// `n . l > 0`, where `l` points from the position to the light's centre, or is the
/// direction of a light at infinity.
pub fn facing_light(positions: &[Vec3], normals: &[Vec3], light: &Light) -> Result<Vec<bool>, MetricsError> {
    same_len("positions and normals", positions.len(), normals.len())?;
    Ok(positions
        .iter()
        .zip(normals)
        .map(|(&p, &n)| {
            if !(p.is_finite() && n.is_finite()) {
                return false;
            }
            let l = match (light.center(), light.direction()) {
                (Some(c), _) => c - p,
                (None, Some(d)) => d,
                (None, None) => return false,
            };
            n.dot(l) > 0.0
        })
        .collect())
}

/// The pixels of `mask` where the truth is strictly between 0 and 1.
pub fn penumbra(truth: &[f32], mask: &[bool]) -> Result<Vec<bool>, MetricsError> {
    same_len("truth and mask", truth.len(), mask.len())?;
    Ok(truth.iter().zip(mask).map(|(&t, &m)| m && t > 0.0 && t < 1.0).collect())
}

/// RMS, max and mean error of `estimate` against `truth` over the pixels of `mask`, in
/// 0..255 units. No pixel gives zeros.
pub fn error_stats(estimate: &[f32], truth: &[f32], mask: &[bool]) -> Result<ErrorStats, MetricsError> {
    same_len("estimate and truth", estimate.len(), truth.len())?;
    same_len("estimate and mask", estimate.len(), mask.len())?;
    let mut s = ErrorStats::default();
    let (mut sum, mut sum_sq) = (0f64, 0f64);
    for ((&e, &t), &m) in estimate.iter().zip(truth).zip(mask) {
        if !m {
            continue;
        }
        s.pixels += 1;
        let err = match signed_error(e, t) {
            Some(err) => err * UNITS,
            None => {
                s.non_finite += 1;
                UNITS
            }
        };
        sum += err;
        sum_sq += err * err;
        s.max = s.max.max(err.abs());
    }
    if s.pixels > 0 {
        s.rms = (sum_sq / s.pixels as f64).sqrt();
        s.mean = sum / s.pixels as f64;
    }
    Ok(s)
}

/// The facing pixels split by what the truth says of them: (lit, `truth = 1`; umbra,
/// `truth = 0`). With [`penumbra`] they partition `mask`. The truth's stratified estimate
/// is exactly 1 (or 0) only where every light sample of every run was unblocked (blocked),
/// so a pixel is never called lit for being nearly lit.
pub fn regions(truth: &[f32], mask: &[bool]) -> Result<(Vec<bool>, Vec<bool>), MetricsError> {
    same_len("truth and mask", truth.len(), mask.len())?;
    Ok((
        truth.iter().zip(mask).map(|(&t, &m)| m && t >= 1.0).collect(),
        truth.iter().zip(mask).map(|(&t, &m)| m && t <= 0.0).collect(),
    ))
}

/// [`error_stats`] over the facing pixels, and over each of the regions the truth splits
/// them into: penumbra, lit and umbra ([`regions`]).
pub fn accuracy(estimate: &[f32], truth: &[f32], facing: &[bool]) -> Result<Accuracy, MetricsError> {
    let pen = penumbra(truth, facing)?;
    let (lit, umbra) = regions(truth, facing)?;
    Ok(Accuracy {
        facing: error_stats(estimate, truth, facing)?,
        penumbra: error_stats(estimate, truth, &pen)?,
        lit: error_stats(estimate, truth, &lit)?,
        umbra: error_stats(estimate, truth, &umbra)?,
        ground: None,
        flip: None,
    })
}

/// The region split in words: each region's signed mean and RMS (0..255), and what a
/// sign means there (`sshc compare` and `sshc tune` print it).
pub fn split_line(a: &Accuracy) -> String {
    let part = |what: &str, s: &ErrorStats| {
        if s.pixels == 0 {
            format!("{what}: no pixels")
        } else {
            format!("{what} mean {:+.2} RMS {:.2} over {} px", s.mean, s.rms, s.pixels)
        }
    };
    format!(
        "error by region (signed, technique - truth, 0..255): {}; {}; {} (lit < 0: acne or darkening; umbra and penumbra > 0: leaks or peter-panning)",
        part("lit", &a.lit),
        part("penumbra", &a.penumbra),
        part("umbra", &a.umbra),
    )
}

/// FLIP's viewing condition, in pixels per degree of visual angle: FLIP's own default, 67
/// (a 0.7 m wide monitor of 3840 pixels seen from 0.7 m). sshc's camera images are far
/// smaller than such a screen; seen at that pixel density, a penumbra a few pixels wide
/// spans a few arc-minutes, which is how a viewer sees the figures' images enlarged on a
/// monitor pixel for pixel.
pub const FLIP_PIXELS_PER_DEGREE: f32 = 67.0;

/// The image the runtime shades from a visibility (`back::shade`: the grey
/// `0.12 + 0.88 v max(n . l, 0)` with `l` the unit vector to the light's centre or the
/// direction of a light at infinity), as 8-bit codes, RGB, rows from the top; black
/// where no surface is seen. The codes are what `sshc render` writes to its PNG (an
/// `Rgba8Unorm` target), which a viewer displays as sRGB, as FLIP's LDR metric takes them.
pub fn shaded(visibility: &[f32], positions: &[Vec3], normals: &[Vec3], light: &Light) -> Result<Vec<u8>, MetricsError> {
    same_len("visibility and positions", visibility.len(), positions.len())?;
    same_len("positions and normals", positions.len(), normals.len())?;
    let mut out = Vec::with_capacity(3 * visibility.len());
    for ((&v, &p), &n) in visibility.iter().zip(positions).zip(normals) {
        let l = match (light.center(), light.direction()) {
            (Some(c), _) => c - p,
            (None, Some(d)) => d,
            (None, None) => Vec3::ZERO,
        };
        let grey = if p.is_finite() && n.is_finite() {
            let lambert = n.normalize_or_zero().dot(l.normalize_or_zero()).max(0.0);
            // a visibility that is not finite counts as lit, as the runtime's shading does
            let v = if v.is_finite() { v.clamp(0.0, 1.0) } else { 1.0 };
            0.12 + 0.88 * v * lambert
        } else {
            0.0
        };
        let code = (grey.clamp(0.0, 1.0) * 255.0).round() as u8;
        out.extend([code; 3]);
    }
    Ok(out)
}

/// FLIP's error map (LDR-FLIP, NVIDIA's implementation through `nv-flip`) of the `test`
/// image against the `reference`, both `w x h` RGB8: one value in [0, 1] per pixel.
pub fn flip_map(reference: &[u8], test: &[u8], w: u32, h: u32) -> Result<Vec<f32>, MetricsError> {
    let n = 3 * w as usize * h as usize;
    same_len("the reference image's bytes and its size", reference.len(), n)?;
    same_len("the test image's bytes and its size", test.len(), n)?;
    if w == 0 || h == 0 {
        return Err(MetricsError("FLIP of an empty image".into()));
    }
    let (r, t) = (
        nv_flip::FlipImageRgb8::with_data(w, h, reference),
        nv_flip::FlipImageRgb8::with_data(w, h, test),
    );
    Ok(nv_flip::flip(r, t, FLIP_PIXELS_PER_DEGREE).to_vec())
}

/// Mean FLIP over the pixels of `mask` of the image shaded with `estimate` against the
/// same image shaded with `truth` ([`shaded`]): 0 where they look alike, towards 1 where a
/// viewer sees them differ. The error map is computed over the whole image (FLIP filters
/// spatially), then averaged over the mask, as the RMS figures are.
pub fn flip(
    estimate: &[f32],
    truth: &[f32],
    positions: &[Vec3],
    normals: &[Vec3],
    light: &Light,
    (w, h): (u32, u32),
    mask: &[bool],
) -> Result<f64, MetricsError> {
    same_len("visibility and mask", estimate.len(), mask.len())?;
    let map = flip_map(
        &shaded(truth, positions, normals, light)?,
        &shaded(estimate, positions, normals, light)?,
        w,
        h,
    )?;
    let (sum, count) = map
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .fold((0.0f64, 0usize), |(s, c), (v, _)| (s + f64::from(*v), c + 1));
    Ok(if count == 0 { 0.0 } else { sum / count as f64 })
}

/// The error over Lawlor's shadow on the ground ([`shadow_on_ground`]) of `scene`'s first
/// light, with the ground the pixels on objects that cast no shadow: the pixel set, or
/// `None` when every object casts (the set is then not defined).
pub fn ground_set(
    scene: &crate::scene::Scene,
    truth: &[f32],
    positions: &[Vec3],
    facing: &[bool],
) -> Result<Option<Vec<bool>>, MetricsError> {
    if (0..scene.objects().len()).all(|i| scene.casts(i)) {
        return Ok(None);
    }
    let light = scene
        .lights
        .first()
        .ok_or_else(|| MetricsError("the scene has no light: add one to `lights`".into()))?;
    let ground = crate::visibility::Visibility::new(scene).on_non_casters(scene, positions);
    shadow_on_ground(truth, positions, &ground, facing, scene.penumbra_reach(light)).map(Some)
}

/// Lawlor's "shadow on the ground plane" (see the module docs): the pixels of `facing`
/// that are on `ground` (a surface that casts no shadow) and whose truth is below 1, or
/// whose world position lies within `reach` of the position of such a pixel. `reach` <= 0
/// or not finite keeps only the pixels whose truth is below 1.
pub fn shadow_on_ground(
    truth: &[f32],
    positions: &[Vec3],
    ground: &[bool],
    facing: &[bool],
    reach: f32,
) -> Result<Vec<bool>, MetricsError> {
    same_len("truth and positions", truth.len(), positions.len())?;
    same_len("truth and ground mask", truth.len(), ground.len())?;
    same_len("truth and mask", truth.len(), facing.len())?;
    let candidate = |i: usize| facing[i] && ground[i] && positions[i].is_finite();
    let mut out: Vec<bool> = (0..truth.len()).map(|i| candidate(i) && truth[i] < 1.0).collect();
    if !(reach.is_finite() && reach > 0.0) {
        return Ok(out);
    }
    // The shadowed ground pixels hashed on a grid of cells `reach` wide: a pixel within
    // `reach` of one lies in one of the 27 cells around its own.
    let cell = |p: Vec3| {
        let c = (p / reach).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    };
    let mut grid: std::collections::HashMap<(i64, i64, i64), Vec<Vec3>> = std::collections::HashMap::new();
    for (i, &o) in out.iter().enumerate() {
        if o {
            grid.entry(cell(positions[i])).or_default().push(positions[i]);
        }
    }
    let r2 = reach * reach;
    for i in 0..truth.len() {
        if out[i] || !candidate(i) {
            continue;
        }
        let p = positions[i];
        let (x, y, z) = cell(p);
        out[i] = (-1..=1).any(|dx| {
            (-1..=1).any(|dy| {
                (-1..=1).any(|dz| {
                    // cells saturate at the ends of i64 (a tiny reach far from the origin)
                    grid.get(&(x.saturating_add(dx), y.saturating_add(dy), z.saturating_add(dz)))
                        .is_some_and(|ps| ps.iter().any(|q| q.distance_squared(p) <= r2))
                })
            })
        });
    }
    Ok(out)
}

/// The colour of a signed error `e` for a symmetric range `[-range, range]` (values
/// beyond it are clamped): red for positive, blue for negative, near white at 0.
pub fn error_colour(e: f64, range: f64) -> [u8; 3] {
    let x = if e.is_nan() {
        1.0
    } else if range > 0.0 {
        (e / range).clamp(-1.0, 1.0)
    } else if e == 0.0 {
        0.0
    } else {
        e.signum()
    };
    // RdBu runs from red (0) to blue (1).
    let c = colorous::RED_BLUE.eval_continuous(0.5 - 0.5 * x);
    [c.r, c.g, c.b]
}

/// The half-width of a symmetric colour range that holds every masked error: the largest
/// absolute error in 0..255 units rounded up to 4, 8, 16, 32, 64, 128 or 255. Returned
/// in 0..255 units.
pub fn error_range(estimate: &[f32], truth: &[f32], mask: &[bool]) -> Result<f64, MetricsError> {
    let s = error_stats(estimate, truth, mask)?;
    Ok([4.0, 8.0, 16.0, 32.0, 64.0, 128.0]
        .into_iter()
        .find(|&r| s.max <= r)
        .unwrap_or(UNITS))
}

/// The signed error image (RGB, 8 bits per channel, rows top first): see the module docs.
/// `range` is the half-width of the colour range in 0..255 units; pixels outside `mask`
/// (when given) are [`MASKED_GREY`].
pub fn error_image(
    estimate: &[f32],
    truth: &[f32],
    mask: Option<&[bool]>,
    width: u32,
    height: u32,
    range: f64,
) -> Result<image::RgbImage, MetricsError> {
    same_len("estimate and truth", estimate.len(), truth.len())?;
    same_len("image size and values", width as usize * height as usize, estimate.len())?;
    if let Some(m) = mask {
        same_len("estimate and mask", estimate.len(), m.len())?;
    }
    let bytes = estimate
        .iter()
        .zip(truth)
        .enumerate()
        .flat_map(|(i, (&e, &t))| {
            if mask.is_some_and(|m| !m[i]) {
                return MASKED_GREY;
            }
            let err = signed_error(e, t).map_or(f64::NAN, |x| x * UNITS);
            error_colour(err, range)
        })
        .collect();
    image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| MetricsError(format!("no {width} x {height} image")))
}

/// Mean absolute change of visibility between consecutive frames over the pixels of
/// `mask`, in 0..255 units (a non-finite value counts as a change of 255). Fewer than two
/// frames, or an empty mask, give 0.
pub fn mean_frame_change(frames: &[Vec<f32>], mask: &[bool]) -> Result<f64, MetricsError> {
    for f in frames {
        same_len("frame and mask", f.len(), mask.len())?;
    }
    let mut sum = 0f64;
    let mut count = 0usize;
    for pair in frames.windows(2) {
        for ((&a, &b), &m) in pair[0].iter().zip(&pair[1]).zip(mask) {
            if m {
                let d = (f64::from(b) - f64::from(a)).abs() * UNITS;
                sum += if d.is_finite() { d } else { UNITS };
                count += 1;
            }
        }
    }
    Ok(if count == 0 { 0.0 } else { sum / count as f64 })
}
