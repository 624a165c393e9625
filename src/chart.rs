//! Charts for people: PNG line and scatter charts with numbered axes, axis labels, a title
//! and a legend, drawn by `plotters` into memory and written atomically through
//! [`crate::reference::write_png`].
//!
//! Text is set in DejaVu Sans, embedded in the library (`assets/DejaVuSans.ttf`, licence in
//! `assets/LICENSE-DejaVu.txt`), so charts look the same on every machine and need no
//! system fonts. Colours follow the Okabe-Ito palette, which stays distinct for readers with
//! colour-blindness.
//!
//! ```no_run
//! use rendernet::chart::{Options, line_chart};
//! let loss = vec![(0.0, 1.0), (100.0, 0.3), (200.0, 0.1)];
//! line_chart("loss.png".as_ref(), "Training loss", "step", "loss", &[("mean of 100 steps", loss)], &Options { log_y: true, ..Options::default() })?;
//! # Ok::<(), rendernet::Error>(())
//! ```

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;
use std::path::Path;

const FONT_BYTES: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const SANS: &str = "sans-serif";

/// Okabe-Ito colours (black and yellow left out: black is the axes' colour, yellow is
/// unreadable on white), in the order series get them.
/// Okabe-Ito, colour-blind safe (its yellow darkened to read on white).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(190, 175, 20),
];
const GRID: RGBColor = RGBColor(228, 228, 228);

/// The colour of the `i`-th series (cycling through eight).
pub fn colour(i: usize) -> [u8; 3] {
    let RGBColor(r, g, b) = PALETTE[i % PALETTE.len()];
    [r, g, b]
}

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if plotters::style::register_font(SANS, FontStyle::Normal, FONT_BYTES).is_err() {
            panic!("the embedded DejaVu Sans does not parse");
        }
    });
}

/// Values drawn at a ceiling rather than at their height (e.g. a PSNR capped for identical
/// images, which would otherwise squash every other point into a line).
#[derive(Clone, Debug, PartialEq)]
pub struct Cap {
    /// Values at or above this are drawn as triangles on the top edge of the plot.
    pub at: f64,
    /// The legend's explanation of those triangles.
    pub note: String,
}

/// How a chart is drawn besides its data. `Options::default()`: 800x480, linear axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Image size in pixels, width and height.
    pub size: (u32, u32),
    /// A base-10 logarithmic y axis; points with y <= 0 are left out.
    pub log_y: bool,
    /// A categorical x axis: x = 0, 1, ... are labelled with these names instead of
    /// numbers (use x values 0..n). Empty: a numeric x axis.
    pub x_categories: Vec<String>,
    /// Values at or above a ceiling drawn on the top edge.
    pub cap: Option<Cap>,
    /// Draw a marker at every point of a line (for sparse data such as sweep levels).
    pub markers: bool,
    /// The x axis' extent (e.g. the same for stacked panels, so they line up); `None` fits
    /// the data. Ignored on a categorical axis.
    pub x_range: Option<(f64, f64)>,
    /// The y axis' extent for values below the cap (e.g. the same for a set of charts, so
    /// they compare at a glance); `None` fits the data.
    pub y_range: Option<(f64, f64)>,
}

impl Default for Options {
    fn default() -> Self {
        Options { size: (800, 480), log_y: false, x_categories: Vec::new(), cap: None, markers: false, x_range: None, y_range: None }
    }
}

/// One chart of a [`line_panels`] image.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis (say what and in which unit).
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Named lines of (x, y) points; a series named "" gets no legend entry.
    pub series: Vec<(String, Vec<(f64, f64)>)>,
    /// Size (this panel's share of the image) and axes.
    pub options: Options,
}

