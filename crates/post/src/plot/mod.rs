//! Plots for reports, drawn with plotters: line plots ([`line_plot`]), log–log convergence
//! plots with fitted power-law rates ([`convergence_plot`], [`fit_rate`]) and 2D maps of a
//! node cloud ([`field_map`]). Data in, files out: every plot writes `<stem>.png` and
//! `<stem>.svg`; no physics and no case files here. Text uses the bundled DejaVu Sans
//! (`crates/post/assets/fonts/`), so it renders on machines without system fonts.

mod colour;
mod convergence;
mod line;
mod map;

pub use colour::ColourMap;
pub use convergence::{convergence_plot, fit_power_law, fit_rate, PowerLaw};
pub use line::{line_plot, Legend, Series, Style};
pub use map::{field_map, isoline, FieldMap, IRREGULAR_SQUARE};

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Font family name under which the bundled font is registered (and named in the SVG).
pub const FONT: &str = "sans-serif";

/// The bundled font (DejaVu Sans 2.37, Bitstream Vera licence: `crates/post/assets/fonts/`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the bundled font once; false if it could not be parsed.
fn font_ready() -> bool {
    static READY: OnceLock<bool> = OnceLock::new();
    *READY
        .get_or_init(|| plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok())
}

/// Title and axis labels of a plot (put the units in the labels, e.g. "x (m)").
#[derive(Clone, Debug, Default)]
pub struct Labels {
    /// Title above the plot.
    pub title: String,
    /// Label of the horizontal axis, with its unit.
    pub x: String,
    /// Label of the vertical axis, with its unit.
    pub y: String,
}

impl Labels {
    /// Labels from a title and the two axis labels.
    pub fn new(title: impl Into<String>, x: impl Into<String>, y: impl Into<String>) -> Self {
        Labels {
            title: title.into(),
            x: x.into(),
            y: y.into(),
        }
    }
}

/// Ten distinguishable series colours (matplotlib's "tab10"); index modulo 10.
pub fn palette(k: usize) -> RGBColor {
    const C: [(u8, u8, u8); 10] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
    ];
    let (r, g, b) = C[k % C.len()];
    RGBColor(r, g, b)
}

/// Error type of the drawing code (plotters' errors, boxed).
type DrawError = Box<dyn std::error::Error>;

/// A chart with f64 coordinates on both axes (the maps' metres, the convergence plots' log10).
type Chart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// A picture that can be drawn on any plotters backend.
trait Figure {
    /// Size of the image, pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the picture on `root` (already filled white).
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static;
}

/// The chart of the line and convergence plots on `root`: `title` above, room for the axis
/// labels, f64 axes over the ranges `x` and `y` (their mesh is the caller's).
fn titled_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    x: (f64, f64),
    y: (f64, f64),
) -> std::result::Result<Chart<'a, DB>, DrawError>
where
    DB::ErrorType: 'static,
{
    let chart = ChartBuilder::on(root)
        .caption(title, (FONT, 26))
        .margin(15)
        .x_label_area_size(55)
        .y_label_area_size(85)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
    Ok(chart)
}

/// The box of the series' legend entries in the corner `legend` asks for (none for
/// [`Legend::None`]).
fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    legend: Legend,
) -> std::result::Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    if let Some(pos) = legend.position() {
        chart
            .configure_series_labels()
            .position(pos)
            .label_font((FONT, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()?;
    }
    Ok(())
}

/// `stem` with `.ext` appended (a stem like `conv_k0.5` keeps its dot).
fn with_ext(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// A [`Error::Plot`] about `stem`.
fn plot_error(stem: &Path, message: impl Into<String>) -> Error {
    Error::Plot {
        path: stem.to_path_buf(),
        message: message.into(),
    }
}

/// Draws `fig` into `<stem>.png` and `<stem>.svg`.
fn render(stem: &Path, fig: &impl Figure) -> Result<()> {
    if !font_ready() {
        return Err(plot_error(stem, "the bundled font could not be loaded"));
    }
    let size = fig.size();
    let fail = |what: &str, e: &dyn std::fmt::Display| plot_error(stem, format!("{what}: {e}"));
    {
        let png = with_ext(stem, "png");
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail("png", &e))?;
        fig.draw(&root).map_err(|e| fail("png", &e))?;
        root.present()
            .map_err(|e| fail(&png.display().to_string(), &e))?;
    }
    {
        let svg = with_ext(stem, "svg");
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail("svg", &e))?;
        fig.draw(&root).map_err(|e| fail("svg", &e))?;
        root.present()
            .map_err(|e| fail(&svg.display().to_string(), &e))?;
    }
    Ok(())
}

/// Smallest and largest of `v` (which must be finite and non-empty).
fn extent(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    })
}

/// A range that is never empty: a single value gets ±10 % (±1 at zero) around it.
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if hi > lo {
        (lo, hi)
    } else {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    }
}

/// Tick label of `v` on an axis spanning `span`: fixed decimals suited to the span, or
/// scientific notation for very large or small numbers.
fn tick_label(v: f64, span: f64, largest: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let d = 1.0 - (span / 2.0).log10().floor();
    if largest >= 1e5 || d > 5.0 {
        return sci(v);
    }
    let d = d.max(0.0) as usize;
    let s = format!("{v:.d$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        &s
    };
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// The tick labels of a linear axis over `(lo, hi)`: [`tick_label`] with the axis's span and
/// largest magnitude.
fn axis_ticks((lo, hi): (f64, f64)) -> impl Fn(&f64) -> String {
    let (span, largest) = (hi - lo, lo.abs().max(hi.abs()));
    move |v| tick_label(*v, span, largest)
}

/// `v` in short scientific notation: "2.5e-3", "1e6".
fn sci(v: f64) -> String {
    let s = format!("{v:.2e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let m = m.trim_end_matches('0').trim_end_matches('.');
    format!("{m}e{e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tick labels read naturally on metre, degree and damage axes.
    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(0.005, 0.02, 0.01), "0.005");
        assert_eq!(tick_label(-100.0, 200.0, 100.0), "-100");
        assert_eq!(tick_label(0.2, 1.0, 1.0), "0.2");
        assert_eq!(tick_label(2.5e-3, 0.01, 0.005), "0.0025");
        assert_eq!(tick_label(2.5e-7, 1e-6, 1e-6), "2.5e-7");
        assert_eq!(tick_label(1.0e6, 2e6, 2e6), "1e6");
        assert_eq!(sci(-1.25e-7), "-1.25e-7");
    }

    /// The stem keeps its dots and gains the extension.
    #[test]
    fn extensions() {
        assert_eq!(
            with_ext(Path::new("out/conv_k0.5"), "png"),
            PathBuf::from("out/conv_k0.5.png")
        );
    }
}
