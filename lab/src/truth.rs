//! Ground truth (docs/truth.md): for every camera pixel, the fraction of the light
//! visible from exactly the world position the GPU shaded there, by ray casting with the
//! CPU visibility query ([`crate::visibility`]).
//!
//! The inputs are the camera pass's position and normal buffers as the runtime rendered
//! them (one entry per pixel, rows top first). The normal is the camera pass's, turned
//! towards the camera (surfaces are two-sided; the receiver is the side the camera sees),
//! and is taken as given: light behind its tangent plane is blocked
//! ([`crate::visibility`]). A pixel with a non-finite position shows no
//! surface: its truth is 1 (lit, as the visibility buffer reads there) with no error. The
//! scene's first light is used, as [`crate::bind::scene_inputs`] binds it for the GPU.
//!
//! **Convergence is measured, not assumed.** Each pixel's truth is the mean of `runs`
//! independent estimates (independent seeds), each with `samples` stratified light
//! samples (rounded up to a square `n x n`, see [`TruthSettings::samples`]). The standard
//! error of that mean is measured per pixel from the spread of the runs:
//! `se = s / sqrt(runs)` with `s` the sample standard deviation (denominator `runs - 1`).
//! [`Truth`] reports its largest, mean and root-mean-square value over the pixels that
//! show a surface. With [`TruthSettings::target_std_error`], the samples per run are
//! doubled (`n` grows by `sqrt 2`) until the largest standard error is at or below the
//! target or the cap [`TruthSettings::max_samples`] is reached; only the last level's runs
//! make the result, the rays of the earlier ones are counted in its cost.
//!
//! Stratified sampling converges faster than independent sampling: across a straight
//! shadow edge only the `O(n)` strata the edge cuts have any variance, so the standard
//! error falls about as `samples^-3/4` rather than `samples^-1/2` (docs/truth.md has the
//! measured slope).
//!
//! Results are cached on disk ([`TruthCache`]) under a key ([`cache_key`]) that hashes
//! everything that determines them: the scene file's bytes, every OBJ mesh's bytes, the
//! camera (its resolution included), the lights, the world-space geometry, the positions
//! and normals themselves, the settings, and [`TRUTH_VERSION`] with the crate version.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::Vec3;
use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::{Xxh3, xxh3_64};

use crate::claim::{self, Attempt, Claim, Watch};
use crate::scene::Scene;
use crate::visibility::Visibility;

/// The largest cached truth record read: the most pixels a camera has
/// (`scene::MAX_CAMERA_PIXELS`, 4096^2) at 32 bytes of RON each, and its header.
pub const MAX_RECORD_BYTES: u64 = 32 * 4096 * 4096 + (1 << 20);

/// Version of the ground-truth computation, part of every cache key: bump it whenever the
/// sampling (here or in [`crate::visibility`]) changes what a given key computes.
pub const TRUTH_VERSION: u32 = 2;

/// Pixels per task handed to the visibility query; each chunk of each run has its own
/// seed, so the result does not depend on the thread count (but does on this constant,
/// which is why it is part of [`TRUTH_VERSION`]).
const CHUNK: usize = 4096;

/// How much work the ground truth gets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthSettings {
    /// Light samples per pixel in one run, rounded up to a square `n x n` (the stratified
    /// grid of [`Visibility`]); the starting count when a target is set. At least 1.
    pub samples: u32,
    /// Independent runs per pixel; the truth is their mean and their spread gives the
    /// standard error. At least 2.
    pub runs: u32,
    /// Double the samples per run until the largest per-pixel standard error is at most
    /// this (visibility units, 0..1), or [`TruthSettings::max_samples`] is reached.
    pub target_std_error: Option<f32>,
    /// The cap on samples per run when a target is set.
    pub max_samples: u32,
    /// Seed of the first run; run `r` at `n x n` samples uses seeds derived from it.
    pub seed: u64,
}

impl Default for TruthSettings {
    fn default() -> Self {
        TruthSettings {
            samples: 256,
            runs: 4,
            target_std_error: None,
            max_samples: 4096,
            seed: 0,
        }
    }
}