/// Writes `path` (PNG, `options.size`): one line per series, in distinct colours, against
/// numbered x and y axes labelled `x_label` and `y_label`, under `title`, with a legend of
/// the series' names where it hides the fewest points. Non-finite points are left out.
pub fn line_chart<S: AsRef<str>>(path: &Path, title: &str, x_label: &str, y_label: &str, series: &[(S, Vec<(f64, f64)>)], options: &Options) -> Result<()> {
    let layers = series.iter().map(|(n, p)| Layer { name: n.as_ref(), points: p.iter().map(|&(x, y)| (x, y, "")).collect(), line: true }).collect();
    write(path, options.size, |area| draw_panel(area, &PanelRef { title, x_label, y_label, layers, options }))
}

/// Writes `path`: the panels stacked top to bottom, each as [`line_chart`] draws it at its
/// `options.size`; the image is as wide as the widest panel and as tall as all together.
pub fn line_panels(path: &Path, panels: &[Panel]) -> Result<()> {
    let refs: Vec<PanelRef> = panels
        .iter()
        .map(|p| {
            let layers = p.series.iter().map(|(n, pts)| Layer { name: n, points: pts.iter().map(|&(x, y)| (x, y, "")).collect(), line: true }).collect();
            PanelRef { title: &p.title, x_label: &p.x_label, y_label: &p.y_label, layers, options: &p.options }
        })
        .collect();
    draw_grid(path, &refs, 1)
}

/// One chart of a [`scatter_panels`] image: groups of labelled points, as [`scatter_chart`].
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterPanel {
    /// Title above the plot.
    pub title: String,
    /// Label of the x axis (say what and in which unit).
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Named groups (a colour and legend entry each) of (x, y, point label).
    pub groups: Vec<(String, Vec<(f64, f64, String)>)>,
    /// Size (this panel's share of the image) and axes.
    pub options: Options,
}

/// Writes `path`: scatter panels in rows of `columns`, each drawn as [`scatter_chart`] draws
/// it in a cell as large as the largest panel's `options.size`.
pub fn scatter_panels(path: &Path, panels: &[ScatterPanel], columns: usize) -> Result<()> {
    let refs: Vec<PanelRef> = panels
        .iter()
        .map(|p| {
            let layers = p.groups.iter().map(|(n, pts)| Layer { name: n, points: pts.iter().map(|(x, y, l)| (*x, *y, l.as_str())).collect(), line: false }).collect();
            PanelRef { title: &p.title, x_label: &p.x_label, y_label: &p.y_label, layers, options: &p.options }
        })
        .collect();
    draw_grid(path, &refs, columns)
}

/// Draws panels into a grid of `columns` columns, each cell as large as the largest panel.
fn draw_grid(path: &Path, panels: &[PanelRef], columns: usize) -> Result<()> {
    let columns = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(columns).max(1);
    let cw = panels.iter().map(|p| p.options.size.0).max().unwrap_or(200);
    let ch = panels.iter().map(|p| p.options.size.1).max().unwrap_or(150);
    write(path, (cw * columns as u32, ch * rows as u32), |root| {
        for (cell, p) in root.split_evenly((rows, columns)).iter().zip(panels) {
            draw_panel(cell, p)?;
        }
        Ok(())
    })
}

/// Writes `path` (PNG, `options.size`): groups of labelled points, a colour and a legend
/// entry per group, each point's label beside it (e.g. speed against accuracy, one point
/// per model). `options.markers` is implied; lines are not drawn.
pub fn scatter_chart<S: AsRef<str>, L: AsRef<str>>(path: &Path, title: &str, x_label: &str, y_label: &str, groups: &[(S, Vec<(f64, f64, L)>)], options: &Options) -> Result<()> {
    let layers = groups.iter().map(|(n, p)| Layer { name: n.as_ref(), points: p.iter().map(|(x, y, l)| (*x, *y, l.as_ref())).collect(), line: false }).collect();
    write(path, options.size, |area| draw_panel(area, &PanelRef { title, x_label, y_label, layers, options }))
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type DrawResult = std::result::Result<(), DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

/// Draws into an in-memory RGB buffer of `size` with `body`, then writes it as a PNG.
fn write(path: &Path, (w, h): (u32, u32), body: impl FnOnce(&Area) -> DrawResult) -> Result<()> {
    register_font();
    let failed = |e: String| Error::Invalid(format!("{}: drawing the chart failed: {e}", path.display()));
    if w < 200 || h < 150 || w > 8192 || h > 8192 {
        return Err(failed(format!("size {w}x{h} is outside 200x150..=8192x8192")));
    }
    let mut buf = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| failed(e.to_string()))?;
        body(&root).map_err(|e| failed(e.to_string()))?;
        root.present().map_err(|e| failed(e.to_string()))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf).expect("buffer sized w*h*3");
    crate::reference::write_png(&image::DynamicImage::ImageRgb8(img), path)
}

