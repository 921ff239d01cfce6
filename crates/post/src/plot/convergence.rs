//! Log–log convergence plots (error against δ, m or spacing) with fitted power-law rates.

use super::line::check_series;
use super::FONT;
use super::{
    draw_legend, extent, palette, plot_error, render, sci, titled_chart, Chart, DrawError, Figure,
    Labels, Legend, Series,
};
use crate::error::{CoreError, Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
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

/// Draws each series on log–log axes as markers (its `style` is ignored) with its
/// least-squares power law as a dashed line of the same colour, the rate in the legend ("name (rate 1.07)"), into `<stem>.png` and `<stem>.svg` (900 × 600 px).
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
                    Error::Core(CoreError::Model { message, .. }) => message,
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

/// Ticks of a log axis from 10^lo to 10^hi: (value, labelled). Every decade is labelled
/// (every n-th beyond eight decades); 2 and 5 times a decade too below four decades, 3 times
/// below one and a half, every integer multiple below 0.8 decades; unlabelled ticks mark the other integer
/// multiples when the axis spans fewer than six decades.
fn log_ticks(lo: f64, hi: f64) -> Vec<(f64, bool)> {
    let span = hi - lo;
    let mut out = Vec::new();
    let first = lo.floor() as i32;
    let last = hi.ceil() as i32;
    let step = ((span / 8.0).ceil() as i32).max(1);
    for k in first..=last {
        for m in 1..=9 {
            let v = m as f64 * 10f64.powi(k);
            let l = v.log10();
            if l < lo || l > hi {
                continue;
            }
            let label = match m {
                1 => k.rem_euclid(step) == 0,
                2 | 5 => span < 4.0,
                3 => span < 1.5,
                _ => span < 0.8,
            };
            if label || span < 6.0 {
                out.push((v, label));
            }
        }
    }
    out
}

/// A convergence plot ready to draw (coordinates are log10 of the data).
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
        let (x0, y0) = lg((self.x.0, self.y.0));
        let (x1, y1) = lg((self.x.1, self.y.1));
        let mut chart = titled_chart(root, &self.labels.title, (x0, x1), (y0, y1))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(0)
            .y_labels(0)
            .x_desc(&self.labels.x)
            .y_desc(&self.labels.y)
            .axis_desc_style((FONT, 20))
            .draw()?;
        draw_log_grid(&mut chart, root, (x0, x1), (y0, y1))?;
        self.draw_series(&mut chart)?;
        draw_legend(&mut chart, self.legend)
    }
}

/// (log10 x, log10 y): the chart's coordinates of a data point.
fn lg(p: (f64, f64)) -> (f64, f64) {
    (p.0.log10(), p.1.log10())
}

impl Convergence<'_> {
    /// Each series as dots with its fitted power law dashed, labelled with its rate.
    fn draw_series<'a, DB: DrawingBackend + 'a>(
        &self,
        chart: &mut Chart<'a, DB>,
    ) -> std::result::Result<(), DrawError>
    where
        DB::ErrorType: 'static,
    {
        for (s, law) in self.series.iter().zip(self.laws) {
            let c = palette(s.colour);
            let (a, b) = extent(s.points.iter().map(|p| p.0));
            let fit = [lg((a, law.at(a))), lg((b, law.at(b)))];
            let line = c.stroke_width(2);
            chart.draw_series(DashedLineSeries::new(fit, 10, 6, line))?;
            let dot = c.filled();
            let pts = s.points.iter().map(|&p| lg(p));
            let anno = chart.draw_series(pts.map(|p| Circle::new(p, 5, dot)))?;
            let name = if s.name.is_empty() {
                format!("rate {:.2}", law.rate)
            } else {
                format!("{} (rate {:.2})", s.name, law.rate)
            };
            anno.label(name).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (8, 0)], line)
                    + PathElement::new(vec![(16, 0), (24, 0)], line)
                    + Circle::new((12, 0), 5, dot)
            });
        }
        Ok(())
    }
}

/// Log ticks, grid lines and labels by hand over the log10 ranges `x` and `y` (plotters'
/// log axes skip the values below the first power of ten): bold at the labelled values.
fn draw_log_grid<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    root: &DrawingArea<DB, Shift>,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> std::result::Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let label = TextStyle::from((FONT, 18).into_font()).color(&BLACK);
    let grid = |bold: bool| BLACK.mix(if bold { 0.15 } else { 0.06 }).stroke_width(1);
    for (v, bold) in log_ticks(x0, x1) {
        let l = v.log10();
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(l, y0), (l, y1)],
            grid(bold),
        )))?;
        let (px, py) = chart.backend_coord(&(l, y0));
        let len = if bold { 6 } else { 3 };
        root.draw(&PathElement::new(vec![(px, py), (px, py + len)], BLACK))?;
        if bold {
            let style = label.pos(Pos::new(HPos::Center, VPos::Top));
            root.draw(&Text::new(log_tick(v), (px, py + 9), style))?;
        }
    }
    for (v, bold) in log_ticks(y0, y1) {
        let l = v.log10();
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x0, l), (x1, l)],
            grid(bold),
        )))?;
        let (px, py) = chart.backend_coord(&(x0, l));
        let len = if bold { 6 } else { 3 };
        root.draw(&PathElement::new(vec![(px - len, py), (px, py)], BLACK))?;
        if bold {
            let style = label.pos(Pos::new(HPos::Right, VPos::Center));
            root.draw(&Text::new(log_tick(v), (px - 9, py), style))?;
        }
    }
    Ok(())
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
    fn log_tick_labels() {
        assert_eq!(log_tick(0.002), "0.002");
        assert_eq!(log_tick(5e-5), "5e-5");
        assert_eq!(log_tick(10.0), "10");
        let labelled = |lo: f64, hi: f64| -> Vec<f64> {
            log_ticks(lo, hi)
                .into_iter()
                .filter(|t| t.1)
                .map(|t| t.0)
                .collect()
        };
        let same = |a: Vec<f64>, b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x / y - 1.0).abs() < 1e-12)
        };
        assert!(same(labelled(-3.6, -3.1), &[3e-4, 4e-4, 5e-4, 6e-4, 7e-4]));
        assert!(same(labelled(-3.9, -2.9), &[2e-4, 3e-4, 5e-4, 1e-3]));
        assert!(same(
            labelled(-4.2, -2.3),
            &[1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3]
        ));
        assert_eq!(labelled(-12.5, 0.0).len(), 7);
    }
}