/// Why the ground truth could not be computed, read or written.
#[derive(Clone, Debug, PartialEq)]
pub enum TruthError {
    /// The scene has no light.
    NoLight,
    /// The inputs do not fit together (buffer lengths, image size, settings).
    Input(String),
    /// A file could not be read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl fmt::Display for TruthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TruthError::NoLight => write!(f, "the scene has no light: add one to `lights`"),
            TruthError::Input(m) => write!(f, "{m}"),
            TruthError::Io { path, message } => write!(f, "{}: {message}", path.display()),
        }
    }
}

impl std::error::Error for TruthError {}

fn io_error(path: &Path) -> impl Fn(std::io::Error) -> TruthError + '_ {
    move |e| TruthError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The truth of one camera image and its levels (in `sshc-records`, with the cache
/// record's reading); its files are written by [`TruthFiles`].
pub use sshc_records::truth::{Level, Truth};

/// The files of a truth: its visibility and standard error as PFM, its visibility as PNG.
pub trait TruthFiles {
    /// Writes the visibility as a one-channel PFM (float) file.
    fn write_pfm(&self, path: &Path) -> Result<(), TruthError>;
    /// Writes the per-pixel standard error as a one-channel PFM file.
    fn write_std_error_pfm(&self, path: &Path) -> Result<(), TruthError>;
    /// Writes the visibility as an 8-bit grey PNG (0 black, 1 white).
    fn write_png(&self, path: &Path) -> Result<(), TruthError>;
}

impl TruthFiles for Truth {
    fn write_pfm(&self, path: &Path) -> Result<(), TruthError> {
        write_pfm_gray(path, self.width, self.height, &self.visibility)
    }

    fn write_std_error_pfm(&self, path: &Path) -> Result<(), TruthError> {
        write_pfm_gray(path, self.width, self.height, &self.std_error)
    }

    fn write_png(&self, path: &Path) -> Result<(), TruthError> {
        let bytes = self.visibility.iter().map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8).collect();
        let img = image::GrayImage::from_raw(self.width, self.height, bytes)
            .ok_or_else(|| TruthError::Input("the truth's size does not match its data".into()))?;
        crate::files::save_image(&img, path).map_err(|e| TruthError::Io {
            path: path.to_path_buf(),
            message: e.trim_start_matches("error: ").to_string(),
        })
    }
}

/// Writes a one-channel PFM file (rows top first in `data`).
pub fn write_pfm_gray(path: &Path, width: u32, height: u32, data: &[f32]) -> Result<(), TruthError> {
    if width == 0 || height == 0 || data.len() != width as usize * height as usize {
        return Err(TruthError::Input(format!(
            "cannot write {}: {} values for a {width} x {height} image",
            path.display(),
            data.len()
        )));
    }
    let bytes = crate::image_io::pfm_bytes(width, height, false, data.to_vec())
        .map_err(|e| TruthError::Input(format!("cannot write {}: {e}", path.display())))?;
    crate::files::write_new(path, bytes).map_err(|e| TruthError::Io {
        path: path.to_path_buf(),
        message: e.trim_start_matches("error: ").to_string(),
    })
}

/// Where the computation stands, for a progress bar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress {
    /// Samples per pixel per run of the level being computed.
    pub samples: u32,
    /// Pixel-runs done in this level.
    pub done: u64,
    /// Pixel-runs in this level (pixels x runs).
    pub total: u64,
}

/// What the camera pass rendered: a `width x height` image's world positions (rows top
/// first, non-finite where no surface is seen) and normals (one per position, or empty
/// when unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Points<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// World position per pixel.
    pub positions: &'a [Vec3],
    /// World normal per pixel, or empty.
    pub normals: &'a [Vec3],
}

/// Strata per axis for `samples` light samples (rounded up to a square).
pub fn strata(samples: u32) -> u32 {
    let s = samples.max(1);
    let mut n = (f64::from(s).sqrt()).floor() as u32;
    while n * n < s {
        n += 1;
    }
    n
}