/// One series as drawn: points with optional labels, joined by a line or not.
struct Layer<'a> {
    name: &'a str,
    points: Vec<(f64, f64, &'a str)>,
    line: bool,
}

struct PanelRef<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    layers: Vec<Layer<'a>>,
    options: &'a Options,
}

/// A short number: no trailing zeros, no float noise, exponents only when very large or small.
pub fn format_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { v.to_string() };
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        let s = format!("{v:.1e}");
        return s.replace(".0e", "e");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.to_string() }
}

/// The data's (or `options.y_range`'s) y extent in the axis' space (log10 for log axes),
/// padded; with capped points a band on top holds them: `(lo, hi, Some((band start, top)))`.
fn y_extent(p: &PanelRef) -> (f64, f64, Option<(f64, f64)>) {
    let o = p.options;
    let to_axis = |y: f64| if o.log_y { y.log10() } else { y };
    let capped = |y: f64| o.cap.as_ref().is_some_and(|c| y >= c.at);
    let usable = |y: f64| y.is_finite() && (!o.log_y || y > 0.0);
    let ys: Vec<f64> = p.layers.iter().flat_map(|l| &l.points).map(|q| q.1).filter(|&y| usable(y) && !capped(y)).map(to_axis).collect();
    let any_capped = p.layers.iter().flat_map(|l| &l.points).any(|q| q.1.is_finite() && capped(q.1));
    let (mut lo, mut hi) = ys.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| (a.min(y), b.max(y)));
    if let Some((a, b)) = o.y_range.filter(|&(a, b)| a < b && usable(a) && usable(b)) {
        (lo, hi) = (to_axis(a), to_axis(b));
    } else if lo > hi {
        (lo, hi) = if o.log_y { (-1.0, 1.0) } else { (0.0, 1.0) };
    }
    if hi - lo < 1e-9 {
        let d = if o.log_y { 0.5 } else { (0.1 * lo.abs()).max(1e-3) };
        (lo, hi) = (lo - d, hi + d);
    }
    let pad = if o.y_range.is_some() { 0.0 } else { 0.06 * (hi - lo) };
    let (lo, hi) = (lo - pad, hi + pad);
    if any_capped {
        let top = hi + 0.1 * (hi - lo);
        (lo, top, Some((hi, top)))
    } else {
        (lo, hi, None)
    }
}

