//! Paper-style plots (after the paper's Fig. 10 ff.) regenerated from a simulator trace CSV.
//!
//! The trace has one row per frame and (at least) the columns
//! `t`, `x_mm`, `y_mm`, `z_mm`, `e1`, `e2`, `e3` (true pose of the target in the right camera
//! frame), `est_x_mm`, `est_y_mm`, `est_z_mm`, `est_e1`, `est_e2`, `est_e3` (the estimate) and
//! `F` (fitness); other columns (`q1..q7`, `qd1..qd7`, …) are ignored. Empty or `NaN` cells
//! are gaps (e.g. frames without an estimate).
//!
//! [`plot_trace`] writes three PNGs: `position.png` and `orientation.png` (three stacked
//! panels each: ground truth as a line, the estimate as points on a thin line) and
//! `fitness.png`. Text is drawn with the DejaVu Sans font embedded from the `dejavu` crate,
//! so no system font or fontconfig is needed.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use anyhow::{Context, anyhow, bail};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// Size (pixels) of `position.png` and `orientation.png`: three stacked panels.
pub const PANEL_PLOT_SIZE: (u32, u32) = (1000, 900);
/// Size (pixels) of `fitness.png`.
pub const FITNESS_PLOT_SIZE: (u32, u32) = (1000, 380);

/// Font family name under which the embedded font is registered with plotters.
pub(crate) const FONT: &str = "sans-serif";

/// Registers the embedded DejaVu Sans with plotters once per process.
pub(crate) fn ensure_font() -> anyhow::Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        let normal = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok();
        let bold = plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok();
        normal && bold
    });
    if ok { Ok(()) } else { Err(anyhow!("the embedded DejaVu Sans font could not be loaded")) }
}

/// The columns of a trace that the plots use, one `Vec` per column.
#[derive(Debug, Clone, Default)]
struct Trace {
    columns: HashMap<&'static str, Vec<f64>>,
    /// The optional `status` column (tracker status per frame), empty when absent.
    status: Vec<String>,
}

/// Columns read from the trace.
const COLUMNS: [&str; 14] = [
    "t", "x_mm", "y_mm", "z_mm", "e1", "e2", "e3", "est_x_mm", "est_y_mm", "est_z_mm", "est_e1", "est_e2", "est_e3",
    "F",
];

impl Trace {
    fn read(path: &Path) -> anyhow::Result<Self> {
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_path(path)
            .with_context(|| format!("cannot open trace {}", path.display()))?;
        let headers = reader.headers().with_context(|| format!("no header in {}", path.display()))?.clone();
        let mut index = Vec::with_capacity(COLUMNS.len());
        for name in COLUMNS {
            let i = headers
                .iter()
                .position(|h| h == name)
                .ok_or_else(|| anyhow!("trace {} has no column `{name}`", path.display()))?;
            index.push((name, i));
        }
        let mut columns: HashMap<&'static str, Vec<f64>> = COLUMNS.iter().map(|&n| (n, Vec::new())).collect();
        let status_index = headers.iter().position(|h| h == "status");
        let mut status = Vec::new();
        for (row, record) in reader.records().enumerate() {
            let record = record.with_context(|| format!("{}: bad CSV record {}", path.display(), row + 1))?;
            if let Some(i) = status_index {
                status.push(record.get(i).unwrap_or("").to_owned());
            }
            for &(name, i) in &index {
                let cell = record.get(i).unwrap_or("");
                let value = if cell.is_empty() {
                    f64::NAN
                } else {
                    cell.parse::<f64>()
                        .with_context(|| format!("{}: row {}, column `{name}`: `{cell}`", path.display(), row + 1))?
                };
                columns.entry(name).or_default().push(value);
            }
        }
        Ok(Self { columns, status })
    }

    fn column(&self, name: &str) -> &[f64] {
        self.columns.get(name).map_or(&[], Vec::as_slice)
    }

