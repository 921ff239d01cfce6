//! Log–log convergence plots (error against δ, m or spacing) with fitted power-law rates.

use super::line::check_series;
use super::{extent, palette, plot_error, render, sci, DrawError, Figure, Labels, Legend, Series};
use super::{Style, FONT};
use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// A power law y = coefficient · x^rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerLaw {
    /// The exponent (the convergence rate).
    pub rate: f64,
    /// The prefactor (y at x = 1).
    pub coefficient: f64,
}

impl PowerLaw {
    /// The law's value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        self.coefficient * x.powf(self.rate)
    }
}

/// Least-squares fit of ln y = ln c + r ln x; needs at least two points with distinct
/// positive x and positive y.
pub fn fit_power_law(xs: &[f64], ys: &[f64]) -> Result<PowerLaw> {
    let bad = |m: String| Error::model("fit_rate", m);
    if xs.len() != ys.len() {
        return Err(bad(format!(
            "{} x values but {} y values",
            xs.len(),
            ys.len()
        )));
    }
    if xs.len() < 2 {
        return Err(bad(format!("needs at least two points, got {}", xs.len())));
    }
    if let Some((x, y)) = xs
        .iter()
        .zip(ys)
        .find(|(x, y)| !(x.is_finite() && y.is_finite() && **x > 0.0 && **y > 0.0))
    {
        return Err(bad(format!(
            "point ({x}, {y}): x and y must be finite and positive"
        )));
    }
    let n = xs.len() as f64;
    let lx: Vec<f64> = xs.iter().map(|x| x.ln()).collect();
    let ly: Vec<f64> = ys.iter().map(|y| y.ln()).collect();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    if sxx <= 0.0 {
        return Err(bad("every x is the same: no rate can be fitted".into()));
    }
    let rate = sxy / sxx;
    Ok(PowerLaw {
        rate,
        coefficient: (my - rate * mx).exp(),
    })
}

/// The fitted power-law exponent of y against x (see [`fit_power_law`]).
pub fn fit_rate(xs: &[f64], ys: &[f64]) -> Result<f64> {
    fit_power_law(xs, ys).map(|p| p.rate)
}

/// Draws each series on log–log axes (markers joined by a thin line, its own style
/// ignored) with its least-squares power law as a dashed line of the same colour, the rate
/// in the legend ("name (rate 1.07)"), into `<stem>.png` and `<stem>.svg` (900 × 600 px).
/// Returns the fitted laws in the order of `series`; every series needs two or more
/// distinct positive x and positive y.
pub fn convergence_plot(
    stem: &Path,
    labels: &Labels,
    series: &[Series],
    legend: Legend,
) -> Result<Vec<PowerLaw>> {
    check_series(stem, series, true)?;
    let laws = series
        .iter()
        .map(|s| {
            let (xs, ys): (Vec<f64>, Vec<f64>) = s.points.iter().copied().unzip();
            fit_power_law(&xs, &ys).map_err(|e| {
                let msg = match e {
                    Error::Model { message, .. } => message,
                    e => e.to_string(),
                };
                plot_error(stem, format!("series `{}`: {msg}", s.name))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = extent(all().map(|p| p.0));
    let (y0, y1) = extent(all().map(|p| p.1));
    let fig = Convergence {
        labels,
        series,
        laws: &laws,
        legend,
        x: (x0 / 1.15, x1 * 1.15),
        y: (y0 / 1.6, y1 * 1.6),
    };
    render(stem, &fig)?;
    Ok(laws)
}

/// Tick label on a logarithmic axis.
fn log_tick(v: f64) -> String {
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        sci(v)
    }
}

/// A convergence plot ready to draw.
struct Convergence<'a> {
    labels: &'a Labels,
    series: &'a [Series],
    laws: &'a [PowerLaw],
    legend: Legend,
    x: (f64, f64),
    y: (f64, f64),
}

impl Figure for Convergence<'_> {
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
        let mut chart = ChartBuilder::on(root)
            .caption(&self.labels.title, (FONT, 26))
            .margin(15)
            .x_label_area_size(55)
            .y_label_area_size(85)
            .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())?;
        let f = |v: &f64| log_tick(*v);
        chart
            .configure_mesh()
            .x_desc(&self.labels.x)
            .y_desc(&self.labels.y)
            .label_style((FONT, 18))
            .axis_desc_style((FONT, 20))
            .x_label_formatter(&f)
            .y_label_formatter(&f)
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(TRANSPARENT)
            .draw()?;
        for (s, law) in self.series.iter().zip(self.laws) {
            let c = palette(s.colour);
            let (a, b) = extent(s.points.iter().map(|p| p.0));
            let fit = [(a, law.at(a)), (b, law.at(b))];
            chart.draw_series(DashedLineSeries::new(fit, 9, 5, c.stroke_width(1)))?;
            let pts = s.points.iter().copied();
            if s.style != Style::Markers {
                chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?;
            }
            let dot = c.filled();
            let anno = chart.draw_series(pts.map(|p| Circle::new(p, 5, dot)))?;
            let name = if s.name.is_empty() {
                format!("rate {:.2}", law.rate)
            } else {
                format!("{} (rate {:.2})", s.name, law.rate)
            };
            anno.label(name).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (24, 0)], c.stroke_width(2))
                    + Circle::new((12, 0), 5, dot)
            });
        }
        if let Some(pos) = self.legend.position() {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact power laws come back to round-off, including negative and zero rates.
    #[test]
    fn fit_recovers_exact_rates() {
        for rate in [2.0, 1.07, -0.5, 0.0, 3.25] {
            let xs = [1e-4, 3e-4, 1e-3, 2.5e-3, 1e-2];
            let ys: Vec<f64> = xs.iter().map(|x: &f64| 4.2 * x.powf(rate)).collect();
            let law = fit_power_law(&xs, &ys).unwrap();
            assert!((law.rate - rate).abs() < 1e-12, "{rate}: {}", law.rate);
            assert!((law.coefficient / 4.2 - 1.0).abs() < 1e-9);
            assert_eq!(fit_rate(&xs, &ys).unwrap(), law.rate);
        }
    }

    /// Too few points, equal x, mismatched lengths and non-positive values are errors.
    #[test]
    fn fit_refuses_bad_input() {
        assert!(fit_rate(&[], &[]).is_err());
        assert!(fit_rate(&[1.0], &[1.0]).is_err());
        assert!(fit_rate(&[1.0, 1.0], &[1.0, 2.0]).is_err());
        assert!(fit_rate(&[1.0, 2.0], &[1.0]).is_err());
        assert!(fit_rate(&[1.0, 2.0], &[0.0, 1.0]).is_err());
        assert!(fit_rate(&[1.0, f64::NAN], &[1.0, 1.0]).is_err());
    }

    /// Log tick labels.
    #[test]
    fn log_ticks() {
        assert_eq!(log_tick(0.002), "0.002");
        assert_eq!(log_tick(5e-5), "5e-5");
        assert_eq!(log_tick(10.0), "10");
    }
}
