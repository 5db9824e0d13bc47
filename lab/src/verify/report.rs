//! What verify reports: the rows as a Markdown table, the count of each verdict and the
//! last line, the note after an UNCHECKED row, and a row as a picture.

use super::verdict::{Row, Verdict};
use std::fmt::Write as _;

impl Row {
    /// The row as a picture, `scale` screen pixels per camera pixel: the GPU's visibility,
    /// the CPU's, and the difference over the allowance (black: equal; through the viridis
    /// map up to the allowance; red: outside it). Pixels not compared stay dark blue.
    pub fn picture(&self, scale: u32) -> image::RgbImage {
        let n = self.camera;
        let s = scale.max(1);
        let mut img = image::RgbImage::from_pixel(3 * n * s + 2 * s, n * s, image::Rgb([16, 16, 48]));
        let grey = |v: f64| {
            let g = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
            image::Rgb([g, g, g])
        };
        for &(i, got, expected, ratio) in &self.compared {
            let (x, y) = ((i as u32) % n, (i as u32) / n);
            let diff = if ratio > 1.0 || ratio.is_nan() {
                image::Rgb([230, 20, 20])
            } else if ratio == 0.0 {
                image::Rgb([0, 0, 0])
            } else {
                let c = colorous::VIRIDIS.eval_continuous(ratio);
                image::Rgb([c.r, c.g, c.b])
            };
            for (panel, colour) in [grey(got), grey(expected), diff].into_iter().enumerate() {
                let x0 = panel as u32 * (n * s + s) + x * s;
                for dy in 0..s {
                    for dx in 0..s {
                        img.put_pixel(x0 + dx, y * s + dy, colour);
                    }
                }
            }
        }
        img
    }
}

/// How many rows got each verdict.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    pub agree: usize,
    pub unchecked: usize,
    pub differ: usize,
    pub lossy: usize,
}

impl Summary {
    pub fn of(rows: &[Row]) -> Summary {
        let mut s = Summary::default();
        for r in rows {
            *match r.verdict {
                Verdict::Agrees => &mut s.agree,
                Verdict::Unchecked => &mut s.unchecked,
                Verdict::Differs => &mut s.differ,
                Verdict::Lossy => &mut s.lossy,
            } += 1;
        }
        s
    }

    /// The counts in words: `14 agree, 2 UNCHECKED, 0 DIFFER, 0 LOSSY (16 rows)`.
    pub fn counts(&self) -> String {
        format!(
            "{} agree, {} UNCHECKED, {} DIFFER, {} LOSSY ({} rows)",
            self.agree,
            self.unchecked,
            self.differ,
            self.lossy,
            self.agree + self.unchecked + self.differ + self.lossy
        )
    }

    /// The command's last line when nothing fails (DIFFERS, LOSSY): agreement on every
    /// input only where every row agrees; UNCHECKED rows said to be such.
    pub fn line(&self) -> String {
        if self.unchecked == 0 {
            format!("verdict: agrees on every input: {}", self.counts())
        } else {
            format!(
                "verdict: nothing differs, but {} row{} UNCHECKED (an allowance of 1/2 or more admits a GPU value 1/2 or more from the CPU's: lit cannot be told from shadowed there): {}",
                self.unchecked,
                if self.unchecked == 1 { " is" } else { "s are" },
                self.counts()
            )
        }
    }
}

/// What `sshc verify` says after its table of an UNCHECKED row: how many receivers, and the
/// one with the largest difference.
pub fn unchecked_note(r: &Row) -> Option<String> {
    let w = r.unchecked_worst?;
    Some(format!(
        "note: {} (camera {}): UNCHECKED at {} receiver{}: GPU and CPU 1/2 or more apart within an allowance of 1/2 or more, which tells a lit pixel from a shadowed one at none of them; the largest at ({}, {}): {:.6} against {:.6}, allowance {:.3}",
        r.input,
        r.camera,
        r.unchecked,
        if r.unchecked == 1 { "" } else { "s" },
        w.pixel.0,
        w.pixel.1,
        w.got,
        w.expected,
        w.allowance
    ))
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let with_reference = rows.iter().any(|r| r.reference.is_some());
    let mut s = String::from(
        "| input | camera | receivers | loose | outside | max diff | median allowance | worst (pixel: got, expected, allowance) | storage p99 |",
    );
    if with_reference {
        s.push_str(" reference outside | reference max diff |");
    }
    s.push_str(" verdict |\n|---|---|---|---|---|---|---|---|---|");
    if with_reference {
        s.push_str("---|---|");
    }
    s.push_str("---|\n");
    for r in rows {
        let worst = r.worst.map_or("-".into(), |w| {
            format!(
                "({}, {}): {:.6}, {:.6}, {:.2e} ({:.2} of it)",
                w.pixel.0,
                w.pixel.1,
                w.got,
                w.expected,
                w.allowance,
                w.ratio()
            )
        });
        let _ = write!(
            s,
            "| {} | {} | {} | {} | {} | {:.2e} | {:.2e} | {} | {:.2e} |",
            r.input, r.camera, r.receivers, r.loose, r.outside, r.max_diff, r.median_allowance, worst, r.storage
        );
        if with_reference {
            match r.reference {
                Some((out, max, _)) => {
                    let _ = write!(s, " {out} | {max:.2e} |");
                }
                None => s.push_str(" - | - |"),
            }
        }
        let _ = writeln!(s, " {} |", r.verdict.name());
    }
    let debug: Vec<&str> = rows
        .first()
        .map(|r| r.debug.iter().map(|d| d.name.as_str()).collect())
        .unwrap_or_default();
    if !debug.is_empty() {
        s.push_str("\nDebug outputs, each against its CPU evaluation (every component, every cascade):\n\n| input | camera | output | values | outside | max diff | worst (pixel: got, expected, allowance) |\n|---|---|---|---|---|---|---|\n");
        for r in rows {
            for d in &r.debug {
                let worst = d.worst.map_or("-".into(), |w| {
                    format!(
                        "({}, {}): {:.6}, {:.6}, {:.2e}",
                        w.pixel.0, w.pixel.1, w.got, w.expected, w.allowance
                    )
                });
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {:.2e} | {worst} |",
                    r.input, r.camera, d.name, d.values, d.outside, d.max_diff
                );
            }
        }
    }
    s
}
