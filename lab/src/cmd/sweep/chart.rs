//! The Pareto charts of `sshc sweep` and `sshc tune`: error against cost (time or memory,
//! on a log axis), a colour per technique, the front drawn through the configurations no
//! other beats, each of the front's points labelled with its configuration, the legend
//! (and what the error bars span) in a panel beside the plot, never over a point, and a
//! time's spread over repeated timings as a horizontal error bar through its median.
//! SVG or PNG by the file's extension, both with the bundled font.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{BackendColor, BackendCoord, DrawingErrorKind};
use std::ops::Range;
use std::path::Path;

/// One configuration on a chart.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Point {
    /// Its technique: the colour and the legend's entry.
    pub technique: String,
    /// Its configuration (`shadow_map=64 N=16`), the label of a point on the front.
    pub config: String,
    pub x: f64,
    pub y: f64,
    /// The fastest and slowest of its repeated timings, where `x` is a time that has
    /// them: an error bar from one to the other.
    pub spread: Option<(f64, f64)>,
}

impl Point {
    /// The label a point on the front carries: its technique and its configuration.
    pub fn label(&self) -> String {
        if self.config.is_empty() {
            self.technique.clone()
        } else {
            format!("{}: {}", self.technique, self.config)
        }
    }

    /// Its error bar, where it has one wider than nothing.
    fn bar(&self) -> Option<(f64, f64)> {
        self.spread
            .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && *lo > 0.0 && hi > lo)
    }
}

/// What a chart says besides its points.
pub(crate) struct Chart<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// What the error bars span, in words (the legend's caption, where a point has one).
    pub spread: &'a str,
    /// The chosen configuration (the tuner's): a cross at `(x, y)` and its label.
    pub mark: Option<(f64, f64, &'a str)>,
}

/// The chart's size in pixels, and the plot's share of its width: the legend panel holds
/// the rest.
pub(crate) const SIZE: (u32, u32) = (1100, 640);
pub(crate) const PLOT_WIDTH: u32 = 800;

const FONT: &str = "sshc-sweep";

/// Where a chart's parts were drawn, in pixels: what the tests check.
#[derive(Clone, Debug, Default)]
pub(crate) struct Layout {
    /// The plotting area (inside the axes).
    pub plot: (Range<i32>, Range<i32>),
    /// The legend panel's left edge: every legend entry lies right of it (what the tests
    /// check the legend's place against).
    #[cfg_attr(not(test), expect(dead_code))]
    pub legend_x: i32,
    /// Each front point's label and the box it was drawn in.
    pub labels: Vec<(String, (i32, i32, i32, i32))>,
    /// Error bars drawn.
    pub bars: usize,
}

/// Draws `pts` (every `x > 0`) into `path`, SVG or PNG by its extension.
pub(crate) fn chart(path: &Path, pts: &[Point], c: &Chart) -> Result<Layout, String> {
    if pts.is_empty() {
        return Err(format!("error: {}: nothing to plot", path.display()));
    }
    crate::session::writable(path)?;
    // text is measured with the bundled font in both backends
    plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR)
        .map_err(|_| "error: the bundled font cannot be read".to_string())?;
    if path.extension().is_some_and(|e| e == "svg") {
        let (text, layout) = svg(pts, c)?;
        crate::session::write_new(path, text)?;
        Ok(layout)
    } else {
        let mut buf = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        let layout = {
            let backend = Bitmap::new(BitMapBackend::with_buffer(&mut buf, SIZE))?;
            draw(&backend.into_drawing_area(), pts, c)?
        };
        let img = image::RgbImage::from_raw(SIZE.0, SIZE.1, buf).ok_or_else(|| "error: chart buffer of the wrong size".to_string())?;
        crate::session::save_image(&img, path)?;
        Ok(layout)
    }
}

/// The chart as SVG text.
pub(crate) fn svg(pts: &[Point], c: &Chart) -> Result<(String, Layout), String> {
    plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR)
        .map_err(|_| "error: the bundled font cannot be read".to_string())?;
    let mut text = String::new();
    let layout = {
        let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
        draw(&root, pts, c)?
    };
    Ok((text, layout))
}

