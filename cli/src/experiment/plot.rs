//! Line plots with `plotters` (bitmap backend, encoded by the `png` crate).
//!
//! Text is drawn with an embedded subset of DejaVu Sans
//! (`cli/assets/DejaVuSans-subset.ttf`, Bitstream Vera licence with DejaVu's
//! public-domain changes, see `cli/assets/FONT-LICENSE.txt`), so plotting
//! needs no system font library. Logarithmic axes are drawn as linear axes
//! over `log₂ x` or `log₁₀ y` whose tick labels show the original values.

use crate::error::CliError;
use plotters::prelude::*;
use std::io::BufWriter;
use std::path::Path;
use std::sync::OnceLock;

/// The embedded font (ASCII, Greek Δ λ μ σ α, ×, −, ≈, ≤, ≥, subscripts).
const FONT: &[u8] = include_bytes!("../../assets/DejaVuSans-subset.ttf");
/// The family name the font is registered under.
const FAMILY: &str = "sans-serif";
/// Plot size, pixels.
pub const PLOT_SIZE_PX: (u32, u32) = (880, 520);
/// Title, axis label and legend font sizes, pixels.
const TITLE_PX: u32 = 22;
const LABEL_PX: u32 = 16;
const LEGEND_PX: u32 = 15;
/// Margin around the chart and the space of the axis labels, pixels.
const MARGIN_PX: u32 = 14;
const X_LABEL_AREA_PX: u32 = 46;
const Y_LABEL_AREA_PX: u32 = 70;
/// Marker radius, pixels.
const MARKER_PX: i32 = 3;
/// Most ticks on an axis (about).
const MAX_TICKS: usize = 8;
/// Log axes spanning at most this many decades get ticks at 2 and 5 too.
const DECADES_WITH_SUBTICKS: f64 = 2.5;
/// Fraction of the data span added above and below the y range.
const Y_PADDING: f64 = 0.06;

/// Distinct line colours (Okabe–Ito, colour-blind safe, then grey, brown
/// and violet).
const COLOURS: [RGBColor; 10] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(128, 128, 128),
    RGBColor(153, 79, 0),
    RGBColor(120, 60, 200),
];

/// How an axis maps values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear.
    Linear,
    /// Logarithmic, base 2 (sample counts).
    Log2,
    /// Logarithmic, base 10.
    Log10,
}

impl Scale {
    fn forward(self, v: f64) -> f64 {
        match self {
            Self::Linear => v,
            Self::Log2 => v.log2(),
            Self::Log10 => v.log10(),
        }
    }

    /// Tick positions (in drawing space) over `[lo, hi]`: powers of two,
    /// decades with 2 and 5 between them over short spans, or 1-2-5 steps.
    fn ticks(self, lo: f64, hi: f64) -> Vec<f64> {
        let within = |t: &f64| *t >= lo - 1e-9 && *t <= hi + 1e-9;
        let mut ticks: Vec<f64> = match self {
            Self::Log2 => {
                let step = ((hi - lo) / MAX_TICKS as f64).ceil().max(1.0);
                let first = (lo / step).ceil() as i64;
                let last = (hi / step).floor() as i64;
                (first..=last).map(|k| k as f64 * step).collect()
            }
            Self::Log10 => {
                let sub: &[f64] = if hi - lo <= DECADES_WITH_SUBTICKS {
                    &[1.0, 2.0, 5.0]
                } else {
                    &[1.0]
                };
                let (first, last) = (lo.floor() as i64, hi.ceil() as i64);
                (first..=last)
                    .flat_map(|d| sub.iter().map(move |m| d as f64 + m.log10()))
                    .filter(within)
                    .collect()
            }
            Self::Linear => {
                let raw = (hi - lo) / MAX_TICKS as f64;
                let magnitude = 10f64.powf(raw.log10().floor());
                let step = [1.0, 2.0, 5.0, 10.0]
                    .iter()
                    .map(|m| m * magnitude)
                    .find(|s| *s >= raw)
                    .unwrap_or(10.0 * magnitude);
                let (first, last) = ((lo / step).ceil() as i64, (hi / step).floor() as i64);
                (first..=last).map(|k| k as f64 * step).collect()
            }
        };
        ticks.retain(|t| t.is_finite() && within(t));
        if ticks.is_empty() {
            ticks = vec![lo, hi];
        }
        ticks
    }

    fn label(self, t: f64) -> String {
        let v = match self {
            Self::Linear => t,
            Self::Log2 => t.exp2(),
            Self::Log10 => 10f64.powf(t),
        };
        if (v - v.round()).abs() < 1e-6 * v.abs().max(1.0) && v.abs() < 1e7 {
            format!("{}", v.round())
        } else if v.abs() >= 1e-3 && v.abs() < 1.0 {
            let text = format!("{v:.3}");
            text.trim_end_matches('0').to_string()
        } else {
            super::report::sig3(v)
        }
    }
}

