//! Each shadow's error against sshc's truth, measured from the frames Bevy shaded
//! (docs/bevy.md, "Against the truth"; `scripts/bevy-truth.sh` runs it all).
//!
//! The `shadows` example, with `--float --still`, writes frames in linear light. Bevy's
//! lighting is linear in a directional light's shadow term: a pixel is `A + V D`, where `A`
//! is the rest of the lighting (`--light off`), `A + D` the light unshadowed
//! (`--light unshadowed`) and `V` the visibility the shadow applied, sshc's or Bevy's own.
//! So every shadow's visibility is measured the same way, from its frame and those two:
//! `V = (F - A) / D`, on luminance, where the light's direct term `D` is at least 5 % of
//! its brightest in the frame (elsewhere the surface faces away, and any `V` shades alike).
//! `--check NAME=VIS.pfm` compares that measure with sshc's own visibility image of the
//! same run: the measure's own error.
//!
//! `against_truth equal INSIDE.pfm RENDER.pfm`: sshc inside Bevy against `sshc render` of
//! the exported scene, bit for bit (the suite's check; see [`equal`]).
//!
//! `cargo run --ignore-rust-version --example against_truth -- measure --truth T.pfm
//!  --unshadowed U/frame-000.pfm --off O/frame-000.pfm --out DIR NAME=FRAME.pfm ...`
//! prints a Markdown table and writes it, and `DIR/side-by-side.png`: a column per shadow,
//! the truth first, its visibility above and its error below (red where it is too dark,
//! blue too light, full at 0.5; grey outside the measured pixels).

use clap::Parser;
use std::io::Read;
use std::path::{Path, PathBuf};

#[derive(Parser)]
enum Command {
    /// Each shadow's error against the truth, measured from its frame.
    Measure(Args),
    /// sshc's visibility inside Bevy (`shadows --visibility`) against `sshc render
    /// --visibility` of the scene the plugin exported: equal but for the pixels the two
    /// paths' f32 rounding may decide (see `equal`'s comment).
    Equal {
        /// The plugin's visibility (`visibility-000.pfm`).
        inside: PathBuf,
        /// `sshc render --visibility` of the exported scene.
        render: PathBuf,
    },
}

#[derive(clap::Args)]
struct Args {
    /// The truth: `sshc truth`'s one-channel PFM at the frames' pixels.
    #[arg(long)]
    truth: PathBuf,
    /// The light unshadowed (`shadows --float --light unshadowed`).
    #[arg(long)]
    unshadowed: PathBuf,
    /// The light off (`shadows --float --light off`).
    #[arg(long)]
    off: PathBuf,
    /// The folder of the table and the picture.
    #[arg(long)]
    out: PathBuf,
    /// `NAME=VIS.pfm`: sshc's visibility image of shadow NAME's run, to measure the
    /// measure's own error against.
    #[arg(long, value_parser = named)]
    check: Vec<(String, PathBuf)>,
    /// `NAME=FRAME.pfm`: each shadow's frame, in the picture's order.
    #[arg(required = true, value_parser = named)]
    shadows: Vec<(String, PathBuf)>,
}

fn named(s: &str) -> Result<(String, PathBuf), String> {
    let (name, path) = s.split_once('=').ok_or("NAME=FILE")?;
    match !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || "-_ .()".contains(c)) {
        true => Ok((name.to_string(), PathBuf::from(path))),
        false => Err(format!("`{name}`: a name of letters, digits, spaces and -_.()")),
    }
}

/// The largest side read: the example's frames are at most 4096 pixels wide.
const MAX_SIDE: usize = 4096;

/// An image's pixels (one or three channels), rows top first.
struct Pfm {
    width: usize,
    height: usize,
    channels: usize,
    data: Vec<f32>,
}

/// A PFM file: a regular file, at most a 4096^2 colour image's bytes, decoded by `pxm`.
fn read_pfm(path: &Path) -> Result<Pfm, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let meta = std::fs::metadata(path).map_err(|e| at(&e))?;
    if !meta.is_file() {
        return Err(at(&"not a regular file"));
    }
    let cap = (MAX_SIDE * MAX_SIDE * 12 + 64) as u64;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(|e| at(&e))?
        .take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| at(&e))?;
    if bytes.len() as u64 > cap {
        return Err(at(&format!("over {cap} bytes")));
    }
    let pfm = pxm::PFM::read_from(&mut bytes.as_slice()).map_err(|e| at(&e))?;
    let channels = if pfm.color { 3 } else { 1 };
    if pfm.width == 0
        || pfm.width > MAX_SIDE
        || pfm.height == 0
        || pfm.height > MAX_SIDE
        || pfm.data.len() != pfm.width * pfm.height * channels
    {
        return Err(at(&format!("a {}x{} image of {} values", pfm.width, pfm.height, pfm.data.len())));
    }
    Ok(Pfm {
        width: pfm.width,
        height: pfm.height,
        channels,
        data: pfm.data,
    })
}

