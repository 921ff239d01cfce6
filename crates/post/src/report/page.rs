//! Reports of finished runs: plots of PD against the reference along the probe lines, the
//! error along them, maps of temperature (and damage and heat flux for cracked bodies), and
//! `report.md` plus `index.html` showing them with the metrics and the run's settings.

use crate::error::{IoError, Result};
use crate::plot::{
    field_map, isoline, line_plot, ColourMap, FieldMap, Labels, Legend, Series, Style,
};
use peritherm_core::crack::segments_at;
use peritherm_core::math::Point;
use peritherm_core::model::crack_cutters;
use peritherm_io::atomic::write_atomic;
use peritherm_io::case::Case;
use peritherm_io::output::{number_label, FieldRows, RunSummary};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A straight probe line of a report: the nodes within half a spacing of it.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeLine {
    /// Name used in file names and titles, e.g. "y = 0".
    pub name: String,
    /// The coordinate that varies along the line (0 = x, 1 = y).
    pub along: usize,
    /// The coordinate held fixed, and its value, m.
    pub fixed: Option<(usize, f64)>,
}

impl ProbeLine {
    /// The rows of `f` on this line, ordered along it, as (index, coordinate along).
    pub fn nodes(&self, f: &FieldRows) -> Vec<(usize, f64)> {
        let mut v: Vec<(usize, f64)> = (0..f.pos.len())
            .filter(|&i| match self.fixed {
                Some((a, c)) => (f.pos[i][a] - c).abs() <= 0.5 * f.spacing[i] * (1.0 + 1e-9),
                None => true,
            })
            .map(|i| (i, f.pos[i][self.along]))
            .collect();
        v.sort_by(|a, b| a.1.total_cmp(&b.1));
        v
    }

    /// A file-name-safe form of the name.
    pub fn slug(&self) -> String {
        self.name
            .chars()
            .filter_map(|c| match c {
                ' ' => None,
                '=' => Some('_'),
                c if c.is_ascii_alphanumeric() || c == '.' || c == '-' => Some(c),
                _ => Some('_'),
            })
            .collect()
    }
}

/// The case's probe lines: the bar in 1D; in 2D and 3D the reference's `line_y`, `line_x`,
/// `lines_y` and `lines_x`, or the horizontal line through the middle of the nodes when it
/// names none.
pub fn probe_lines(case: &Case, f: &FieldRows, dim: usize) -> Vec<ProbeLine> {
    if dim == 1 {
        return vec![ProbeLine {
            name: "bar".into(),
            along: 0,
            fixed: None,
        }];
    }
    let (ly, lx) = case
        .reference
        .as_ref()
        .map_or((None, None), |r| (r.line_y, r.line_x));
    let mut lines = Vec::new();
    let horizontal = |y: f64| ProbeLine {
        name: format!("y = {}", number_label(y)),
        along: 0,
        fixed: Some((1, y)),
    };
    let vertical = |x: f64| ProbeLine {
        name: format!("x = {}", number_label(x)),
        along: 1,
        fixed: Some((0, x)),
    };
    if let Some(y) = ly {
        lines.push(horizontal(y));
    }
    if let Some(x) = lx {
        lines.push(vertical(x));
    }
    if let Some(r) = &case.reference {
        lines.extend(r.lines_y.iter().map(|&y| horizontal(y)));
        lines.extend(r.lines_x.iter().map(|&x| vertical(x)));
    }
    lines.dedup();
    if lines.is_empty() {
        // the node row nearest the middle of the body
        let (lo, hi) = f
            .pos
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.y), b.max(p.y)));
        let mid = 0.5 * (lo + hi);
        let y = f
            .pos
            .iter()
            .map(|p| p.y)
            .min_by(|a, b| (a - mid).abs().total_cmp(&(b - mid).abs()))
            .unwrap_or(mid);
        lines.push(horizontal(y));
    }
    lines
}