/// A tick value as an axis prints it: at most three significant digits, no trailing zeros
/// or point, no exponent between 1e-4 and 1e6 (`0.05`, `10`, `2.5`, `1500`).
pub(crate) fn tick_label(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v.is_nan() {
            "NaN".into()
        } else {
            format!("{}", v.abs() * v.signum())
        };
    }
    let a = v.abs();
    if !(1e-4..1e6).contains(&a) {
        let s = format!("{v:.2e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let decimals = (2 - a.log10().floor() as i32).clamp(0, 8) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

/// Ticks of a log axis over `[lo, hi]` (`0 < lo <= hi`): the coarsest of powers of ten;
/// 1, 2 and 5 times them; every whole multiple; every tenth of one, that puts at least
/// [`MIN_TICKS`] on the axis (or the finest, where none does), thinned to at most
/// [`MAX_TICKS`], each value once and no two printed alike.
pub(crate) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo) {
        return Vec::new();
    }
    let mantissas: [Vec<u32>; 4] = [vec![10], vec![10, 20, 50], (1..10).map(|m| m * 10).collect(), (10..100).collect()];
    let (e0, e1) = (lo.log10().floor() as i32 - 1, hi.log10().ceil() as i32 + 1);
    let mut best = Vec::new();
    for set in &mantissas {
        let mut t: Vec<f64> = Vec::new();
        for e in e0..=e1 {
            for &m in set {
                // the decimal m/10 x 10^e, read from its text: 0.3 is 0.3, not 3 x 0.1
                let Ok(v) = format!("{m}e{}", e - 1).parse::<f64>() else { continue };
                if (lo..=hi).contains(&v) && t.last().is_none_or(|l| tick_label(*l) != tick_label(v)) {
                    t.push(v);
                }
            }
        }
        best = t;
        if best.len() >= MIN_TICKS {
            break;
        }
    }
    if best.len() > MAX_TICKS {
        let step = best.len().div_ceil(MAX_TICKS);
        best = best.into_iter().step_by(step).collect();
    }
    best
}

/// At least this many ticks on a log axis where its range allows, and at most this many.
pub(crate) const MIN_TICKS: usize = 4;
pub(crate) const MAX_TICKS: usize = 12;

/// The configurations no other one beats on both axes (lower x and lower error), in order
/// of x: indices into `pts`.
pub(crate) fn pareto_front(pts: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0).then(pts[a].1.total_cmp(&pts[b].1)));
    let mut front: Vec<usize> = Vec::new();
    for i in order {
        if front.last().is_none_or(|&l| pts[i].1 < pts[l].1) {
            front.push(i);
        }
    }
    front
}