fn x_extent(p: &PanelRef) -> Range<f64> {
    let n = p.options.x_categories.len();
    if n > 0 {
        return -0.5..n as f64 - 0.5;
    }
    if let Some((lo, hi)) = p.options.x_range.filter(|(lo, hi)| lo < hi) {
        return lo..hi;
    }
    let (lo, hi) = p.layers.iter().flat_map(|l| &l.points).map(|q| q.0).filter(|x| x.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if lo > hi {
        return 0.0..1.0;
    }
    let d = if hi - lo < 1e-9 { (0.1 * lo.abs()).max(1.0) } else { 0.03 * (hi - lo) };
    lo - d..hi + d
}

/// Where the legend box (`box_frac`: its width and height as fractions of the plot) covers
/// the fewest points and line stretches: a corner when one is as empty as anywhere, else
/// the middle of a side or of the plot.
fn emptiest_place(p: &PanelRef, x: &Range<f64>, (ylo, yhi): (f64, f64), to_axis: impl Fn(f64) -> f64, (bw, bh): (f64, f64)) -> SeriesLabelPosition {
    use SeriesLabelPosition::*;
    let (bw, bh) = (bw.min(1.0), bh.min(1.0));
    // (position, u range, v range), corners first so they win ties.
    let (l, c, r) = ((0.0, bw), (0.5 - bw / 2.0, 0.5 + bw / 2.0), (1.0 - bw, 1.0));
    let (lo, mid, up) = ((0.0, bh), (0.5 - bh / 2.0, 0.5 + bh / 2.0), (1.0 - bh, 1.0));
    let places = [
        (UpperRight, r, up),
        (UpperLeft, l, up),
        (LowerRight, r, lo),
        (LowerLeft, l, lo),
        (MiddleRight, r, mid),
        (MiddleLeft, l, mid),
        (UpperMiddle, c, up),
        (LowerMiddle, c, lo),
        (MiddleMiddle, c, mid),
    ];
    let mut count = [0usize; 9];
    for layer in &p.layers {
        // Lines cover the stretch between points too: sample each segment.
        let pts: Vec<(f64, f64)> = layer.points.iter().map(|q| ((q.0 - x.start) / (x.end - x.start), (to_axis(q.1).min(yhi) - ylo) / (yhi - ylo))).filter(|(u, v)| u.is_finite() && v.is_finite()).collect();
        let mut samples = pts.clone();
        if layer.line {
            for w in pts.windows(2) {
                samples.extend((1..16).map(|k| k as f64 / 16.0).map(|t| (w[0].0 + t * (w[1].0 - w[0].0), w[0].1 + t * (w[1].1 - w[0].1))));
            }
        }
        for (u, v) in samples {
            for (i, (_, (u0, u1), (v0, v1))) in places.iter().enumerate() {
                // A little slack: markers and line width reach beyond the point.
                count[i] += usize::from(u >= u0 - 0.02 && u <= u1 + 0.02 && v >= v0 - 0.03 && v <= v1 + 0.03);
            }
        }
    }
    let best = (0..places.len()).min_by_key(|&i| count[i]).unwrap_or(0);
    places.into_iter().nth(best).map(|p| p.0).unwrap_or(UpperRight)
}

/// Tick values 1-2-5 (or denser when the range spans less than a decade) per decade inside
/// `lo..=hi`; `None` when fewer than two fit (then plotters chooses).
fn log_ticks(lo: f64, hi: f64) -> Option<Vec<f64>> {
    let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let within = |ms: &[f64], every: i32| -> Vec<f64> {
        (d0..=d1).filter(|d| d.rem_euclid(every) == 0).flat_map(|d| ms.iter().map(move |m| m * 10f64.powi(d))).filter(|t| (lo..=hi).contains(t)).collect()
    };
    let decades = d1 - d0;
    let v = if decades > 8 {
        within(&[1.0], (decades + 7) / 8)
    } else if decades > 3 {
        within(&[1.0], 1)
    } else {
        let mut v = within(&[1.0, 2.0, 5.0], 1);
        if v.len() < 4 {
            v = within(&[1.0, 2.0, 3.0, 5.0], 1);
        }
        if v.len() < 4 {
            v = within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0], 1);
        }
        v
    };
    (v.len() >= 2).then_some(v)
}

fn draw_panel(area: &Area, p: &PanelRef) -> DrawResult {
    let (lo, hi, band) = y_extent(p);
    let axis = (lo, hi);
    if p.options.log_y {
        let (lo, hi) = (10f64.powf(lo), 10f64.powf(hi));
        let band = band.map(|(a, b)| (10f64.powf(a), 10f64.powf(b)));
        match log_ticks(lo, hi) {
            Some(t) => draw_with(area, p, (lo..hi).log_scale().with_key_points(t), band, |y| y.log10(), axis),
            None => draw_with(area, p, (lo..hi).log_scale(), band, |y| y.log10(), axis),
        }
    } else {
        draw_with(area, p, lo..hi, band, |y| y, axis)
    }
}