/// Draws per output k `map_<k>` (temperature on one colour range for all outputs, cracks as
/// at that time, region boundaries, heat-flux arrows when the body is cracked) and, for a
/// cracked body, `damage_<k>`, into `dir`; returns the stems drawn. 2D only.
pub fn draw_maps(
    case: &Case,
    summary: &RunSummary,
    fields: &[FieldRows],
    dir: &Path,
) -> Result<Vec<PathBuf>> {
    let cloud = case.spec.geometry.bare_cloud()?;
    let cutters = crack_cutters(&cloud, &case.spec.cracks);
    let (lo, hi) = fields
        .iter()
        .flat_map(|f| f.theta.iter())
        .fold((f64::MAX, f64::MIN), |(a, b), &t| (a.min(t), b.max(t)));
    let range = (hi > lo).then_some((lo, hi));
    let cracked = fields.iter().any(|f| f.damage.iter().any(|&d| d > 0.0));
    let name = title(summary);
    let mut stems = Vec::new();
    for (k, (f, t)) in fields.iter().zip(&summary.output_times).enumerate() {
        let cracks = segments_at(&cutters, *t);
        let several_regions = f.region.iter().any(|&r| r != f.region[0]);
        // phase fronts: the isotherms at each phase-change temperature (PCS2022
        // Fig. 13)
        let fronts: Vec<[Point; 2]> = case
            .spec
            .materials
            .iter()
            .filter_map(|m| m.phase_change.map(|p| p.temperature))
            .flat_map(|tf| isoline(&f.pos, &f.theta, &f.spacing, tf))
            .collect();
        let mut map = FieldMap::new(&f.pos, &f.theta, &f.spacing);
        map.isolines = &fronts;
        map.title = format!("{name}: temperature at t = {} s", number_label(*t));
        map.quantity = if fronts.is_empty() {
            "Temperature (°C)".into()
        } else {
            "Temperature (°C); dark red: the phase front".into()
        };
        map.range = range;
        map.cracks = &cracks;
        map.regions = several_regions.then_some(&f.region[..]);
        map.flux = cracked.then_some(&f.flux[..]);
        let stem = dir.join(format!("map_{}", k + 1));
        field_map(&stem, &map)?;
        stems.push(stem);
        if cracked {
            let mut map = FieldMap::new(&f.pos, &f.damage, &f.spacing);
            map.title = format!("{name}: damage at t = {} s", number_label(*t));
            map.quantity = "Damage φ (–)".into();
            map.colour_map = ColourMap::Sequential;
            map.range = Some((0.0, 1.0));
            map.cracks = &cracks;
            let stem = dir.join(format!("damage_{}", k + 1));
            field_map(&stem, &map)?;
            stems.push(stem);
        }
    }
    Ok(stems)
}

/// A time unit that reads well for times up to `end`, s: its name and seconds per unit.
fn time_unit(end: f64) -> (&'static str, f64) {
    [("ps", 1e-12), ("ns", 1e-9), ("µs", 1e-6), ("ms", 1e-3)]
        .into_iter()
        .find(|(_, u)| end <= 1e3 * u)
        .unwrap_or(("s", 1.0))
}

/// Draws the history of the run in `run` into `dir`: `history` (temperature against time at
/// every `[history]` point, PD as markers, the reference as lines) and, when the case asks
/// for `plot = "normalised"`, `history_normalised` (each curve over its own largest |θ|,
/// T / T_max). Returns the stems drawn.
pub fn draw_history(
    case: &Case,
    summary: &RunSummary,
    run: &Path,
    dir: &Path,
    reference_name: &str,
) -> Result<Vec<PathBuf>> {
    let curves = peritherm_io::history::read(run)?;
    let end = curves
        .iter()
        .flat_map(|c| c.1.iter().map(|p| p.0))
        .fold(0.0, f64::max);
    let (unit, per) = time_unit(end);
    let normalised = case
        .history
        .as_ref()
        .is_some_and(|h| h.plot == peritherm_io::history::HistoryPlot::Normalised);
    let mut stems = Vec::new();
    for norm in [false, true] {
        if norm && !normalised {
            continue;
        }
        let scale = |v: &[(f64, f64)]| {
            let m = v.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
            if norm && m > 0.0 {
                m
            } else {
                1.0
            }
        };
        let mut series = Vec::new();
        for (k, (p, pd, reference)) in curves.iter().enumerate() {
            let at = format!("({:.3e}, {:.3e}) m", p.x, p.y);
            let s = scale(pd);
            let pts = pd.iter().map(|q| (q.0 / per, q.1 / s)).collect();
            series.push(
                Series::new(format!("PD at {at}"), pts)
                    .style(Style::Markers)
                    .colour(k),
            );
            if let Some(r) = reference {
                let s = scale(r);
                let pts = r.iter().map(|q| (q.0 / per, q.1 / s)).collect();
                series.push(
                    Series::new(format!("{reference_name} at {at}"), pts)
                        .style(Style::Line)
                        .colour(k),
                );
            }
        }
        let (stem, what, y) = if norm {
            (
                "history_normalised",
                "normalised temperature",
                "T / T_max (–)",
            )
        } else {
            ("history", "temperature", "Temperature (°C)")
        };
        let stem = dir.join(stem);
        line_plot(
            &stem,
            &Labels::new(
                format!("{}: {what} against time", title(summary)),
                format!("t ({unit})"),
                y,
            ),
            &series,
            Legend::LowerRight,
        )?;
        stems.push(stem);
    }
    Ok(stems)
}