/// Whether two pixel boxes `(x0, y0, x1, y1)` meet.
fn meets(a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Where a label of `size` goes beside the point at pixel `p`: the first of the places
/// around it that stays inside `area` and meets no box of `taken` (the points and the
/// labels placed before it), else the first inside `area`. The label's top left corner,
/// as an offset from the point.
fn place(p: (i32, i32), size: (i32, i32), area: (i32, i32, i32, i32), taken: &[(i32, i32, i32, i32)]) -> (i32, i32) {
    let (w, h) = size;
    let right = 9;
    let left = -9 - w;
    let mut candidates = Vec::new();
    for dy in [-h - 3, 3, -h / 2, -2 * h - 6, h + 6, -3 * h - 9, 2 * h + 9] {
        candidates.push((right, dy));
        candidates.push((left, dy));
    }
    let boxed = |(dx, dy): (i32, i32)| (p.0 + dx, p.1 + dy, p.0 + dx + w, p.1 + dy + h);
    let inside = |b: (i32, i32, i32, i32)| b.0 >= area.0 && b.1 >= area.1 && b.2 <= area.2 && b.3 <= area.3;
    candidates
        .iter()
        .copied()
        .find(|&c| inside(boxed(c)) && !taken.iter().any(|t| meets(*t, boxed(c))))
        .or_else(|| candidates.iter().copied().find(|&c| inside(boxed(c))))
        .unwrap_or((right, -h - 3))
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, plotters::coord::Shift>, pts: &[Point], c: &Chart) -> Result<Layout, String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| format!("error: drawing a chart: {e}");
    root.fill(&WHITE).map_err(e)?;
    let body = root.titled(c.title, (FONT, 18)).map_err(e)?;
    let (left, panel) = body.split_horizontally(PLOT_WIDTH);
    // the x range holds every point, every bar and the mark
    let xs = pts
        .iter()
        .flat_map(|p| [Some(p.x), p.bar().map(|b| b.0), p.bar().map(|b| b.1)])
        .flatten()
        .chain(c.mark.map(|m| m.0));
    let (x0, x1) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    let y1 = pts.iter().map(|p| p.y).chain(c.mark.map(|m| m.1)).fold(0.0f64, f64::max);
    let (x0, x1) = (x0 * 0.8, x1 * 1.25);
    let ticks = log_ticks(x0, x1);
    let mut chart = ChartBuilder::on(&left)
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d((x0..x1).log_scale().with_key_points(ticks), 0.0..y1 * 1.1 + 1e-3)
        .map_err(e)?;
    let fmt = |v: &f64| tick_label(*v);
    chart
        .configure_mesh()
        .x_desc(c.x_label)
        .y_desc(c.y_label)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .y_labels(8)
        .max_light_lines(4)
        .label_style((FONT, 13))
        .draw()
        .map_err(e)?;
    let mut layout = Layout {
        plot: chart.plotting_area().get_pixel_range(),
        legend_x: panel.get_base_pixel().0,
        ..Layout::default()
    };
    let mut techniques: Vec<&str> = pts.iter().map(|p| p.technique.as_str()).collect();
    techniques.sort();
    techniques.dedup();
    let colour = |t: &str| Palette99::pick(techniques.iter().position(|x| *x == t).unwrap_or(0)).to_rgba();
    // error bars under the points: a line from the fastest to the slowest timing, capped
    for p in pts {
        if let Some((lo, hi)) = p.bar() {
            let style = colour(&p.technique).stroke_width(2);
            chart
                .draw_series(std::iter::once(PathElement::new(vec![(lo, p.y), (hi, p.y)], style)))
                .map_err(e)?;
            chart
                .draw_series([lo, hi].map(|x| EmptyElement::at((x, p.y)) + PathElement::new(vec![(0, -5), (0, 5)], style)))
                .map_err(e)?;
            layout.bars += 1;
        }
    }
    for t in &techniques {
        let col = colour(t);
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.technique == *t)
                    .map(|p| Circle::new((p.x, p.y), 5, col.filled())),
            )
            .map_err(e)?;
    }
    let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.x, p.y)).collect();
    let front = pareto_front(&xy);
    chart
        .draw_series(LineSeries::new(front.iter().map(|&i| xy[i]), BLACK.stroke_width(1)))
        .map_err(e)?;
    if let Some((x, y, _)) = c.mark {
        chart
            .draw_series(std::iter::once(Cross::new((x, y), 9, BLACK.stroke_width(3))))
            .map_err(e)?;
    }
    // a label beside each front point (and the mark), clear of the points and one another
    let (xr, yr) = layout.plot.clone();
    let area = (xr.start, yr.start, xr.end, yr.end);
    let to_px = |x: f64, y: f64| chart.backend_coord(&(x, y));
    let mut taken: Vec<(i32, i32, i32, i32)> = xy
        .iter()
        .map(|&(x, y)| {
            let (px, py) = to_px(x, y);
            (px - 6, py - 6, px + 6, py + 6)
        })
        .collect();
    let style = TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Left, VPos::Top));
    let mut labels: Vec<(String, f64, f64)> = front.iter().map(|&i| (pts[i].label(), pts[i].x, pts[i].y)).collect();
    if let Some((x, y, l)) = c.mark {
        labels.push((l.trim().to_string(), x, y));
    }
    for (text, x, y) in labels {
        let (w, h) = root.estimate_text_size(&text, &style).map_err(e)?;
        let p = to_px(x, y);
        let (dx, dy) = place(p, (w as i32, h as i32), area, &taken);
        let b = (p.0 + dx, p.1 + dy, p.0 + dx + w as i32, p.1 + dy + h as i32);
        taken.push(b);
        root.draw(&Text::new(text.clone(), (b.0, b.1), style.clone())).map_err(e)?;
        layout.labels.push((text, b));
    }
    // the legend, in its own panel
    let line = 20;
    let (lx, mut ly) = (12, 40);
    let legend = TextStyle::from((FONT, 13).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    for t in &techniques {
        panel.draw(&Circle::new((lx + 6, ly), 5, colour(t).filled())).map_err(e)?;
        panel.draw(&Text::new(t.to_string(), (lx + 20, ly), legend.clone())).map_err(e)?;
        ly += line;
    }
    panel
        .draw(&PathElement::new(vec![(lx, ly), (lx + 14, ly)], BLACK.stroke_width(1)))
        .map_err(e)?;
    panel
        .draw(&Text::new("Pareto front (labelled)".to_string(), (lx + 20, ly), legend.clone()))
        .map_err(e)?;
    ly += line;
    if c.mark.is_some() {
        panel.draw(&Cross::new((lx + 6, ly), 6, BLACK.stroke_width(3))).map_err(e)?;
        panel
            .draw(&Text::new("chosen".to_string(), (lx + 20, ly), legend.clone()))
            .map_err(e)?;
        ly += line;
    }
    if layout.bars > 0 {
        ly += line / 2;
        panel
            .draw(&PathElement::new(vec![(lx, ly), (lx + 14, ly)], BLACK.stroke_width(2)))
            .map_err(e)?;
        for (k, l) in wrap(c.spread, 34).iter().enumerate() {
            panel
                .draw(&Text::new(l.clone(), (lx + 20, ly + k as i32 * 16), legend.clone()))
                .map_err(e)?;
        }
    }
    root.present().map_err(e)?;
    Ok(layout)
}