/// Computes the ground truth at `points` with the scene's first light, casting rays
/// against `vis` (built from the same scene). `progress` is called after every chunk of
/// pixels.
pub fn compute(
    scene: &Scene,
    vis: &Visibility,
    points: &Points,
    settings: &TruthSettings,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Truth, TruthError> {
    let light = scene.lights.first().ok_or(TruthError::NoLight)?;
    check_inputs(points, settings)?;
    let Points {
        width,
        height,
        positions,
        normals,
    } = *points;
    let start = Instant::now();
    let pixels = positions.len();
    let surface: Vec<bool> = positions.iter().map(|p| p.is_finite()).collect();
    // pixels on objects that receive no shadow read 1 (`receives: false`), as the
    // techniques draw them
    let unshadowed = if scene.objects().iter().any(|o| !o.receives) {
        vis.on_non_receivers(scene, positions)
    } else {
        vec![false; pixels]
    };
    let surface_pixels = surface.iter().filter(|&&s| s).count() as u64;
    let binary = !light.has_extent();
    let mut n = strata(settings.samples);
    let cap = strata(settings.max_samples.max(settings.samples));
    let runs = settings.runs;
    let mut levels = Vec::new();
    let mut evaluated = 0u64;
    let mut rays = 0u64;
    loop {
        let level_start = Instant::now();
        let per_sample_set = if binary { 1 } else { u64::from(n * n) };
        let mut sum = vec![0f64; pixels];
        let mut sum_sq = vec![0f64; pixels];
        let total = pixels as u64 * u64::from(runs);
        let mut done = 0u64;
        progress(Progress {
            samples: n * n,
            done,
            total,
        });
        for r in 0..runs {
            for (c, start) in (0..pixels).step_by(CHUNK).enumerate() {
                let end = (start + CHUNK).min(pixels);
                let seed = chunk_seed(settings.seed, n, r, c as u64);
                let normals = if normals.is_empty() { &[][..] } else { &normals[start..end] };
                let v = vis.visible_fractions_seeded(&positions[start..end], normals, light, n, seed);
                for (k, &x) in v.iter().enumerate() {
                    let i = start + k;
                    let x = f64::from(x);
                    sum[i] += x;
                    sum_sq[i] += x * x;
                    if surface[i] {
                        evaluated += per_sample_set;
                        if x < 1.0 {
                            rays += per_sample_set;
                        }
                    }
                }
                done += (end - start) as u64;
                progress(Progress {
                    samples: n * n,
                    done,
                    total,
                });
            }
        }
        let rf = f64::from(runs);
        let mut visibility = Vec::with_capacity(pixels);
        let mut std_error = Vec::with_capacity(pixels);
        for i in 0..pixels {
            if !surface[i] {
                visibility.push(1.0);
                std_error.push(0.0);
                continue;
            }
            if unshadowed[i] {
                visibility.push(1.0);
                std_error.push(0.0);
                continue;
            }
            let mean = sum[i] / rf;
            let var = ((sum_sq[i] - rf * mean * mean) / (rf - 1.0)).max(0.0);
            visibility.push(mean as f32);
            std_error.push((var / rf).sqrt() as f32);
        }
        let max = std_error.iter().copied().fold(0f32, f32::max);
        let rms = if surface_pixels == 0 {
            0.0
        } else {
            (std_error.iter().map(|&e| f64::from(e) * f64::from(e)).sum::<f64>() / surface_pixels as f64).sqrt() as f32
        };
        let samples = if binary { 1 } else { n * n };
        levels.push(Level {
            samples,
            max_std_error: max,
            rms_std_error: rms,
            seconds: level_start.elapsed().as_secs_f64(),
        });
        let done = match settings.target_std_error {
            None => true,
            Some(t) => binary || max <= t || n >= cap,
        };
        if done {
            return Ok(Truth {
                width,
                height,
                visibility,
                std_error,
                samples,
                runs,
                levels,
                surface_pixels,
                samples_evaluated: evaluated,
                rays_at_least: rays,
                seconds: start.elapsed().as_secs_f64(),
                threads: rayon::current_num_threads() as u32,
            });
        }
        // Double the samples: n grows by sqrt 2 (at least by one), up to the cap.
        let next = ((f64::from(n) * std::f64::consts::SQRT_2).round() as u32).max(n + 1);
        n = next.min(cap);
    }
}

fn check_inputs(points: &Points, s: &TruthSettings) -> Result<(), TruthError> {
    let Points {
        width,
        height,
        positions,
        normals,
    } = *points;
    let pixels = width as usize * height as usize;
    if width == 0 || height == 0 {
        return Err(TruthError::Input(format!(
            "the image is {width} x {height}: it needs at least one pixel"
        )));
    }
    if positions.len() != pixels {
        return Err(TruthError::Input(format!(
            "{} positions for a {width} x {height} image ({pixels} pixels)",
            positions.len()
        )));
    }
    if !normals.is_empty() && normals.len() != pixels {
        return Err(TruthError::Input(format!(
            "{} normals for {} positions: give one normal per position, or none",
            normals.len(),
            positions.len()
        )));
    }
    if s.runs < 2 {
        return Err(TruthError::Input(format!(
            "{} run(s): the standard error is measured from at least 2 independent runs",
            s.runs
        )));
    }
    if s.samples == 0 {
        return Err(TruthError::Input("0 samples per pixel: ask for at least 1".into()));
    }
    if let Some(t) = s.target_std_error
        && !(t > 0.0 && t.is_finite())
    {
        return Err(TruthError::Input(format!("target standard error {t}: it must be > 0")));
    }
    Ok(())
}

fn chunk_seed(seed: u64, n: u32, run: u32, chunk: u64) -> u64 {
    let mut b = [0u8; 24];
    b[..8].copy_from_slice(&seed.to_le_bytes());
    b[8..12].copy_from_slice(&n.to_le_bytes());
    b[12..16].copy_from_slice(&run.to_le_bytes());
    b[16..].copy_from_slice(&chunk.to_le_bytes());
    xxh3_64(&b)
}

// ---------------------------------------------------------------------------------------
// The cache
// ---------------------------------------------------------------------------------------

/// A cache key: a 128-bit XXH3 hash of everything that determines a [`Truth`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CacheKey(pub u128);

impl fmt::Display for CacheKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:032x}", self.0)
    }
}