fn title(s: &RunSummary) -> String {
    if s.title.is_empty() {
        s.case.clone()
    } else {
        s.title.clone()
    }
}

/// What a report wrote, for an index over several reports.
#[derive(Debug, Clone)]
pub struct Written {
    /// The report's directory.
    pub dir: PathBuf,
    /// The run's summary.
    pub summary: RunSummary,
    /// Plots (stems, relative to `dir`).
    pub plots: Vec<String>,
}

/// Writes the report of the finished run in `run` of `case` into `dir`: the line plots, the
/// maps (2D), `report.md` and `index.html`. `reference_name` names the reference in legends;
/// `extra` is another finished run of the same case (e.g. `peritherm fem`) drawn along the
/// probe lines as dashed lines, with its name.
pub fn write_report(
    case: &Case,
    run: &Path,
    dir: &Path,
    reference_name: &str,
    extra: Option<(&Path, &str)>,
) -> Result<Written> {
    std::fs::create_dir_all(dir).map_err(|error| IoError::Io {
        path: dir.to_path_buf(),
        error,
    })?;
    let summary = RunSummary::read(run)?;
    let fields = (0..summary.fields.len())
        .map(|k| summary.read_field(run, k))
        .collect::<peritherm_io::Result<Vec<_>>>()?;
    let dim = case.spec.geometry.bare_cloud()?.dim;
    let extra = match extra {
        Some((d, name)) => Some(ExtraRun::read(d, name, &summary)?),
        None => None,
    };
    let mut plots = Vec::new();
    let stem_name = |p: &Path| {
        p.strip_prefix(dir)
            .unwrap_or(p)
            .to_string_lossy()
            .into_owned()
    };
    if let Some(first) = fields.first() {
        let lines = LinePlots {
            summary: &summary,
            fields: &fields,
            extra: extra.as_ref(),
            reference_name,
            dir,
        };
        for line in probe_lines(case, first, dim) {
            for stem in lines.draw(&line)? {
                plots.push(stem_name(&stem));
            }
        }
    }
    if summary.history.is_some() {
        for stem in draw_history(case, &summary, run, dir, reference_name)? {
            plots.push(stem_name(&stem));
        }
    }
    if dim == 2 {
        for stem in draw_maps(case, &summary, &fields, dir)? {
            plots.push(stem_name(&stem));
        }
    }
    let written = Written {
        dir: dir.to_path_buf(),
        summary,
        plots,
    };
    let (md, html) = page(&written, case, run, reference_name);
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    write_atomic(&dir.join("index.html"), html.as_bytes())?;
    Ok(written)
}

/// Another finished run of the same case, drawn dashed along the probe lines.
struct ExtraRun<'a> {
    /// Its field at each output time of the report's run, when it has that time.
    by_output: Vec<Option<FieldRows>>,
    /// Its name in legends.
    name: &'a str,
}

impl<'a> ExtraRun<'a> {
    /// Reads the fields of the run in `dir` at the output times of `summary`.
    fn read(dir: &Path, name: &'a str, summary: &RunSummary) -> Result<ExtraRun<'a>> {
        let s = RunSummary::read(dir)?;
        let mut by_output = Vec::new();
        for t in &summary.output_times {
            by_output.push(match s.output_index(*t) {
                Some(k) => Some(s.read_field(dir, k)?),
                None => None,
            });
        }
        Ok(ExtraRun { by_output, name })
    }
}

/// What the temperature and error plots along the probe lines of a report draw.
struct LinePlots<'a> {
    summary: &'a RunSummary,
    /// The run's field at each output time.
    fields: &'a [FieldRows],
    extra: Option<&'a ExtraRun<'a>>,
    reference_name: &'a str,
    /// The report's directory.
    dir: &'a Path,
}

