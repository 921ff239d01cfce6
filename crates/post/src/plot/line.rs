//! Line plots: several named series of (x, y) points as lines and/or markers.

use super::{
    axis_ticks, draw_legend, extent, palette, plot_error, render, titled_chart, DrawError, Figure,
    Labels, FONT,
};
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Style {
    /// A solid line through the points.
    #[default]
    Line,
    /// A dashed line through the points.
    Dashed,
    /// A filled circle at each point, no line.
    Markers,
    /// A solid line with a filled circle at each point.
    LineMarkers,
}

/// One named series of (x, y) points; series with the same `colour` index share a colour.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry (empty: none).
    pub name: String,
    /// The points, in drawing order (x, y in the units of the axis labels).
    pub points: Vec<(f64, f64)>,
    /// Lines, markers or both.
    pub style: Style,
    /// Colour index into [`super::palette`].
    pub colour: usize,
}

impl Series {
    /// A solid-line series in colour 0.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            style: Style::Line,
            colour: 0,
        }
    }

    /// The same series drawn in `style`.
    pub fn style(mut self, style: Style) -> Self {
        self.style = style;
        self
    }

    /// The same series in palette colour `k`.
    pub fn colour(mut self, k: usize) -> Self {
        self.colour = k;
        self
    }
}

/// Where the legend goes inside the plotting area.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Legend {
    /// Top right corner.
    #[default]
    UpperRight,
    /// Top left corner.
    UpperLeft,
    /// Bottom right corner.
    LowerRight,
    /// Bottom left corner.
    LowerLeft,
    /// No legend.
    None,
}

impl Legend {
    /// plotters' position, or None for no legend.
    pub(super) fn position(self) -> Option<SeriesLabelPosition> {
        match self {
            Legend::UpperRight => Some(SeriesLabelPosition::UpperRight),
            Legend::UpperLeft => Some(SeriesLabelPosition::UpperLeft),
            Legend::LowerRight => Some(SeriesLabelPosition::LowerRight),
            Legend::LowerLeft => Some(SeriesLabelPosition::LowerLeft),
            Legend::None => None,
        }
    }
}

/// Checks that there is at least one series, none is empty and every value is finite
/// (and positive if `positive`).
pub(super) fn check_series(stem: &Path, series: &[Series], positive: bool) -> Result<()> {
    if series.is_empty() {
        return Err(plot_error(stem, "no series to plot"));
    }
    for s in series {
        if s.points.is_empty() {
            return Err(plot_error(
                stem,
                format!("series `{}` has no points", s.name),
            ));
        }
        for (k, &(x, y)) in s.points.iter().enumerate() {
            if !x.is_finite() || !y.is_finite() {
                return Err(plot_error(
                    stem,
                    format!("series `{}`: point {k} is ({x}, {y}), not finite", s.name),
                ));
            }
            if positive && (x <= 0.0 || y <= 0.0) {
                return Err(plot_error(
                    stem,
                    format!(
                        "series `{}`: point {k} is ({x}, {y}); a log–log plot needs positive values",
                        s.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Draws `series` against linear axes into `<stem>.png` and `<stem>.svg` (900 × 600 px):
/// the ranges are the data's with margins of 1 % (x) and 5 % (y).
pub fn line_plot(stem: &Path, labels: &Labels, series: &[Series], legend: Legend) -> Result<()> {
    check_series(stem, series, false)?;
    let all = || series.iter().flat_map(|s| s.points.iter());
    let x = extent(all().map(|p| p.0));
    if x.1 <= x.0 {
        return Err(plot_error(
            stem,
            format!("every x is {}: the x range has zero size", x.0),
        ));
    }
    let (y0, y1) = extent(all().map(|p| p.1));
    let (y0, y1) = super::widen(y0, y1);
    let pad = 0.05 * (y1 - y0);
    let margin = 0.01 * (x.1 - x.0);
    let fig = LinePlot {
        labels,
        series,
        legend,
        x: (x.0 - margin, x.1 + margin),
        y: (y0 - pad, y1 + pad),
    };
    render(stem, &fig)
}

/// A line plot ready to draw.
struct LinePlot<'a> {
    labels: &'a Labels,
    series: &'a [Series],
    legend: Legend,
    x: (f64, f64),
    y: (f64, f64),
}

impl Figure for LinePlot<'_> {
    fn size(&self) -> (u32, u32) {
        (900, 600)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        let (x, y) = (self.x, self.y);
        let mut chart = titled_chart(root, &self.labels.title, x, y)?;
        let (fx, fy) = (axis_ticks(x), axis_ticks(y));
        chart
            .configure_mesh()
            .set_all_tick_mark_size(5)
            .x_desc(&self.labels.x)
            .y_desc(&self.labels.y)
            .label_style((FONT, 18))
            .axis_desc_style((FONT, 20))
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(TRANSPARENT)
            .draw()?;
        let mut named = false;
        for s in self.series {
            let c = palette(s.colour);
            let line = c.stroke_width(2);
            let dot = c.filled();
            let pts = s.points.iter().copied();
            let anno = match s.style {
                Style::Line => chart.draw_series(LineSeries::new(pts, line))?,
                Style::Dashed => chart.draw_series(DashedLineSeries::new(pts, 9, 5, line))?,
                Style::Markers => chart.draw_series(pts.map(|p| Circle::new(p, 4, dot)))?,
                Style::LineMarkers => {
                    chart.draw_series(LineSeries::new(pts.clone(), line))?;
                    chart.draw_series(pts.map(|p| Circle::new(p, 4, dot)))?
                }
            };
            if s.name.is_empty() {
                continue;
            }
            named = true;
            anno.label(&s.name);
            match s.style {
                Style::Line => {
                    anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], line))
                }
                Style::Dashed => anno.legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (9, 0)], line)
                        + PathElement::new(vec![(15, 0), (24, 0)], line)
                }),
                Style::Markers => anno.legend(move |(x, y)| Circle::new((x + 12, y), 4, dot)),
                Style::LineMarkers => anno.legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (24, 0)], line)
                        + Circle::new((12, 0), 4, dot)
                }),
            };
        }
        if named {
            draw_legend(&mut chart, self.legend)?;
        }
        Ok(())
    }
}
