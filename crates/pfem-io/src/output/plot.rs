//! PNG plots of simulated time series against measured reference points.
//!
//! Drawn with `plotters`' bitmap backend and text rendered by `ab_glyph`
//! from the DejaVu Sans font shipped in `crates/pfem-io/assets/` (licence
//! beside it): no system font libraries are needed.

use std::borrow::Cow;
use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::{write_atomic, OutputError};

/// The font every plot uses, registered with plotters as `"sans-serif"`.
static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Series colours (Matplotlib's "tab10"), cycled.
const COLOURS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// How a series is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeriesStyle {
    /// A polyline through the points (simulation output).
    #[default]
    Line,
    /// One circle per point (measurements).
    Markers,
    /// Both.
    LineAndMarkers,
}

/// One curve of a [`PlotSpec`].
#[derive(Clone, Debug)]
pub struct PlotSeries<'a> {
    /// Legend entry.
    pub label: Cow<'a, str>,
    /// `(x, y)` points; non-finite points are skipped.
    pub points: &'a [(f64, f64)],
    /// Line or markers.
    pub style: SeriesStyle,
}

impl<'a> PlotSeries<'a> {
    /// A series drawn as a line.
    pub fn line(label: impl Into<Cow<'a, str>>, points: &'a [(f64, f64)]) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::Line,
        }
    }

    /// A series drawn as markers.
    pub fn markers(label: impl Into<Cow<'a, str>>, points: &'a [(f64, f64)]) -> Self {
        Self {
            label: label.into(),
            points,
            style: SeriesStyle::Markers,
        }
    }
}

/// A plot: title, axis labels, series, and the image size.
#[derive(Clone, Debug)]
pub struct PlotSpec<'a> {
    /// Caption above the plot (empty for none).
    pub title: Cow<'a, str>,
    /// Horizontal axis label.
    pub x_label: Cow<'a, str>,
    /// Vertical axis label.
    pub y_label: Cow<'a, str>,
    /// The curves, drawn in order, coloured in turn.
    pub series: Vec<PlotSeries<'a>>,
    /// Horizontal range; `None` fits all points with a 5 % margin.
    pub x_range: Option<(f64, f64)>,
    /// Vertical range; `None` fits all points with a 5 % margin.
    pub y_range: Option<(f64, f64)>,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
}

impl Default for PlotSpec<'_> {
    fn default() -> Self {
        Self {
            title: Cow::Borrowed(""),
            x_label: Cow::Borrowed("x"),
            y_label: Cow::Borrowed("y"),
            series: Vec::new(),
            x_range: None,
            y_range: None,
            width: 800,
            height: 600,
        }
    }
}

/// Draws `spec` and writes it to `path` as a PNG, atomically.
///
/// ```
/// use pfem_io::output::{parse_reference_csv, plot_series_png, reference, PlotSeries, PlotSpec};
///
/// let measured = parse_reference_csv(reference::MARTIN_MOYCE_N2_2_A2_25IN_FRONT).unwrap();
/// let simulated: Vec<(f64, f64)> = (0..50).map(|i| (0.15 * i as f64, 1.0 + 0.18 * (0.15 * i as f64).powf(1.6))).collect();
/// let spec = PlotSpec {
///     title: "Dam break, surge front".into(),
///     x_label: "T = t √(2g/a)".into(),
///     y_label: "Z = x/a".into(),
///     series: vec![
///         PlotSeries::line("pfem", &simulated),
///         PlotSeries::markers("Martin & Moyce 1952", &measured),
///     ],
///     ..Default::default()
/// };
/// let path = std::env::temp_dir().join(format!("pfem-doc-plot-{}.png", std::process::id()));
/// plot_series_png(&path, &spec)?;
/// # std::fs::remove_file(&path).ok();
/// # Ok::<(), pfem_io::output::OutputError>(())
/// ```
pub fn plot_series_png(path: impl AsRef<Path>, spec: &PlotSpec<'_>) -> Result<(), OutputError> {
    let path = path.as_ref();
    let fail = |reason: String| OutputError::Plot {
        path: path.to_path_buf(),
        reason,
    };
    if spec.width < 64 || spec.height < 64 || spec.width > 16384 || spec.height > 16384 {
        return Err(fail(format!(
            "image size {}×{} outside 64…16384 pixels",
            spec.width, spec.height
        )));
    }
    register_font().map_err(|()| fail("the shipped font could not be loaded".into()))?;
    let (w, h) = (spec.width, spec.height);
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    draw(spec, &mut rgb).map_err(fail)?;

    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, w, h);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder
            .write_header()
            .map_err(|e| fail(format!("PNG encoding: {e}")))?;
        writer
            .write_image_data(&rgb)
            .and_then(|()| writer.finish())
            .map_err(|e| fail(format!("PNG encoding: {e}")))?;
    }
    write_atomic(path, &png_bytes)
}