impl Pfm {
    /// Linear luminance (Rec. 709) per pixel, or the one channel.
    fn luminance(&self) -> Vec<f32> {
        match self.channels {
            3 => self
                .data
                .chunks_exact(3)
                .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
                .collect(),
            _ => self.data.clone(),
        }
    }
}

/// The light's direct term below this share of its brightest in the frame: not measured.
const DIRECT_SHARE: f32 = 0.05;

/// A truth value strictly between these is in the penumbra.
const PENUMBRA: (f32, f32) = (0.02, 0.98);

/// One shadow's errors over the measured pixels.
struct Errors {
    rms: f64,
    penumbra_rms: f64,
    bias: f64,
    over_01: f64,
}

fn errors(v: &[f32], truth: &[f32], mask: &[bool]) -> Errors {
    let (mut n, mut sq, mut sum, mut over, mut pn, mut psq) = (0u64, 0.0f64, 0.0f64, 0u64, 0u64, 0.0f64);
    for ((&v, &t), &m) in v.iter().zip(truth).zip(mask) {
        if !m {
            continue;
        }
        let d = f64::from(v) - f64::from(t);
        n += 1;
        sq += d * d;
        sum += d;
        over += u64::from(d.abs() > 0.1);
        if t > PENUMBRA.0 && t < PENUMBRA.1 {
            pn += 1;
            psq += d * d;
        }
    }
    let n = n.max(1) as f64;
    Errors {
        rms: (sq / n).sqrt(),
        penumbra_rms: (psq / pn.max(1) as f64).sqrt(),
        bias: sum / n,
        over_01: over as f64 / n,
    }
}