/// `text` broken at spaces into lines of at most `width` characters (a longer word alone).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(l) if l.len() + 1 + word.len() <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// A bitmap backend whose text is drawn glyph by glyph at each glyph's own offset.
/// plotters' ab_glyph drawing (0.3.7) drops each glyph's left side bearing, so in the
/// bundled monospace font a `.`, drawn at the left of its cell, leaves a gap after it:
/// ticks read "0. 05" (issue 51). Every other drawing is the bitmap backend's own.
struct Bitmap<'a> {
    inner: BitMapBackend<'a>,
    font: ab_glyph::FontRef<'static>,
}

impl<'a> Bitmap<'a> {
    fn new(inner: BitMapBackend<'a>) -> Result<Bitmap<'a>, String> {
        let font = ab_glyph::FontRef::try_from_slice(epaint_default_fonts::HACK_REGULAR)
            .map_err(|_| "error: the bundled font cannot be read".to_string())?;
        Ok(Bitmap { inner, font })
    }
}

type BitmapError<'a> = DrawingErrorKind<<BitMapBackend<'a> as DrawingBackend>::ErrorType>;

impl<'a> DrawingBackend for Bitmap<'a> {
    type ErrorType = <BitMapBackend<'a> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), BitmapError<'a>> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), BitmapError<'a>> {
        self.inner.present()
    }
    fn draw_pixel(&mut self, point: BackendCoord, color: BackendColor) -> Result<(), BitmapError<'a>> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), BitmapError<'a>> {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        a: BackendCoord,
        b: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), BitmapError<'a>> {
        self.inner.draw_rect(a, b, style, fill)
    }
    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), BitmapError<'a>> {
        self.inner.draw_path(path, style)
    }
    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        centre: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), BitmapError<'a>> {
        self.inner.draw_circle(centre, radius, style, fill)
    }
    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), BitmapError<'a>> {
        self.inner.fill_polygon(vert, style)
    }
    fn blit_bitmap(&mut self, pos: BackendCoord, size: (u32, u32), src: &[u8]) -> Result<(), BitmapError<'a>> {
        self.inner.blit_bitmap(pos, size, src)
    }

    /// plotters-backend's own `draw_text` (anchor, transform, clipping), with the glyphs
    /// placed at their bearings.
    fn draw_text<T: plotters_backend::BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), BitmapError<'a>> {
        use ab_glyph::{Font as _, ScaleFont as _};
        let color = style.color();
        if color.alpha == 0.0 {
            return Ok(());
        }
        let ((min_x, min_y), (max_x, max_y)) = style.layout_box(text).map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        let (width, height) = (max_x - min_x, max_y - min_y);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -width,
            HPos::Center => -width / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -height / 2,
            VPos::Bottom => -height,
        };
        let trans = style.transform();
        let size = style.size() as f32;
        let font = self.font.as_scaled(size);
        let mut x_shift = 0f32;
        let mut prev = None;
        let mut ink: Vec<(i32, i32, f32)> = Vec::new();
        for ch in text.chars() {
            let id = font.glyph_id(ch);
            if let Some(p) = prev {
                x_shift += font.kern(p, id);
            }
            prev = Some(id);
            if let Some(q) = font.outline_glyph(font.scaled_glyph(ch)) {
                let r = q.px_bounds();
                let (gx, gy) = ((x_shift + r.min.x).round() as i32, (size / 2.0 + r.min.y) as i32);
                q.draw(|x, y, c| ink.push((gx + x as i32, gy + y as i32, c)));
            }
            x_shift += font.h_advance(id);
        }
        for (x, y, c) in ink {
            let (x, y) = trans.transform(x + dx - min_x, y + dy - min_y);
            self.inner.draw_pixel((pos.0 + x, pos.1 + y), color.mix(c as f64))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_print_without_stray_spaces_zeros_or_exponents() {
        let cases = [
            (0.05, "0.05"),
            (10.0, "10"),
            (1.0, "1"),
            (0.2, "0.2"),
            (2.5, "2.5"),
            (0.3, "0.3"),
            (1500.0, "1500"),
            (0.001, "0.001"),
            (0.123456, "0.123"),
            (12.26, "12.3"),
            (0.0, "0"),
            (2e-5, "2e-5"),
            (3e7, "3e7"),
            (-0.5, "-0.5"),
        ];
        for (v, want) in cases {
            assert_eq!(tick_label(v), want, "{v}");
        }
    }

    #[test]
    fn log_ticks_are_several_distinct_and_printed_once() {
        // a time ratio from 0.04 to 12: 1, 2, 5 per decade
        let t = log_ticks(0.04, 12.0);
        let labels: Vec<String> = t.iter().map(|v| tick_label(*v)).collect();
        assert_eq!(labels, ["0.05", "0.1", "0.2", "0.5", "1", "2", "5", "10"]);
        for (lo, hi) in [
            (0.8, 1.25),
            (0.5, 0.9),
            (3.0, 40.0),
            (1e-3, 1e6),
            (0.53, 1.22),
            (100.0, 100.0),
            (0.0101, 0.0199),
        ] {
            let t = log_ticks(lo, hi);
            let mut labels: Vec<String> = t.iter().map(|v| tick_label(*v)).collect();
            assert!(t.iter().all(|v| (lo..=hi).contains(v)), "{lo}..{hi}: {t:?}");
            assert!(t.len() <= MAX_TICKS, "{lo}..{hi}: {labels:?}");
            assert!(t.len() >= MIN_TICKS || hi / lo < 1.1, "{lo}..{hi}: {labels:?}");
            assert!(labels.iter().all(|l| !l.contains(' ') && !l.ends_with('.')), "{labels:?}");
            let n = labels.len();
            labels.dedup();
            assert_eq!(labels.len(), n, "{lo}..{hi}: a label twice");
        }
        assert!(log_ticks(0.0, 1.0).is_empty() && log_ticks(f64::NAN, 1.0).is_empty());
    }

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let f = pareto_front(&[(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (0.5, 9.0)]);
        assert_eq!(f, vec![4, 0, 1, 3]);
    }

    fn points() -> Vec<Point> {
        let p = |technique: &str, config: &str, x: f64, y: f64, spread: Option<(f64, f64)>| Point {
            technique: technique.into(),
            config: config.into(),
            x,
            y,
            spread,
        };
        vec![
            p("hard", "shadow_map=32", 0.6, 30.0, Some((0.53, 1.22))),
            p("hard", "shadow_map=128", 0.9, 14.0, Some((0.8, 1.1))),
            p("pcf", "shadow_map=32 N=3", 1.5, 12.0, Some((1.2, 1.9))),
            p("pcf", "shadow_map=128 N=3", 2.5, 13.0, Some((2.4, 2.6))),
            p("pcss", "shadow_map=128", 4.0, 5.0, Some((3.0, 6.5))),
            p("pcss", "shadow_map=32", 3.0, 6.0, None),
        ]
    }

    /// The `<text>` elements of an SVG: (x, y, contents).
    fn texts(svg: &str) -> Vec<(i32, i32, String)> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| {
                let attr = |name: &str| -> Option<i32> {
                    let at = t.find(&format!(" {name}=\""))? + name.len() + 3;
                    t[at..].split('"').next()?.parse().ok()
                };
                let body = t.split_once('>')?.1.split("</text>").next()?;
                Some((attr("x")?, attr("y")?, body.trim().to_string()))
            })
            .collect()
    }

    /// Issue 51: every front point named beside it, the legend in a panel right of the plot
    /// (never over a point), the repeated timings' spread as error bars and said so, and
    /// ticks printed once each without stray spaces.
    #[test]
    fn the_svg_labels_the_front_keeps_the_legend_outside_and_draws_the_spread() {
        let pts = points();
        let c = Chart {
            title: "triangle: RMS penumbra error vs time",
            x_label: "GPU time / reference's",
            y_label: "RMS error",
            spread: "error bars: fastest to slowest of the timed frames",
            mark: None,
        };
        let (svg, layout) = svg(&pts, &c).unwrap();
        let texts = texts(&svg);
        let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.x, p.y)).collect();
        let front = pareto_front(&xy);
        assert_eq!(front, [0, 1, 2, 5, 4]);
        let (xr, yr) = layout.plot.clone();
        assert!(xr.end <= layout.legend_x, "{layout:?}");
        for &i in &front {
            let label = pts[i].label();
            let (x, y, _) = texts
                .iter()
                .find(|t| t.2 == label)
                .unwrap_or_else(|| panic!("no label `{label}` in the SVG"));
            assert!(
                xr.contains(x) && yr.contains(y),
                "`{label}` at ({x}, {y}), outside the plot {layout:?}"
            );
        }
        // labels clear of one another
        for (k, a) in layout.labels.iter().enumerate() {
            for b in &layout.labels[k + 1..] {
                assert!(!meets(a.1, b.1), "{a:?} meets {b:?}");
            }
        }
        // every legend entry right of the plot
        for name in [
            "hard",
            "pcf",
            "pcss",
            "Pareto front (labelled)",
            "error bars: fastest to slowest of",
        ] {
            let (x, _, _) = texts
                .iter()
                .find(|t| t.2 == name)
                .unwrap_or_else(|| panic!("no legend entry `{name}`"));
            assert!(
                *x >= layout.legend_x,
                "legend entry `{name}` at x = {x}, inside the plot (ends at {})",
                xr.end
            );
        }
        // a bar per point with a spread (the last has none)
        assert_eq!(layout.bars, 5);
        // ticks under the plot: 0.5, 1, 2, 5 on the time axis, once each
        let under: Vec<&str> = texts
            .iter()
            .filter(|t| t.1 >= yr.end && t.0 < xr.end)
            .map(|t| t.2.as_str())
            .collect();
        for t in ["0.5", "1", "2", "5"] {
            assert_eq!(under.iter().filter(|x| **x == t).count(), 1, "tick {t}: {under:?}");
        }
        assert!(!texts.iter().any(|t| t.2.contains(". ")), "a label with a stray space");

        // the tuner's chosen point: a cross, named in the plot and in the legend
        let chosen = Chart {
            mark: Some((1.5, 12.0, "chosen: pcf")),
            ..c
        };
        let (svg, layout) = super::svg(&pts, &chosen).unwrap();
        let texts = super::tests::texts(&svg);
        let at = |name: &str| texts.iter().find(|t| t.2 == name).map(|t| t.0);
        assert!(at("chosen: pcf").is_some_and(|x| xr.contains(&x)), "{layout:?}");
        assert!(at("chosen").is_some_and(|x| x >= layout.legend_x), "{layout:?}");

        // one timing per configuration: no bar, and no caption for bars
        let single: Vec<Point> = pts.iter().map(|p| Point { spread: None, ..p.clone() }).collect();
        let (svg, layout) = super::svg(&single, &c).unwrap();
        assert_eq!(layout.bars, 0);
        assert!(!svg.contains("error bars"));
    }

    /// The PNG's text: a `.` sits in the middle of its cell, as far from the digit before
    /// it as from the one after. Drawn by plotters' own text drawing, which drops each
    /// glyph's left side bearing, the point hugged the `0` before it and left a gap a glyph
    /// wide after it: "0. 05".
    #[test]
    fn png_text_puts_a_point_midway_between_its_digits() {
        assert!(plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR).is_ok());
        let (w, h) = (120u32, 40u32);
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let root = Bitmap::new(BitMapBackend::with_buffer(&mut buf, (w, h)))
                .unwrap()
                .into_drawing_area();
            let style = TextStyle::from((FONT, 24).into_font()).pos(Pos::new(HPos::Left, VPos::Top));
            root.draw(&Text::new("0.05".to_string(), (4, 4), style)).unwrap();
            root.present().unwrap();
        }
        let inked = |x: u32| (0..h).any(|y| buf[((y * w + x) * 3) as usize] < 128);
        // the runs of inked columns: 0, ., 0, 5
        let mut runs: Vec<(u32, u32)> = Vec::new();
        for x in 0..w {
            match runs.last_mut() {
                Some(r) if inked(x) && r.1 + 1 == x => r.1 = x,
                _ if inked(x) => runs.push((x, x)),
                _ => {}
            }
        }
        assert_eq!(runs.len(), 4, "{runs:?}");
        let (before, after) = (runs[1].0 - runs[0].1, runs[2].0 - runs[1].1);
        assert!(
            before.abs_diff(after) <= 2,
            "the point {before} px after the 0 and {after} px before the next: {runs:?}"
        );
    }
}
