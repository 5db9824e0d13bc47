//! The ray-traced truth refined while the view stands still: on a thread of its own, the
//! lab's truth ([`crate::truth::compute`]) is computed again and again at the camera's
//! positions, each round an independent estimate (two runs of a stratified grid, its own
//! seed), and the rounds are averaged; the spread of the rounds gives the standard error of
//! the mean. A moved view or light starts it over.

use crate::scene::Scene;
use crate::truth::{self, Points, TruthSettings};
use crate::visibility::Visibility;
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Instant;

/// Light samples per pixel in each round (a 4 x 4 grid per run, two runs).
const ROUND_SAMPLES: u32 = 16;
/// Light samples per pixel each round adds (its two runs).
pub const SAMPLES_PER_ROUND: u32 = 2 * ROUND_SAMPLES;

/// The truth so far.
pub struct Estimate {
    /// The view it is of (the request's id).
    pub id: u64,
    pub width: u32,
    pub height: u32,
    /// Mean visibility per pixel over the rounds (NaN where no surface is seen).
    pub visibility: Vec<f32>,
    /// Standard error of that mean per pixel (rounds' spread / sqrt(rounds); 0 without a
    /// surface; from the runs of the one round before a second).
    pub std_error: Vec<f32>,
    pub rounds: u32,
    /// Seconds since this view's first round began.
    pub seconds: f64,
    /// The pixels whose surface faces the light (its centre, or its direction at
    /// infinity): where the RMS is taken.
    pub facing: Vec<bool>,
}

impl Estimate {
    /// Mean and largest standard error over the pixels that show a surface.
    pub fn std_errors(&self) -> (f32, f32) {
        let se: Vec<f32> = self
            .visibility
            .iter()
            .zip(&self.std_error)
            .filter(|(v, _)| v.is_finite())
            .map(|(_, e)| *e)
            .collect();
        let mean = se.iter().sum::<f32>() / se.len().max(1) as f32;
        (mean, se.iter().copied().fold(0.0, f32::max))
    }
}

pub struct Refiner {
    to: Option<mpsc::Sender<Job>>,
    from: mpsc::Receiver<Estimate>,
    stop: Arc<AtomicBool>,
    next: u64,
    /// The id of the view being refined.
    pub current: Option<u64>,
    paused: bool,
}

struct Job {
    id: u64,
    scene: Scene,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    stop: Arc<AtomicBool>,
}

impl Refiner {
    pub fn start() -> Refiner {
        let (to, jobs) = mpsc::channel::<Job>();
        let (estimates, from) = mpsc::channel();
        std::thread::spawn(move || {
            let mut pending: Option<Job> = None;
            loop {
                let job = match pending.take() {
                    Some(j) => j,
                    None => match jobs.recv() {
                        Ok(j) => j,
                        Err(_) => break,
                    },
                };
                if refine(job, &jobs, &estimates, &mut pending).is_err() {
                    break;
                }
            }
        });
        Refiner {
            to: Some(to),
            from,
            stop: Arc::new(AtomicBool::new(false)),
            next: 0,
            current: None,
            paused: false,
        }
    }

    /// Start over at these camera positions and normals (the view or the light moved).
    pub fn restart(&mut self, scene: Scene, positions: Vec<Vec3>, normals: Vec<Vec3>) {
        self.stop.store(true, Ordering::Relaxed);
        self.stop = Arc::new(AtomicBool::new(self.paused));
        self.next += 1;
        self.current = Some(self.next);
        if let Some(to) = &self.to {
            let _ = to.send(Job {
                id: self.next,
                scene,
                positions,
                normals,
                stop: self.stop.clone(),
            });
        }
    }

    /// Stop refining (the rounds in flight end at their next chunk) until `restart`.
    pub fn pause(&mut self, paused: bool) {
        self.paused = paused;
        if paused {
            self.stop.store(true, Ordering::Relaxed);
        }
    }