/// The key of the truth of `scene` at `points` with `settings`: a hash
/// of the scene file's bytes and every OBJ mesh's bytes (when the scene was loaded from a
/// file), the camera (resolution included) and lights as loaded and possibly changed since,
/// the world-space geometry, the image size, the positions and normals (bit for bit), the
/// settings, [`TRUTH_VERSION`] and the crate version. The shadow-map resolution is left
/// out: it changes no position.
pub fn cache_key(scene: &Scene, points: &Points, settings: &TruthSettings) -> Result<CacheKey, TruthError> {
    let Points {
        width,
        height,
        positions,
        normals,
    } = *points;
    let mut h = Xxh3::new();
    let mut field = |name: &str, bytes: &[u8]| {
        h.update(name.as_bytes());
        h.update(&(bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field("version", format!("{TRUTH_VERSION} {}", env!("CARGO_PKG_VERSION")).as_bytes());
    if let Some(path) = scene.source() {
        let text = sshc_scene::read_capped(path, sshc_scene::MAX_TEXT_BYTES).map_err(io_error(path))?;
        field("scene file", &text);
        for mesh in scene.files() {
            let bytes = sshc_scene::read_capped(mesh, crate::scene::MAX_OBJ_BYTES).map_err(io_error(mesh))?;
            field("mesh", &bytes);
        }
    }
    field("camera", to_ron(&scene.camera).as_bytes());
    field("lights", to_ron(&scene.lights).as_bytes());
    field("objects", to_ron(&scene.objects()).as_bytes());
    let vertices: Vec<u8> = scene.vertex_data().iter().flat_map(|v| v.to_le_bytes()).collect();
    field("geometry", &vertices);
    field("size", &[width.to_le_bytes(), height.to_le_bytes()].concat());
    let floats = |v: &[Vec3]| -> Vec<u8> {
        v.iter()
            .flat_map(|p| p.to_array())
            .flat_map(|x| x.to_bits().to_le_bytes())
            .collect()
    };
    field("positions", &floats(positions));
    field("normals", &floats(normals));
    field("settings", to_ron(settings).as_bytes());
    Ok(CacheKey(h.digest128()))
}

/// RON text of a value, for hashing. Serialising plain data to a string cannot fail; an
/// empty string would only make a key that never hits.
fn to_ron<T: Serialize>(v: &T) -> String {
    ron::to_string(v).unwrap_or_default()
}

/// What [`TruthCache::load`] found.
#[derive(Clone, Debug, PartialEq)]
pub enum CacheLookup {
    /// A stored truth for this key.
    Hit(Box<Truth>),
    /// Nothing stored for this key.
    Miss,
    /// A file for this key that cannot be used (it is recomputed and overwritten): why.
    Unreadable(String),
}

/// Ground truths stored on disk, one RON file per key. The folder may be shared by any
/// number of processes and hosts: [`compute_cached`] claims a key before computing it
/// (`KEY.claim`, [`crate::claim`]), so that one computes and the others wait and read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TruthCache {
    dir: PathBuf,
    /// How long a claim may stand still (its owner's beats stopped) before a waiter takes
    /// it over.
    stale_after: Duration,
}

use sshc_records::truth::{Record, checksum};

impl TruthCache {
    /// The default folder, relative to the working directory: `.sshc-cache/truth`.
    pub const DEFAULT_DIR: &'static str = ".sshc-cache/truth";

    /// How long a claim stands still before it is taken over, by default: its owner
    /// beats four times in this time.
    pub const DEFAULT_STALE_AFTER: Duration = Duration::from_secs(120);

    /// A cache in `dir` (created on the first store).
    pub fn new(dir: impl Into<PathBuf>) -> TruthCache {
        TruthCache {
            dir: dir.into(),
            stale_after: Self::DEFAULT_STALE_AFTER,
        }
    }

    /// The same cache with claims taken over after `stale_after` without a beat.
    pub fn with_stale_after(self, stale_after: Duration) -> TruthCache {
        TruthCache { stale_after, ..self }
    }

    /// The cache's folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file of `key`.
    pub fn path(&self, key: CacheKey) -> PathBuf {
        self.dir.join(format!("{key}.ron"))
    }

    /// The claim file of `key`, present while a process computes it.
    pub fn claim_path(&self, key: CacheKey) -> PathBuf {
        self.dir.join(format!("{key}.claim"))
    }

    /// The truth stored for `key`, if any (a regular file of at most [`MAX_RECORD_BYTES`]).
    pub fn load(&self, key: CacheKey) -> CacheLookup {
        let path = self.path(key);
        let text = match sshc_scene::read_text(&path, MAX_RECORD_BYTES) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return CacheLookup::Miss,
            Err(e) => return CacheLookup::Unreadable(format!("{}: {e}", path.display())),
        };
        match sshc_records::truth::parse_record(&text, &key.to_string(), &path) {
            Ok(t) => CacheLookup::Hit(Box::new(t)),
            Err(why) => CacheLookup::Unreadable(why),
        }
    }

    /// Stores `truth` under `key`: written to a temporary file of a name no other writer
    /// has (`KEY.HOST.PID.RANDOM.tmp`, created exclusively: another process, thread or
    /// machine sharing the folder writes its own), then renamed over the record, so that a
    /// reader never sees half a file and the last writer's whole record wins.
    pub fn store(&self, key: CacheKey, truth: &Truth) -> Result<PathBuf, TruthError> {
        std::fs::create_dir_all(&self.dir).map_err(io_error(&self.dir))?;
        let path = self.path(key);
        let record = Record {
            key: key.to_string(),
            checksum: Some(checksum(truth).map_err(|message| TruthError::Io {
                path: path.clone(),
                message,
            })?),
            truth: truth.clone(),
        };
        let text = ron::to_string(&record).map_err(|e| TruthError::Io {
            path: path.clone(),
            message: e.to_string(),
        })?;
        let mut tmp = tempfile::Builder::new()
            .prefix(&format!("{key}.{}.", crate::claim::process_tag()))
            .suffix(".tmp")
            .tempfile_in(&self.dir)
            .map_err(io_error(&self.dir))?;
        std::io::Write::write_all(&mut tmp, text.as_bytes()).map_err(io_error(tmp.path()))?;
        tmp.persist(&path).map_err(|e| io_error(&path)(e.error))?;
        Ok(path)
    }
}

/// Where a truth came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// Computed now (and stored when a cache was given; the file stored).
    Computed(Option<PathBuf>),
    /// Read from the cache file.
    Cached(PathBuf),
}