    /// `(t, value)` pairs of a column with finite entries only.
    fn series(&self, name: &str) -> Vec<(f64, f64)> {
        self.column("t")
            .iter()
            .zip(self.column(name))
            .filter(|(t, v)| t.is_finite() && v.is_finite())
            .map(|(&t, &v)| (t, v))
            .collect()
    }
}

/// `[lo, hi]` of the finite values, padded by 5 % (at least `min_span` wide).
fn padded_range<'a>(values: impl Iterator<Item = &'a f64>, min_span: f64) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return (-min_span / 2.0, min_span / 2.0);
    }
    let pad = ((hi - lo) * 0.05).max(min_span / 2.0 - (hi - lo) / 2.0).max(0.0);
    (lo - pad, hi + pad)
}

/// Tick labels with as many decimals as the axis span `lo..hi` needs (and no `-0`).
fn tick_formatter(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let span = (hi - lo).abs().max(1e-12);
    let decimals = (2.0 - span.log10().floor()).clamp(0.0, 9.0) as usize;
    move |v: &f64| {
        let v = if v.abs() < span * 1e-9 { 0.0 } else { *v };
        format!("{v:.decimals$}")
    }
}

pub(crate) fn draw_err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e}")
}

/// One panel: ground truth `truth` as a line, estimate `est` as points on a thin line.
fn draw_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    trace: &Trace,
    truth: &str,
    est: &str,
    y_desc: &str,
    colour: RGBColor,
    min_span: f64,
) -> anyhow::Result<()> {
    let truth_pts = trace.series(truth);
    let est_pts = trace.series(est);
    let (t0, t1) = padded_range(trace.column("t").iter(), 1e-3);
    let (y0, y1) = padded_range(truth_pts.iter().chain(&est_pts).map(|(_, v)| v), min_span);
    let mut chart = ChartBuilder::on(area)
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(75)
        .build_cartesian_2d(t0..t1, y0..y1)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(y_desc)
        .x_label_formatter(&tick_formatter(t0, t1))
        .y_label_formatter(&tick_formatter(y0, y1))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(draw_err)?;
    chart
        .draw_series(LineSeries::new(truth_pts, BLACK.stroke_width(2)))
        .map_err(draw_err)?
        .label("true")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    chart.draw_series(LineSeries::new(est_pts.iter().copied(), colour.stroke_width(1))).map_err(draw_err)?;
    chart
        .draw_series(est_pts.iter().map(|&p| Circle::new(p, 2, colour.filled())))
        .map_err(draw_err)?
        .label("estimate")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, colour.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)?;
    Ok(())
}

/// Renders into an RGB buffer with `draw` and saves it as a PNG.
pub(crate) fn render_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut buf = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        draw(&root)?;
        root.present().map_err(draw_err)?;
    }
    let img = image::RgbImage::from_raw(size.0, size.1, buf).ok_or_else(|| anyhow!("bad plot buffer size"))?;
    crate::output::io::write_png(path, &img)
}

/// Three stacked panels of `(truth, estimate, y description)` with a title.
fn three_panels(
    path: &Path,
    trace: &Trace,
    title: &str,
    panels: [(&str, &str, &str); 3],
    min_span: f64,
) -> anyhow::Result<()> {
    let colours = [RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(31, 119, 180)];
    render_png(path, PANEL_PLOT_SIZE, |root| {
        let body = root.titled(title, (FONT, 24)).map_err(draw_err)?;
        for ((area, (truth, est, desc)), colour) in body.split_evenly((3, 1)).iter().zip(panels).zip(colours) {
            draw_panel(area, trace, truth, est, desc, colour, min_span)?;
        }
        Ok(())
    })
}