impl LinePlots<'_> {
    /// Draws the temperatures along `line` (and the difference to the reference, when the
    /// fields carry one); returns the stems drawn, none when no node lies on the line.
    fn draw(&self, line: &ProbeLine) -> Result<Vec<PathBuf>> {
        let reference_name = self.reference_name;
        let axis = ["x (m)", "y (m)", "z (m)"][line.along];
        let (temps, errors) = self.series(line);
        if temps.is_empty() {
            return Ok(Vec::new());
        }
        let mut stems = Vec::new();
        let stem = self.dir.join(format!("line_{}", line.slug()));
        line_plot(
            &stem,
            &Labels::new(
                format!("{}: temperature along {}", title(self.summary), line.name),
                axis,
                "Temperature (°C)",
            ),
            &temps,
            Legend::UpperLeft,
        )?;
        stems.push(stem);
        if !errors.is_empty() {
            let stem = self.dir.join(format!("error_{}", line.slug()));
            line_plot(
                &stem,
                &Labels::new(
                    format!("PD − {reference_name} along {}", line.name),
                    axis,
                    "Difference (°C)",
                ),
                &errors,
                Legend::UpperLeft,
            )?;
            stems.push(stem);
        }
        Ok(stems)
    }

    /// The temperature series along `line` (PD, the extra run, the reference at each output
    /// time) and the PD − reference series.
    fn series(&self, line: &ProbeLine) -> (Vec<Series>, Vec<Series>) {
        let reference_name = self.reference_name;
        let mut temps = Vec::new();
        let mut errors = Vec::new();
        for (k, (f, t)) in self
            .fields
            .iter()
            .zip(&self.summary.output_times)
            .enumerate()
        {
            let nodes = line.nodes(f);
            if nodes.is_empty() {
                continue;
            }
            let pd: Vec<(f64, f64)> = nodes.iter().map(|&(i, s)| (s, f.theta[i])).collect();
            temps.push(
                Series::new(format!("PD, t = {} s", number_label(*t)), pd)
                    .style(Style::Markers)
                    .colour(k),
            );
            if let Some(extra) = self.extra {
                if let Some(Some(e)) = extra.by_output.get(k) {
                    let p: Vec<(f64, f64)> = line
                        .nodes(e)
                        .iter()
                        .map(|&(i, s)| (s, e.theta[i]))
                        .collect();
                    if !p.is_empty() {
                        temps.push(
                            Series::new(format!("{}, t = {} s", extra.name, number_label(*t)), p)
                                .style(Style::Dashed)
                                .colour(k),
                        );
                    }
                }
            }
            if let Some(r) = &f.reference {
                let rf: Vec<(f64, f64)> = nodes.iter().map(|&(i, s)| (s, r[i])).collect();
                temps.push(
                    Series::new(format!("{reference_name}, t = {} s", number_label(*t)), rf)
                        .style(Style::Line)
                        .colour(k),
                );
                let e: Vec<(f64, f64)> =
                    nodes.iter().map(|&(i, s)| (s, f.theta[i] - r[i])).collect();
                errors.push(
                    Series::new(format!("t = {} s", number_label(*t)), e)
                        .style(Style::LineMarkers)
                        .colour(k),
                );
            }
        }
        (temps, errors)
    }
}