    /// The newest estimate of the current view, if a round has ended since the last call.
    pub fn poll(&self) -> Option<Estimate> {
        let mut latest = None;
        while let Ok(e) = self.from.try_recv() {
            if Some(e.id) == self.current {
                latest = Some(e);
            }
        }
        latest
    }
}

/// Rounds for one job until it is stopped or a newer job comes (left in `pending`).
fn refine(job: Job, jobs: &mpsc::Receiver<Job>, out: &mpsc::Sender<Estimate>, pending: &mut Option<Job>) -> Result<(), ()> {
    let (width, height) = job.scene.camera_size();
    let vis = Visibility::new(&job.scene);
    let points = Points {
        width,
        height,
        positions: &job.positions,
        normals: &job.normals,
    };
    let n = job.positions.len();
    let (mut mean, mut m2) = (vec![0f64; n], vec![0f64; n]);
    let light = job.scene.lights.first();
    let facing: Vec<bool> = job
        .positions
        .iter()
        .zip(&job.normals)
        .map(|(p, nrm)| {
            let to_light = match light.and_then(|l| l.center()) {
                Some(c) => c - *p,
                None => light.and_then(|l| l.direction()).unwrap_or(Vec3::Y),
            };
            p.is_finite() && nrm.dot(to_light) > 0.0
        })
        .collect();
    let start = Instant::now();
    let mut first_se = Vec::new();
    for round in 0u32.. {
        if job.stop.load(Ordering::Relaxed) {
            return Ok(());
        }
        if let Ok(newer) = jobs.try_recv() {
            *pending = Some(newer);
            return Ok(());
        }
        let settings = TruthSettings {
            samples: ROUND_SAMPLES,
            runs: 2,
            seed: u64::from(round) * 7919 + 1,
            ..Default::default()
        };
        // a round is not cut short: a restart waits for the round in flight
        let Ok(t) = truth::compute(&job.scene, &vis, &points, &settings, &|_| {}) else {
            return Ok(());
        };
        if job.stop.load(Ordering::Relaxed) {
            return Ok(());
        }
        // Welford's running mean and variance of the rounds' estimates
        let k = f64::from(round + 1);
        for (i, v) in t.visibility.iter().enumerate() {
            let x = f64::from(*v);
            let d = x - mean[i];
            mean[i] += d / k;
            m2[i] += d * (x - mean[i]);
        }
        if round == 0 {
            first_se = t.std_error.clone();
        }
        let std_error = if round == 0 {
            first_se.clone()
        } else {
            m2.iter().map(|m| ((m / (k - 1.0)) / k).sqrt() as f32).collect()
        };
        let visibility = mean.iter().map(|m| *m as f32).collect::<Vec<f32>>();
        let visibility = visibility
            .iter()
            .zip(&job.positions)
            .map(|(v, p)| if p.is_finite() { *v } else { f32::NAN })
            .collect();
        let std_error = std_error
            .iter()
            .zip(&job.positions)
            .map(|(e, p)| if p.is_finite() && e.is_finite() { *e } else { 0.0 })
            .collect();
        out.send(Estimate {
            id: job.id,
            width,
            height,
            visibility,
            std_error,
            rounds: round + 1,
            seconds: start.elapsed().as_secs_f64(),
            facing: facing.clone(),
        })
        .map_err(|_| ())?;
    }
    Ok(())
}

/// RMS of `vis - truth` over the pixels that face the light (`facing`), and over those of
/// them in the penumbra (truth strictly between 0.02 and 0.98).
pub fn rms(vis: &[f32], truth: &[f32], facing: &[bool]) -> (f64, f64) {
    let (mut all, mut na, mut pen, mut np) = (0.0, 0usize, 0.0, 0usize);
    for ((v, t), f) in vis.iter().zip(truth).zip(facing) {
        if !(*f && v.is_finite() && t.is_finite()) {
            continue;
        }
        let e = f64::from(v - t).powi(2);
        all += e;
        na += 1;
        if *t > 0.02 && *t < 0.98 {
            pen += e;
            np += 1;
        }
    }
    ((all / na.max(1) as f64).sqrt(), (pen / np.max(1) as f64).sqrt())
}