/// Registers the shipped font once per process.
fn register_font() -> Result<(), ()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(())
    }
}

/// The range covering `values` with a 5 % margin, or `fixed`.
fn axis_range(fixed: Option<(f64, f64)>, values: impl Iterator<Item = f64>) -> (f64, f64) {
    // A span or margin that overflows (a range from f64::MIN to f64::MAX,
    // values near ±1e308) would hang the plotting library's choice of tick
    // marks: such a range falls back to the data's, then to (0, 1).
    let usable = |(lo, hi): (f64, f64)| lo < hi && (1.1 * (hi - lo)).is_finite();
    if let Some(r) = fixed.filter(|&r| usable(r)) {
        return r;
    }
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let range = if lo > hi {
        (0.0, 1.0)
    } else if lo == hi {
        (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
    } else {
        let m = 0.05 * (hi - lo);
        (lo - m, hi + m)
    };
    if usable(range) {
        range
    } else {
        (0.0, 1.0)
    }
}

fn draw(spec: &PlotSpec<'_>, rgb: &mut [u8]) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let all = || {
        spec.series
            .iter()
            .flat_map(|s| s.points.iter().filter(finite))
    };
    let (x0, x1) = axis_range(spec.x_range, all().map(|p| p.0));
    let (y0, y1) = axis_range(spec.y_range, all().map(|p| p.1));

    let root = BitMapBackend::with_buffer(rgb, (spec.width, spec.height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut builder = ChartBuilder::on(&root);
    builder
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(64);
    if !spec.title.is_empty() {
        builder.caption(spec.title.as_ref(), ("sans-serif", 24));
    }
    let mut chart = builder
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_ref())
        .y_desc(spec.y_label.as_ref())
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| err(&e))?;

    for (k, s) in spec.series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let points = s.points.iter().filter(finite).copied();
        let line = matches!(s.style, SeriesStyle::Line | SeriesStyle::LineAndMarkers);
        let markers = matches!(s.style, SeriesStyle::Markers | SeriesStyle::LineAndMarkers);
        if line {
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| err(&e))?;
        }
        if markers {
            chart
                .draw_series(points.map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| err(&e))?;
        }
        // The legend entry: an invisible empty series carrying label and
        // glyph, so lines and markers share one entry.
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|e| err(&e))?
            .label(s.label.as_ref())
            .legend(move |(x, y)| {
                let stroke = colour.stroke_width(2);
                let fill = colour.filled();
                // Line and/or marker: a zero-radius circle draws nothing.
                let radius = if markers { 4 } else { 0 };
                let length = if line { 20 } else { 0 };
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(10 - length / 2, 0), (10 + length / 2, 0)], stroke)
                    + Circle::new((10, 0), radius, fill)
            });
    }
    if !spec.series.is_empty() {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A range whose span or margin overflows falls back to a finite one:
    /// handed to the plotting library, it hung the choice of tick marks.
    #[test]
    fn an_overflowing_axis_range_falls_back_to_a_finite_one() {
        let finite = |(lo, hi): (f64, f64)| lo < hi && (hi - lo).is_finite();
        assert!(finite(axis_range(
            Some((f64::MIN, f64::MAX)),
            [1.0, 2.0].into_iter()
        )));
        let (lo, hi) = axis_range(Some((f64::MIN, f64::MAX)), [1.0, 3.0].into_iter());
        assert!(
            (lo - 0.9).abs() < 1e-12 && (hi - 3.1).abs() < 1e-12,
            "{lo} {hi}"
        );
        assert!(finite(axis_range(None, [-1e308, 1e308].into_iter())));
        assert!(finite(axis_range(None, [f64::MAX].into_iter())));
        assert_eq!(axis_range(Some((0.0, 2.0)), [5.0].into_iter()), (0.0, 2.0));
    }
}