/// The settings table rows of a run: (setting, value).
fn settings(s: &RunSummary, case: &Case, run: &Path) -> Vec<(String, String)> {
    vec![
        ("case file".into(), s.case.clone()),
        ("run directory".into(), run.display().to_string()),
        ("body nodes".into(), s.nodes.to_string()),
        ("fictitious nodes".into(), s.fictitious_nodes.to_string()),
        ("directed bonds".into(), s.bonds.to_string()),
        ("kernel".into(), {
            let k = &case.spec.kernel;
            format!(
                "p = {}, {:?} profile, {:?} partial volumes, {:?} calibration",
                k.p, k.profile, k.partial_volume, k.calibration
            )
            .to_lowercase()
        }),
        ("integrator".into(), s.integrator.clone()),
        (
            "time step (s)".into(),
            format!("{:.4e} (stable bound {:.4e})", s.dt, s.dt_stable),
        ),
        ("steps".into(), s.steps.to_string()),
        (
            "set-up / run (s)".into(),
            format!(
                "{:.2} / {:.2} on {} threads",
                s.setup_seconds, s.wall_seconds, s.threads
            ),
        ),
        (
            "energy drift".into(),
            match s.energy.last() {
                Some(e) if s.initial_energy != 0.0 => {
                    format!("{:.3e} (relative, last output)", e / s.initial_energy - 1.0)
                }
                _ => "-".into(),
            },
        ),
    ]
}

/// Rows of the metrics table: (t, max abs diff, eq 45, eq 13, ε, probe).
fn metrics(s: &RunSummary) -> Vec<[String; 6]> {
    s.reference
        .iter()
        .map(|c| {
            [
                number_label(c.time),
                format!("{:.3e}", c.max_abs_diff),
                format!("{:.3e}", c.mean_sq_rel_diff),
                format!("{:.3e}", c.l2_rel_line),
                format!("{:.3e}", c.epsilon),
                c.probe
                    .as_ref()
                    .map(|p| format!("{:.4} / {:.4}", p.peridynamic, p.classical))
                    .unwrap_or_else(|| "-".into()),
            ]
        })
        .collect()
}

const METRIC_HEADER: [&str; 6] = [
    "t (s)",
    "max abs diff (°C)",
    "eq 45 (Bobaru & Duangpanya 2010)",
    "eq 13 (Bobaru & Duangpanya 2012)",
    "ε (eq 27, phase-change paper)",
    "probe PD / reference (°C)",
];

/// The Markdown and HTML pages of one report.
fn page(w: &Written, case: &Case, run: &Path, reference_name: &str) -> (String, String) {
    let s = &w.summary;
    let mut md = format!("# {}\n\n", title(s));
    let mut html = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{0}</title>\n<style>body{{font-family:sans-serif;max-width:1100px;margin:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:3px 8px}}img{{max-width:100%}}</style></head><body>\n<h1>{0}</h1>\n",
        escape(&title(s))
    );
    md.push_str("## Settings\n\n| setting | value |\n|---|---|\n");
    html.push_str("<h2>Settings</h2>\n<table>\n");
    for (k, v) in settings(s, case, run) {
        let _ = writeln!(md, "| {k} | {} |", v.replace('|', "\\|"));
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td>{}</td></tr>",
            escape(&k),
            escape(&v)
        );
    }
    html.push_str("</table>\n");
    let rows = metrics(s);
    if !rows.is_empty() {
        let _ = write!(
            md,
            "\n## Against the reference ({reference_name})\n\n| {} |\n|{}\n",
            METRIC_HEADER.join(" | "),
            "---|".repeat(6)
        );
        let _ = write!(
            html,
            "<h2>Against the reference ({})</h2>\n<table><tr>{}</tr>\n",
            escape(reference_name),
            METRIC_HEADER
                .iter()
                .map(|h| format!("<th>{}</th>", escape(h)))
                .collect::<String>()
        );
        for r in rows {
            let _ = writeln!(md, "| {} |", r.join(" | "));
            let _ = writeln!(
                html,
                "<tr>{}</tr>",
                r.iter()
                    .map(|c| format!("<td>{}</td>", escape(c)))
                    .collect::<String>()
            );
        }
        html.push_str("</table>\n");
    } else {
        md.push_str("\nThe case has no reference.\n");
        html.push_str("<p>The case has no reference.</p>\n");
    }
    if let Some(h) = &s.history {
        let (md_h, html_h) = history_table(h, reference_name);
        md.push_str(&md_h);
        html.push_str(&html_h);
    }
    md.push_str("\n## Plots\n\n");
    html.push_str("<h2>Plots</h2>\n");
    for p in &w.plots {
        let _ = writeln!(md, "![{p}]({p}.png)\n");
        let _ = writeln!(
            html,
            "<p><a href=\"{0}.svg\"><img src=\"{0}.png\" alt=\"{0}\"></a></p>",
            escape(p)
        );
    }
    html.push_str("</body></html>\n");
    (md, html)
}