/// Reads a simulator trace (`trace.csv`, see the module docs) and writes `position.png`,
/// `orientation.png` and `fitness.png` into `out_dir` (created if missing), titled `title`.
/// Returns the paths written, in that order.
///
/// # Errors
/// The CSV cannot be read, lacks a column or holds a non-numeric cell; a plot cannot be drawn
/// or written.
pub fn plot_trace(csv_path: &Path, out_dir: &Path, title: &str) -> anyhow::Result<Vec<PathBuf>> {
    ensure_font()?;
    let trace = Trace::read(csv_path)?;
    if trace.column("t").is_empty() {
        bail!("trace {} has no rows", csv_path.display());
    }
    std::fs::create_dir_all(out_dir).with_context(|| format!("cannot create {}", out_dir.display()))?;

    let position = out_dir.join("position.png");
    three_panels(
        &position,
        &trace,
        &format!("{title}: position"),
        [("x_mm", "est_x_mm", "x [mm]"), ("y_mm", "est_y_mm", "y [mm]"), ("z_mm", "est_z_mm", "z [mm]")],
        2.0,
    )?;

    let orientation = out_dir.join("orientation.png");
    three_panels(
        &orientation,
        &trace,
        &format!("{title}: orientation"),
        [("e1", "est_e1", "ε1 [–]"), ("e2", "est_e2", "ε2 [–]"), ("e3", "est_e3", "ε3 [–]")],
        0.02,
    )?;

    let fitness = out_dir.join("fitness.png");
    fitness_plot(&fitness, &trace, title)?;

    Ok(vec![position, orientation, fitness])
}