fn main() -> std::process::ExitCode {
    let outcome = match Command::parse() {
        Command::Measure(a) => run(a),
        Command::Equal { inside, render } => equal(&inside, &render),
    };
    match outcome {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(a: Args) -> Result<(), String> {
    let truth = read_pfm(&a.truth)?;
    let (w, h) = (truth.width, truth.height);
    let same = |p: &Pfm, path: &Path| match (p.width, p.height) == (w, h) {
        true => Ok(()),
        false => Err(format!("{}: {}x{}, the truth is {w}x{h}", path.display(), p.width, p.height)),
    };
    let (u, o) = (read_pfm(&a.unshadowed)?, read_pfm(&a.off)?);
    same(&u, &a.unshadowed)?;
    same(&o, &a.off)?;
    let (u, o) = (u.luminance(), o.luminance());
    let direct: Vec<f32> = u.iter().zip(&o).map(|(u, o)| u - o).collect();
    let brightest = direct.iter().copied().filter(|d| d.is_finite()).fold(0.0f32, f32::max);
    if brightest <= 0.0 {
        return Err(format!("{}: the light adds nothing to {}", a.unshadowed.display(), a.off.display()));
    }
    let truth = truth.luminance();
    let mask: Vec<bool> = direct
        .iter()
        .zip(&truth)
        .map(|(d, t)| *d > DIRECT_SHARE * brightest && t.is_finite())
        .collect();
    let measured = mask.iter().filter(|m| **m).count();
    let visibility = |frame: &Path| -> Result<Vec<f32>, String> {
        let f = read_pfm(frame)?;
        same(&f, frame)?;
        Ok(f.luminance().iter().zip(&o).zip(&direct).map(|((f, o), d)| (f - o) / d).collect())
    };
    let mut table = "| shadow | RMS | RMS in the penumbra | mean (bias) | pixels off by > 0.1 |\n|---|---|---|---|---|\n".to_string();
    let mut columns = vec![("truth".to_string(), truth.clone())];
    for (name, frame) in &a.shadows {
        let v = visibility(frame)?;
        let e = errors(&v, &truth, &mask);
        table += &format!(
            "| {name} | {:.4} | {:.4} | {:+.4} | {:.2} % |\n",
            e.rms,
            e.penumbra_rms,
            e.bias,
            100.0 * e.over_01
        );
        columns.push((name.clone(), v));
    }
    let penumbra = truth
        .iter()
        .zip(&mask)
        .filter(|(t, m)| **m && **t > PENUMBRA.0 && **t < PENUMBRA.1)
        .count();
    table += &format!(
        "\n{measured} of {} pixels measured (the light's direct term over {:.0} % of its brightest), {penumbra} of them in the truth's penumbra ({} < V < {}).\n",
        w * h,
        100.0 * DIRECT_SHARE,
        PENUMBRA.0,
        PENUMBRA.1
    );
    for (name, vis) in &a.check {
        let Some((_, v)) = columns.iter().find(|(n, _)| n == name) else {
            return Err(format!("--check {name}: no shadow of that name"));
        };
        let own = read_pfm(vis)?;
        same(&own, vis)?;
        let e = errors(v, &own.data, &mask);
        table += &format!(
            "The measure against sshc's own visibility image for {name}: RMS {:.5}, largest share off by > 0.1 {:.3} %.\n",
            e.rms,
            100.0 * e.over_01
        );
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let md = a.out.join("errors.md");
    std::fs::write(&md, &table).map_err(|e| format!("{}: {e}", md.display()))?;
    print!("{table}");
    let png = a.out.join("side-by-side.png");
    picture(&columns, &truth, &mask, w, h)
        .save(&png)
        .map_err(|e| format!("{}: {e}", png.display()))?;
    println!("wrote {} and {}", md.display(), png.display());
    Ok(())
}

/// A column per shadow: its visibility above, its error against the truth below.
fn picture(columns: &[(String, Vec<f32>)], truth: &[f32], mask: &[bool], w: usize, h: usize) -> image::RgbImage {
    let gap = 4;
    let width = columns.len() * (w + gap) - gap;
    let mut img = image::RgbImage::from_pixel(width as u32, (2 * h + gap) as u32, image::Rgb([255, 255, 255]));
    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    for (c, (_, v)) in columns.iter().enumerate() {
        let x0 = c * (w + gap);
        for y in 0..h {
            for x in 0..w {
                let k = y * w + x;
                let (top, bottom) = match mask[k] {
                    false => ([96, 96, 96], [96, 96, 96]),
                    true => {
                        let g = byte(v[k]);
                        // too dark: red; too light: blue; full at 0.5
                        let d = ((v[k] - truth[k]) / 0.5).clamp(-1.0, 1.0);
                        let fade = byte(1.0 - d.abs());
                        let e = if d < 0.0 { [255, fade, fade] } else { [fade, fade, 255] };
                        ([g, g, g], e)
                    }
                };
                img.put_pixel((x0 + x) as u32, y as u32, image::Rgb(top));
                img.put_pixel((x0 + x) as u32, (h + gap + y) as u32, image::Rgb(bottom));
            }
        }
    }
    img
}

/// sshc inside Bevy against `sshc render` of the exported scene: **bit for bit**.
///
/// The same technique runs on the same kind of device on both paths; what differs is how
/// the geometry and the camera reach it. Inside Bevy each mesh is in object space, placed
/// on the GPU by its instance's matrix, and the camera is Bevy's matrix; `sshc render`
/// reads the exported world-space triangles (placed on the CPU) and builds its camera from
/// position, target and field of view. For the example's scene (instances only
/// translated, a camera looking at a point) both give the same f32 positions, so every
/// pixel is equal, and the check allows no difference (measured at 128^2: turns of 30 and
/// 75 degrees, 0 pixels differ). Where a face is edge-on to the sun (a turn of 0 degrees:
/// the box's faces along z), the face's own comparisons are decided by rounding and about
/// 1 % of the pixels flip; the suite's frame is at 30 degrees.
fn equal(inside: &Path, render: &Path) -> Result<(), String> {
    let (a, b) = (read_pfm(inside)?, read_pfm(render)?);
    if (a.width, a.height, a.channels) != (b.width, b.height, b.channels) {
        return Err(format!(
            "{} is {}x{}x{}, {} is {}x{}x{}",
            inside.display(),
            a.width,
            a.height,
            a.channels,
            render.display(),
            b.width,
            b.height,
            b.channels
        ));
    }
    let differ = a.data.iter().zip(&b.data).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
    let shaded = b.data.iter().filter(|v| **v < 1.0).count();
    let penumbra = b.data.iter().filter(|v| **v > 0.0 && **v < 1.0).count();
    println!(
        "{differ} of {} pixels differ in any bit; {shaded} pixels are shadowed, {penumbra} of them in a penumbra",
        a.data.len()
    );
    if penumbra == 0 {
        return Err("no pixel of the render is in a penumbra: nothing was compared".into());
    }
    match differ {
        0 => Ok(()),
        _ => Err(format!("sshc inside Bevy and `sshc render` differ in {differ} pixels")),
    }
}