/// The Markdown and HTML of the history's summary: per point, the node, the PD and reference
/// peaks, and the largest differences of the curves and of the normalised curves.
fn history_table(
    h: &peritherm_io::history::HistorySummary,
    reference_name: &str,
) -> (String, String) {
    const HEADER: [&str; 6] = [
        "node (m)",
        "PD peak (°C)",
        "at t (s)",
        "reference peak (°C)",
        "max abs diff (°C)",
        "max abs diff of T / T_max",
    ];
    let opt = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map(f).unwrap_or_else(|| "-".into());
    let mut md = format!(
        "\n## History ({} samples per point, `{}`; reference: {reference_name})\n\n| {} |\n|{}\n",
        h.samples,
        h.file,
        HEADER.join(" | "),
        "---|".repeat(6)
    );
    let mut html = format!(
        "<h2>History ({} samples per point; reference: {})</h2>\n<table><tr>{}</tr>\n",
        h.samples,
        escape(reference_name),
        HEADER
            .iter()
            .map(|c| format!("<th>{}</th>", escape(c)))
            .collect::<String>()
    );
    for p in &h.points {
        let row = [
            format!("({:.4e}, {:.4e}, {:.4e})", p.node[0], p.node[1], p.node[2]),
            format!("{:.5}", p.peak),
            format!("{:.4e}", p.peak_time),
            opt(p.reference_peak, &|v| format!("{v:.5}")),
            opt(p.max_abs_diff, &|v| format!("{v:.3e}")),
            opt(p.max_abs_diff_normalised, &|v| format!("{v:.3e}")),
        ];
        let _ = writeln!(md, "| {} |", row.join(" | "));
        let _ = writeln!(
            html,
            "<tr>{}</tr>",
            row.iter()
                .map(|c| format!("<td>{}</td>", escape(c)))
                .collect::<String>()
        );
    }
    html.push_str("</table>\n");
    (md, html)
}

/// One index over several reports (their directories relative to `dir`): a table of every
/// report's metrics and links to their pages.
pub fn write_index(dir: &Path, reports: &[Written]) -> Result<()> {
    let mut md = String::from("# peritherm reports\n\n| report | nodes | bonds | run (s) | t (s) | max abs diff (°C) | eq 13 | ε |\n|---|---|---|---|---|---|---|---|\n");
    let mut html = String::from("<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>peritherm reports</title>\n<style>body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px}</style></head><body>\n<h1>peritherm reports</h1>\n<table><tr><th>report</th><th>nodes</th><th>bonds</th><th>run (s)</th><th>t (s)</th><th>max abs diff (°C)</th><th>eq 13</th><th>ε</th></tr>\n");
    for w in reports {
        let rel = w
            .dir
            .strip_prefix(dir)
            .unwrap_or(&w.dir)
            .to_string_lossy()
            .into_owned();
        let s = &w.summary;
        let name = title(s);
        let mut rows: Vec<[String; 4]> = s
            .reference
            .iter()
            .map(|c| {
                [
                    number_label(c.time),
                    format!("{:.3e}", c.max_abs_diff),
                    format!("{:.3e}", c.l2_rel_line),
                    format!("{:.3e}", c.epsilon),
                ]
            })
            .collect();
        if rows.is_empty() {
            rows.push(["-".into(), "-".into(), "-".into(), "-".into()]);
        }
        for r in rows {
            let _ = writeln!(
                md,
                "| [{name}]({rel}/report.md) | {} | {} | {:.1} | {} |",
                s.nodes,
                s.bonds,
                s.setup_seconds + s.wall_seconds,
                r.join(" | ")
            );
            let _ = writeln!(
                html,
                "<tr><td><a href=\"{}/index.html\">{}</a></td><td>{}</td><td>{}</td><td>{:.1}</td>{}</tr>",
                escape(&rel),
                escape(&name),
                s.nodes,
                s.bonds,
                s.setup_seconds + s.wall_seconds,
                r.iter().map(|c| format!("<td>{}</td>", escape(c))).collect::<String>()
            );
        }
    }
    html.push_str("</table>\n</body></html>\n");
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    Ok(write_atomic(&dir.join("index.html"), html.as_bytes())?)
}

/// HTML-escapes text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