/// `fitness.png`: F over time, with the tracker's status as a coloured strip along the bottom.
fn fitness_plot(fitness: &Path, trace: &Trace, title: &str) -> anyhow::Result<()> {
    render_png(fitness, FITNESS_PLOT_SIZE, |root| {
        let body = root.titled(&format!("{title}: fitness"), (FONT, 24)).map_err(draw_err)?;
        let pts = trace.series("F");
        let (t0, t1) = padded_range(trace.column("t").iter(), 1e-3);
        let (f0, f1) = padded_range(pts.iter().map(|(_, f)| f).chain([0.0, 1.0].iter()), 0.1);
        let mut chart = ChartBuilder::on(&body)
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(75)
            .build_cartesian_2d(t0..t1, f0..f1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .x_desc("t [s]")
            .y_desc("F [–]")
            .x_label_formatter(&tick_formatter(t0, t1))
            .y_label_formatter(&tick_formatter(f0, f1))
            .label_style((FONT, 15))
            .axis_desc_style((FONT, 17))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(draw_err)?;
        let blue = RGBColor(31, 119, 180);
        chart.draw_series(LineSeries::new(pts.iter().copied(), blue.stroke_width(1))).map_err(draw_err)?;
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 2, blue.filled()))).map_err(draw_err)?;
        // The tracker's status as a coloured strip along the bottom.
        let y = f0 + 0.03 * (f1 - f0);
        for (name, colour) in [
            ("searching", RGBColor(150, 150, 150)),
            ("tracking", RGBColor(44, 160, 44)),
            ("lost", RGBColor(214, 39, 40)),
            ("uncertain", RGBColor(255, 127, 14)),
        ] {
            let marks: Vec<(f64, f64)> = trace
                .column("t")
                .iter()
                .zip(&trace.status)
                .filter(|(_, s)| s.as_str() == name)
                .map(|(t, _)| (*t, y))
                .collect();
            if marks.is_empty() {
                continue;
            }
            chart
                .draw_series(marks.iter().map(|&p| Rectangle::new([p, (p.0, p.1)], colour.stroke_width(6))))
                .map_err(draw_err)?
                .label(format!("status: {name}"))
                .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], colour.filled()));
        }
        if !trace.status.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .label_font((FONT, 14))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(draw_err)?;
        }
        Ok(())
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use std::fmt::Write as _;

    fn temp_dir(tag: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
        let dir = std::env::temp_dir().join(format!("evorec-plot-{tag}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn header() -> String {
        let mut cols = vec!["t".to_string()];
        cols.extend((1..=7).map(|i| format!("q{i}")));
        cols.extend((1..=7).map(|i| format!("qd{i}")));
        for c in ["x_mm", "y_mm", "z_mm", "e1", "e2", "e3"] {
            cols.push(c.into());
        }
        for c in ["est_x_mm", "est_y_mm", "est_z_mm", "est_e1", "est_e2", "est_e3", "F"] {
            cols.push(c.into());
        }
        cols.join(",")
    }

    fn synthetic_csv(dir: &Path) -> PathBuf {
        let mut s = header();
        s.push('\n');
        for i in 0..120 {
            let t = f64::from(i) * 0.033;
            let truth = [50.0 * t.sin(), -20.0 + 10.0 * t, 700.0 - 30.0 * t, 0.1 * t.cos(), 0.05, -0.02 * t];
            let err = 1.0 / (1.0 + f64::from(i));
            let mut row = format!("{t}");
            for j in 0..14 {
                write!(row, ",{}", 0.01 * f64::from(j) * t).unwrap();
            }
            for v in truth {
                write!(row, ",{v}").unwrap();
            }
            for (k, v) in truth.iter().enumerate() {
                if i == 3 {
                    row.push_str(",NaN"); // a frame without an estimate
                } else {
                    let scale = if k < 3 { 20.0 } else { 0.05 };
                    write!(row, ",{}", v + scale * err * (f64::from(i) * 1.7).sin()).unwrap();
                }
            }
            write!(row, ",{}", 1.0 - 0.8 * err).unwrap();
            s.push_str(&row);
            s.push('\n');
        }
        let path = dir.join("trace.csv");
        std::fs::write(&path, s).unwrap();
        path
    }

    #[test]
    fn plots_are_written_from_the_csv_alone() {
        let dir = temp_dir("ok");
        let csv = synthetic_csv(&dir);
        let out = dir.join("plots");
        let written = plot_trace(&csv, &out, "synthetic run").unwrap();
        let names: Vec<_> = written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["position.png", "orientation.png", "fitness.png"]);
        for (path, size) in written.iter().zip([PANEL_PLOT_SIZE, PANEL_PLOT_SIZE, FITNESS_PLOT_SIZE]) {
            assert!(path.is_file(), "{}", path.display());
            let img = image::open(path).unwrap().to_rgb8();
            assert_eq!(img.dimensions(), size);
            let first = *img.get_pixel(0, 0);
            assert!(img.pixels().any(|p| *p != first), "{} is blank", path.display());
            // Several colours: black text/axes, the coloured series, white.
            let mut colours: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
            colours.sort_unstable();
            colours.dedup();
            assert!(colours.len() > 10, "{}: {} colours", path.display(), colours.len());
            // Text was rendered: the title band (top 30 px) has dark pixels.
            let dark = (0..30).flat_map(|y| (0..size.0).map(move |x| (x, y))).filter(|&(x, y)| {
                let p = img.get_pixel(x, y).0;
                p.iter().all(|&c| c < 100)
            });
            assert!(dark.count() > 50, "{}: no title text", path.display());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_column_or_bad_cell_is_an_error() {
        let dir = temp_dir("bad");
        let csv = dir.join("trace.csv");
        std::fs::write(&csv, "t,x_mm\n0,1\n").unwrap();
        let err = plot_trace(&csv, &dir, "x").unwrap_err();
        assert!(format!("{err:#}").contains("no column"), "{err:#}");
        let mut s = header();
        s.push('\n');
        s.push_str(&vec!["1"; 28].join(","));
        s.push_str("\n0.1");
        s.push_str(&",oops".repeat(27));
        s.push('\n');
        std::fs::write(&csv, s).unwrap();
        let err = plot_trace(&csv, &dir, "x").unwrap_err();
        assert!(format!("{err:#}").contains("oops"), "{err:#}");
        assert!(plot_trace(&dir.join("missing.csv"), &dir, "x").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