/// [`compute`], through `cache` when given: a stored truth for the same key is returned
/// as it is; otherwise the key is claimed (`KEY.claim`), computed and stored, while the
/// claim's owner beats every quarter of the cache's stale time. A key another process
/// claims is waited for and read once stored; a claim that stands still for the stale time
/// (or whose process ended on this host) is taken over. A cache file that cannot be used
/// is recomputed. `note` is told, in lines to print as they are, of an unusable file, a
/// wait and a take-over.
pub fn compute_cached(
    scene: &Scene,
    points: &Points,
    settings: &TruthSettings,
    cache: Option<&TruthCache>,
    progress: &(dyn Fn(Progress) + Sync),
    note: &dyn Fn(&str),
) -> Result<(Truth, Source), TruthError> {
    check_inputs(points, settings)?;
    if scene.lights.is_empty() {
        return Err(TruthError::NoLight);
    }
    // computed here, without a cache (none given, or one that cannot be written)
    let uncached = || -> Result<(Truth, Source), TruthError> {
        let vis = Visibility::new(scene);
        Ok((compute(scene, &vis, points, settings, progress)?, Source::Computed(None)))
    };
    let Some(cache) = cache else {
        return uncached();
    };
    let key = cache_key(scene, points, settings)?;
    let claim_path = cache.claim_path(key);
    let mut watch = Watch::new(cache.stale_after);
    let poll = (cache.stale_after / 8).clamp(Duration::from_millis(10), Duration::from_secs(1));
    let (mut waiting, mut warned) = (false, false);
    loop {
        match cache.load(key) {
            CacheLookup::Hit(t) => return Ok((*t, Source::Cached(cache.path(key)))),
            CacheLookup::Miss => {}
            CacheLookup::Unreadable(why) if !warned => {
                warned = true;
                note(&format!("warning: ignoring an unusable cached truth: {why}"));
            }
            CacheLookup::Unreadable(_) => {}
        }
        // a cache that cannot be written is left out, said once, and the truth computed
        // without it (it ended the run with a bare OS error; issue 48, item 17)
        let unwritable = |why: String| -> Result<(Truth, Source), TruthError> {
            note(&format!(
                "warning: the truth cache cannot be written ({why}): computing without it (pass --no-cache, or --cache DIR with a writable folder)"
            ));
            uncached()
        };
        if let Err(e) = std::fs::create_dir_all(&cache.dir) {
            return unwritable(format!("{}: {e}", cache.dir.display()));
        }
        let attempt = match Claim::try_take(&claim_path) {
            Ok(a) => a,
            Err(e) => return unwritable(format!("{}: {e}", claim_path.display())),
        };
        match attempt {
            Attempt::Taken(claim) => {
                // stored between the look-up and the claim: read it
                if let CacheLookup::Hit(t) = cache.load(key) {
                    return Ok((*t, Source::Cached(cache.path(key))));
                }
                let (truth, claim) = compute_beating(scene, points, settings, progress, claim, cache.stale_after / 4);
                let truth = truth?;
                // a record that cannot be stored leaves the truth computed: kept, and said
                let stored = match cache.store(key, &truth) {
                    Ok(p) => Some(p),
                    Err(e) => {
                        note(&format!(
                            "warning: the truth was computed but cannot be cached ({e}); it is used as computed (pass --no-cache to skip the cache)"
                        ));
                        None
                    }
                };
                // released once the record is in place: a waiter reads it next
                drop(claim);
                return Ok((truth, Source::Computed(stored)));
            }
            Attempt::Held(text) => {
                if watch.is_stale(&text) {
                    note(&format!(
                        "truth: taking over the stale claim of {} ({}: no beat for {} s, or its process ended)",
                        claim::describe(&text),
                        claim_path.display(),
                        cache.stale_after.as_secs_f64()
                    ));
                    claim::remove_stale(&claim_path, &text).map_err(io_error(&claim_path))?;
                    watch.reset();
                    continue;
                }
                if !waiting {
                    waiting = true;
                    note(&format!(
                        "truth: waiting for {}, which is computing this truth ({})",
                        claim::describe(&text),
                        claim_path.display()
                    ));
                }
                std::thread::sleep(poll);
            }
        }
    }
}

/// [`compute`] while a thread beats `claim` every `interval`; the claim is handed back
/// (to be dropped, which releases it, once the truth is stored).
fn compute_beating(
    scene: &Scene,
    points: &Points,
    settings: &TruthSettings,
    progress: &(dyn Fn(Progress) + Sync),
    claim: Claim,
    interval: Duration,
) -> (Result<Truth, TruthError>, Option<Claim>) {
    let (stop, stopped) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|s| {
        let beating = s.spawn(move || {
            let mut claim = claim;
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = stopped.recv_timeout(interval) {
                // a beat that fails (a full disk) only lets waiters take over sooner
                let _ = claim.beat();
            }
            claim
        });
        let vis = Visibility::new(scene);
        let truth = compute(scene, &vis, points, settings, progress);
        drop(stop);
        (truth, beating.join().ok())
    })
}