/// Draws one panel; `band`: the (start, top) of the band for capped values, in data units.
fn draw_with<Y>(area: &Area, p: &PanelRef, y_spec: Y, band: Option<(f64, f64)>, to_axis: impl Fn(f64) -> f64, y_axis: (f64, f64)) -> DrawResult
where
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let o = p.options;
    let x = x_extent(p);
    let cats = &o.x_categories;
    let longest_label = cats.iter().map(|c| c.chars().count()).max().unwrap_or(0);
    // Category names that would overlap side by side (about 7 px a character) stand upright.
    let upright = cats.iter().map(|c| c.chars().count() + 2).sum::<usize>() * 7 > area.dim_in_pixel().0 as usize - 110;
    let label_area = if upright { 36 + 7 * longest_label as u32 } else { 52 };
    let mut chart = ChartBuilder::on(area)
        .caption(p.title, (SANS, 20))
        .margin_top(8)
        .margin_left(10)
        .margin_right(24)
        .margin_bottom(6)
        .x_label_area_size(label_area)
        .y_label_area_size(76)
        .build_cartesian_2d(x.clone(), y_spec)?;
    let x_fmt = |v: &f64| {
        if cats.is_empty() {
            return format_number(*v);
        }
        let i = v.round();
        if (v - i).abs() > 1e-6 || i < 0.0 {
            return String::new();
        }
        let c = cats.get(i as usize).cloned().unwrap_or_default();
        // Upright labels are centred on their tick: leading spaces (narrower than letters,
        // hence twice as many) push the name below the axis.
        if upright { format!("{}{c}", " ".repeat(2 * c.chars().count() + 2)) } else { c }
    };
    // No numbers in the band of capped values: nothing there has its height.
    let y_fmt = |v: &f64| if band.is_some_and(|(b, _)| *v > b) { String::new() } else { format_number(*v) };
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(p.x_label)
        .y_desc(p.y_label)
        .axis_desc_style((SANS, 16))
        .label_style((SANS, if longest_label > 12 { 13 } else { 14 }))
        .bold_line_style(GRID)
        .max_light_lines(0)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_labels(8);
    if cats.is_empty() {
        mesh.x_labels(10);
    } else {
        mesh.x_labels(cats.len());
    }
    let rotated = (SANS, 12).into_font().transform(FontTransform::Rotate90);
    if upright {
        mesh.x_label_style(rotated);
    }
    mesh.draw()?;
    let top = band.map(|b| b.1);
    if let (Some((start, top)), Some(cap)) = (band, &o.cap) {
        // A dashed line under the band, and the cap's value where its tick number would be.
        let grey = RGBColor(150, 150, 150);
        chart.draw_series(DashedLineSeries::new([(x.start, start), (x.end, start)], 6, 4, grey.into()))?;
        let (px, py) = chart.backend_coord(&(x.start, top));
        let (bx, by) = area.get_base_pixel();
        let style = TextStyle::from((SANS, 14).into_font()).color(&BLACK).pos(Pos::new(HPos::Right, VPos::Center));
        area.draw_text(&format!("≥{}", format_number(cap.at)), &style, (px - bx - 8, py - by))?;
    }

    let cap_at = o.cap.as_ref().map(|c| c.at);
    let is_capped = |y: f64| cap_at.is_some_and(|c| y >= c);
    let usable = |(x, y): (f64, f64)| x.is_finite() && y.is_finite() && (!o.log_y || y > 0.0 || is_capped(y));
    let (mut legend, mut longest_name) = (0usize, 0usize);
    for (i, l) in p.layers.iter().enumerate() {
        let c = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = l.points.iter().map(|q| (q.0, q.1)).filter(|&q| usable(q)).map(|(x, y)| (x, if is_capped(y) { top.unwrap_or(y) } else { y })).collect();
        let raw: Vec<f64> = l.points.iter().map(|q| (q.0, q.1)).filter(|&q| usable(q)).map(|q| q.1).collect();
        let style = ShapeStyle::from(c).stroke_width(2);
        let anno = if l.line {
            chart.draw_series(LineSeries::new(pts.clone(), style))?
        } else {
            chart.draw_series(std::iter::empty::<Circle<(f64, f64), u32>>())?
        };
        if !l.name.is_empty() && !pts.is_empty() {
            legend += 1;
            longest_name = longest_name.max(l.name.chars().count());
            // Lines: a stroke with a dot; points: a bigger dot (the path shrinks to under it).
            let (path, r) = if l.line { (vec![(-2, 0), (22, 0)], 4) } else { (vec![(10, 0), (10, 0)], 5) };
            anno.label(l.name).legend(move |(px, py)| EmptyElement::at((px, py)) + PathElement::new(path.clone(), style) + Circle::new((10, 0), r, c.filled()));
        }
        let marker = o.markers || !l.line;
        chart.draw_series(pts.iter().zip(&raw).filter(|(_, y)| marker && !is_capped(**y)).map(|(&q, _)| Circle::new(q, if l.line { 4 } else { 5 }, c.filled())))?;
        chart.draw_series(pts.iter().zip(&raw).filter(|(_, y)| is_capped(**y)).map(|(&q, _)| TriangleMarker::new(q, 7, c.filled())))?;
        let labelled = l.points.iter().filter(|q| !q.2.is_empty() && usable((q.0, q.1)));
        chart.draw_series(labelled.map(|q| {
            let y = if is_capped(q.1) { top.unwrap_or(q.1) } else { q.1 };
            // Right of the point, or left of it in the right fifth so it stays inside.
            let right = (q.0 - x.start) / (x.end - x.start) > 0.8;
            let dx = if right { -7 - 7 * q.2.chars().count() as i32 } else { 7 };
            EmptyElement::at((q.0, y)) + Text::new(q.2.to_string(), (dx, -18), (SANS, 13).into_font().color(&BLACK))
        }))?;
    }
    if let Some(cap) = &o.cap {
        if p.layers.iter().flat_map(|l| &l.points).any(|q| q.1.is_finite() && is_capped(q.1)) {
            legend += 1;
            longest_name = longest_name.max(cap.note.chars().count());
            let grey = RGBColor(90, 90, 90);
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), u32>>())?
                .label(cap.note.as_str())
                .legend(move |(px, py)| TriangleMarker::new((px + 10, py), 7, grey.filled()));
        }
    }
    let plotted = p.layers.iter().flat_map(|l| &l.points).any(|q| usable((q.0, q.1)));
    if !plotted {
        let (w, h) = chart.plotting_area().dim_in_pixel();
        let style = TextStyle::from((SANS, 18).into_font()).color(&RGBColor(110, 110, 110)).pos(Pos::new(HPos::Center, VPos::Center));
        chart.plotting_area().strip_coord_spec().draw_text("no data yet", &style, (w as i32 / 2, h as i32 / 2))?;
    }
    if legend > 0 {
        // The legend box in pixels (14 px text, about 8 px a character, a 30 px sample, 20
        // px a row) as fractions of the plot, to find the corner it hides least in.
        let (w, h) = chart.plotting_area().dim_in_pixel();
        let frac = ((longest_name * 8 + 60) as f64 / w.max(1) as f64, (legend * 20 + 20) as f64 / h.max(1) as f64);
        let corner = emptiest_place(p, &x, y_axis, &to_axis, frac);
        chart
            .configure_series_labels()
            .position(corner)
            .margin(10)
            .legend_area_size(30)
            .label_font((SANS, 14))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("rendernet-chart-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Pixels darker than 100 in every channel (text and axes are black; no palette colour is
    /// that dark) in the box `x0..x1, y0..y1`.
    fn dark(img: &image::RgbImage, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> usize {
        (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y))).filter(|&(x, y)| img.get_pixel(x, y).0.iter().all(|&c| c < 100)).count()
    }

    #[test]
    fn line_chart_has_numbers_and_labels_on_both_axes_and_coloured_lines() {
        let dir = scratch("line");
        let path = dir.join("c.png");
        let a: Vec<(f64, f64)> = (0..20).map(|i| (i as f64 * 100.0, 30.0 - i as f64)).collect();
        let b: Vec<(f64, f64)> = (0..20).map(|i| (i as f64 * 100.0, 12.0 + 0.5 * i as f64)).collect();
        let o = Options { size: (640, 400), markers: true, ..Options::default() };
        line_chart(&path, "Two lines", "step", "PSNR (dB)", &[("falling", a), ("rising", b)], &o).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 400));
        let (w, h) = img.dimensions();
        // Series colours present (Okabe-Ito blue and vermillion).
        for c in [colour(0), colour(1)] {
            assert!(img.pixels().filter(|p| p.0 == c).count() > 200, "colour {c:?} barely drawn");
        }
        // Left strip: y tick numbers and the rotated y label; bottom strip: x numbers and label;
        // top strip: the title. A chart without them has only the axis line there.
        // Left of the plot (x < 86): the rotated y label at x 8..20, tick numbers at 60..76;
        // below it (y > h - 58): tick numbers in the first 22 rows, then the x label.
        // A chart without numbers or labels has nothing dark there but the axis lines.
        let y_label = dark(&img, (0, 40), (40, h - 60));
        let y_numbers = dark(&img, (40, 80), (20, h - 60));
        let x_numbers = dark(&img, (90, w), (h - 54, h - 32));
        let x_label = dark(&img, (90, w), (h - 30, h));
        let title = dark(&img, (90, w), (0, 28));
        for (what, n, min) in [("y axis label", y_label, 120), ("y axis numbers", y_numbers, 150), ("x axis numbers", x_numbers, 150), ("x axis label", x_label, 40), ("title", title, 100)] {
            assert!(n >= min, "{what} missing: {n} dark pixels where {min} were expected");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn log_axes_panels_caps_categories_and_scatter_draw() {
        let dir = scratch("kinds");
        let loss: Vec<(f64, f64)> = (1..50).map(|i| (i as f64 * 100.0, 1.0 / i as f64)).collect();
        let psnr: Vec<(f64, f64)> = (1..6).map(|i| (i as f64 * 1000.0, 20.0 + i as f64)).collect();
        let panel = |t: &str, s: Vec<(f64, f64)>, log_y| Panel {
            title: t.into(),
            x_label: "step".into(),
            y_label: "v".into(),
            series: vec![(t.into(), s)],
            options: Options { size: (640, 300), log_y, ..Options::default() },
        };
        let p = dir.join("panels.png");
        line_panels(&p, &[panel("loss", loss, true), panel("psnr", psnr, false)]).unwrap();
        assert_eq!(image::open(&p).unwrap().to_rgb8().dimensions(), (640, 600));

        let o = Options {
            x_categories: vec!["a".into(), "b".into(), "c".into()],
            cap: Some(Cap { at: 99.0, note: "identical".into() }),
            markers: true,
            ..Options::default()
        };
        let c = dir.join("cats.png");
        line_chart(&c, "cats", "case", "dB", &[("x", vec![(0.0, 99.0), (1.0, 25.0), (2.0, 20.0)])], &o).unwrap();
        let s = dir.join("scatter.png");
        scatter_chart(&s, "frontier", "ms", "dB", &[("tiny", vec![(3.0, 28.0, "tiny")]), ("base", vec![(9.0, 30.0, "base")])], &Options::default()).unwrap();
        assert!(image::open(&s).is_ok());
        assert!(line_chart(&dir.join("x.jpg"), "t", "x", "y", &[("a", vec![(0.0, 1.0)])], &Options::default()).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(format_number(0.30000000000000004), "0.3");
        assert_eq!(format_number(20000.0), "20000");
        assert_eq!(format_number(-6.0), "-6");
        assert_eq!(format_number(0.0001), "1e-4");
        assert_eq!(format_number(0.25), "0.25");
    }
}