/// A linear drawing axis over `[lo, hi]` with the ticks of a [`Scale`].
#[derive(Debug, Clone, PartialEq)]
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
}

impl Axis {
    fn new(lo: f64, hi: f64, scale: Scale) -> Self {
        Self {
            lo,
            hi,
            ticks: scale.ticks(lo, hi),
        }
    }
}

impl Ranged for Axis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let t = (value - self.lo) / (self.hi - self.lo);
        let pixels = f64::from(limit.1 - limit.0);
        limit.0 + (t * pixels).round() as i32
    }

    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// One named line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// A line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot<'a> {
    /// Caption.
    pub title: &'a str,
    /// X axis label.
    pub x_label: &'a str,
    /// Y axis label.
    pub y_label: &'a str,
    /// X scale.
    pub x_scale: Scale,
    /// Y scale.
    pub y_scale: Scale,
    /// The lines.
    pub series: &'a [Series],
}

fn register_font() -> Result<(), CliError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(CliError::input("the embedded plot font could not be read"))
    }
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::input(format!("{}: cannot draw the plot: {e}", path.display()))
}

impl LinePlot<'_> {
    /// Points mapped to the drawing axes; points that cannot be drawn
    /// (non-finite, or not positive on a log axis) are dropped.
    fn mapped(&self) -> Vec<Vec<(f64, f64)>> {
        self.series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .map(|&(x, y)| (self.x_scale.forward(x), self.y_scale.forward(y)))
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect()
            })
            .collect()
    }

    /// Draws the plot into an RGB buffer of [`PLOT_SIZE_PX`].
    fn draw(&self, path: &Path, buffer: &mut [u8]) -> Result<(), CliError> {
        let mapped = self.mapped();
        let all = || mapped.iter().flatten();
        let (mut x0, mut x1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
        let (mut y0, mut y1) = all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
        if !(x0.is_finite() && x1.is_finite()) {
            (x0, x1) = (0.0, 1.0);
        }
        if !(y0.is_finite() && y1.is_finite()) {
            (y0, y1) = (0.0, 1.0);
        }
        if x1 - x0 <= 0.0 {
            (x0, x1) = (x0 - 0.5, x1 + 0.5);
        }
        let pad = (y1 - y0).max(1e-9 * y1.abs().max(1.0)) * Y_PADDING;
        let (y0, y1) = (y0 - pad, y1 + pad);
        let root = BitMapBackend::with_buffer(buffer, PLOT_SIZE_PX).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(self.title, (FAMILY, TITLE_PX))
            .margin(MARGIN_PX)
            .x_label_area_size(X_LABEL_AREA_PX)
            .y_label_area_size(Y_LABEL_AREA_PX)
            .build_cartesian_2d(
                Axis::new(x0, x1, self.x_scale),
                Axis::new(y0, y1, self.y_scale),
            )
            .map_err(|e| plot_error(path, e))?;
        let (x_scale, y_scale) = (self.x_scale, self.y_scale);
        let x_fmt = move |t: &f64| x_scale.label(*t);
        let y_fmt = move |t: &f64| y_scale.label(*t);
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .label_style((FAMILY, LABEL_PX))
            .axis_desc_style((FAMILY, LABEL_PX))
            .bold_line_style(RGBColor(225, 225, 225))
            .draw()
            .map_err(|e| plot_error(path, e))?;
        for (i, (series, points)) in self.series.iter().zip(&mapped).enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let style = ShapeStyle::from(&colour).stroke_width(2);
            chart
                .draw_series(LineSeries::new(points.iter().copied(), style))
                .map_err(|e| plot_error(path, e))?
                .label(series.name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|&p| Circle::new(p, MARKER_PX, colour.filled())),
                )
                .map_err(|e| plot_error(path, e))?;
        }
        chart
            .configure_series_labels()
            .label_font((FAMILY, LEGEND_PX))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| plot_error(path, e))?;
        root.present().map_err(|e| plot_error(path, e))
    }

    /// Draws the plot and writes it as an 8-bit RGB PNG.
    pub fn write_png(&self, path: &Path) -> Result<(), CliError> {
        register_font()?;
        let (width, height) = PLOT_SIZE_PX;
        let mut buffer = vec![255u8; width as usize * height as usize * 3];
        self.draw(path, &mut buffer)?;
        let file = std::fs::File::create(path)
            .map_err(|e| CliError::input(format!("{}: cannot write: {e}", path.display())))?;
        let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::High);
        let mut writer = encoder
            .write_header()
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        writer
            .write_image_data(&buffer)
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        writer
            .finish()
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))
    }
}
