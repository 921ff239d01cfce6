//! Sweeps: variants of cases (over the horizon factor, the spacing, the mesh ratio k, the
//! horizon ratio m, …) made by setting keys of the case file, run one after another, and
//! compared with a reference (theory §9): the case's own `[reference]`, another run, or
//! the first variant.

use crate::case::{Case, ReferenceSource};
use crate::cloud::Cloud;
use crate::crack::tips_at;
use crate::error::{IoError, Result};
use crate::model::crack_cutters;
use crate::output::{FieldRows, RunSummary};
use crate::plot::{convergence_plot, line_plot, Labels, Legend, Series, Style};
use crate::prepare::Options;
use crate::report::field_difference;
use crate::report::page::{probe_lines, ProbeLine};
use crate::run::run_case_with;
use std::path::{Path, PathBuf};

/// One `--vary KEY=V1,V2,…`: a dotted key of the case file and the values it takes.
#[derive(Debug, Clone, PartialEq)]
pub struct Vary {
    /// Dotted key; array items by index (`region.0.spacing`) or all of them (`region.*.spacing`).
    pub key: String,
    /// Values as TOML text (numbers, strings, inline arrays or tables).
    pub values: Vec<String>,
}

impl std::str::FromStr for Vary {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Vary, String> {
        let (key, values) = s
            .split_once('=')
            .ok_or_else(|| format!("`{s}`: expected KEY=V1,V2,..."))?;
        let values = split_values(values);
        if key.trim().is_empty() || values.iter().any(String::is_empty) || values.is_empty() {
            return Err(format!("`{s}`: expected KEY=V1,V2,... with no empty value"));
        }
        Ok(Vary {
            key: key.trim().to_string(),
            values,
        })
    }
}

/// Splits `a,b,[c,d],{e=1,f=2}` at the commas outside brackets and braces.
fn split_values(s: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth) = (Vec::new(), String::new(), 0i32);
    for ch in s.chars() {
        match ch {
            '[' | '{' => depth += 1,
            ']' | '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(ch);
    }
    out.push(cur.trim().to_string());
    out
}

/// A case with some keys set: its label, the settings and the validated case.
#[derive(Debug, Clone)]
pub struct Variant {
    /// Short name, also its output directory's name.
    pub label: String,
    /// The keys set, as (key, value text).
    pub settings: Vec<(String, String)>,
    /// The case with the settings applied (its path is the original file's).
    pub case: Case,
}

/// All variants of the case file `path` (text `text`): the Cartesian product of `vary`, in
/// order (the last key varies fastest). Labels start with `prefix`.
pub fn variants(text: &str, path: &Path, prefix: &str, vary: &[Vary]) -> Result<Vec<Variant>> {
    let err = |key: &str, message: String| IoError::Case {
        file: path.to_path_buf(),
        key: key.to_string(),
        message,
    };
    let base: toml::Table = toml::from_str(text).map_err(|e| {
        err(
            "-",
            format!("not a TOML table: {}", e.message().replace('\n', " ")),
        )
    })?;
    let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for v in vary {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                v.values.iter().map(move |x| {
                    let mut c = c.clone();
                    c.push((v.key.clone(), x.clone()));
                    c
                })
            })
            .collect();
    }
    combos
        .into_iter()
        .map(|settings| {
            let mut table = base.clone();
            for (key, value) in &settings {
                set(&mut table, key, value).map_err(|m| err(key, m))?;
            }
            let text = toml::to_string(&table).expect("a TOML table serialises");
            let case = Case::parse(&text, path).map_err(|e| match e {
                // line numbers of the rewritten text mean nothing to the user: name the settings
                IoError::Case { key, message, .. } => {
                    let set: Vec<String> =
                        settings.iter().map(|(k, v)| format!("{k}={v}")).collect();
                    let at = if key.starts_with("line ") {
                        String::new()
                    } else {
                        format!(" ({key})")
                    };
                    err(
                        &format!("--vary {}", set.join(" ")),
                        format!("{message}{at}"),
                    )
                }
                other => other,
            })?;
            let label = label(prefix, &settings);
            let mut case = case;
            case.settings = settings.iter().map(|(k, v)| format!("{k}={v}")).collect();
            Ok(Variant {
                label,
                settings,
                case,
            })
        })
        .collect()
}

/// The case file `path` with some keys set (`peritherm run --set KEY=VALUE`, one value each).
pub fn load_with(path: &Path, set: &[Vary]) -> Result<Case> {
    if set.is_empty() {
        return Ok(Case::load(path)?);
    }
    if let Some(v) = set.iter().find(|v| v.values.len() != 1) {
        return Err(IoError::Case {
            file: path.to_path_buf(),
            key: format!("--set {}", v.key),
            message: "takes one value (`peritherm sweep --vary` takes several)".into(),
        }
        .into());
    }
    let text = std::fs::read_to_string(path).map_err(|e| IoError::Case {
        file: path.to_path_buf(),
        key: "-".into(),
        message: format!("cannot read: {e}"),
    })?;
    let mut variants = variants(&text, path, "", set)?;
    Ok(variants.remove(0).case)
}

/// `prefix` plus `last-key-segment=value` for each setting, made safe for a directory name.
fn label(prefix: &str, settings: &[(String, String)]) -> String {
    let mut parts: Vec<String> = Vec::new();
    if !prefix.is_empty() {
        parts.push(prefix.to_string());
    }
    for (k, v) in settings {
        let short = k.rsplit('.').next().unwrap_or(k);
        parts.push(format!("{short}={v}"));
    }
    let raw = parts.join("_");
    raw.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._=-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Parses a value's TOML text; a bare word that is not TOML is a string. An integer where
/// the file has a float becomes a float.
fn parse_value(text: &str, old: Option<&toml::Value>) -> toml::Value {
    let parsed = toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(text.to_string()));
    match (parsed, old) {
        (toml::Value::Integer(i), Some(toml::Value::Float(_))) => toml::Value::Float(i as f64),
        (v, _) => v,
    }
}

/// Sets the dotted `key` of `table` to `value` (TOML text). Every segment but the last must
/// exist; `*` applies the rest of the key to every item of an array.
fn set(table: &mut toml::Table, key: &str, value: &str) -> std::result::Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let mut root = toml::Value::Table(std::mem::take(table));
    let r = set_in(&mut root, &parts, value, key);
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    r
}

fn set_in(
    node: &mut toml::Value,
    parts: &[&str],
    value: &str,
    key: &str,
) -> std::result::Result<(), String> {
    let missing = || format!("no such key in the case file (`{key}`)");
    let (head, rest) = parts.split_first().ok_or_else(missing)?;
    match node {
        toml::Value::Table(t) => {
            if rest.is_empty() {
                let v = parse_value(value, t.get(*head));
                t.insert(head.to_string(), v);
                return Ok(());
            }
            set_in(t.get_mut(*head).ok_or_else(missing)?, rest, value, key)
        }
        toml::Value::Array(items) => {
            let targets: Vec<usize> = if *head == "*" {
                (0..items.len()).collect()
            } else {
                vec![head.parse::<usize>().map_err(|_| missing())?]
            };
            for i in targets {
                let item = items.get_mut(i).ok_or_else(missing)?;
                if rest.is_empty() {
                    *item = parse_value(value, Some(item));
                } else {
                    set_in(item, rest, value, key)?;
                }
            }
            Ok(())
        }
        _ => Err(missing()),
    }
}

/// One row of a sweep's table: a variant at one output time.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Variant label.
    pub label: String,
    /// The keys set, as (key, value text).
    pub settings: Vec<(String, String)>,
    /// Body nodes.
    pub nodes: usize,
    /// Directed bonds.
    pub bonds: usize,
    /// Time steps.
    pub steps: u64,
    /// Seconds of set-up plus integration.
    pub wall_seconds: f64,
    /// Smallest horizon δ of the body, m.
    pub delta_min: f64,
    /// δ/Δ at the node with the smallest horizon.
    pub ratio: f64,
    /// Mean node spacing h = (Σ V_i / (τ N))^(1/d) over the N body nodes, m (τ the 2D
    /// thickness or 1D area; axisymmetric volumes carry their 2πr).
    pub h_mean: f64,
    /// Output time, s.
    pub time: f64,
    /// max |θ − θ_ref| over the body nodes compared, °C.
    pub max_abs: f64,
    /// Mean |θ − θ_ref| over the nodes compared, °C (field-to-field comparisons only).
    pub mean_abs: Option<f64>,
    /// Bobaru & Duangpanya 2012, eq. 13 along the case's probe line (classical references only).
    pub eq13: Option<f64>,
    /// PCS2022 (doi:10.1007/s42102-022-00092-3), eq. 27: rms difference
    /// / max |θ_ref| (the other run's field is the reference when comparing with a run).
    pub epsilon: Option<f64>,
    /// Volume-weighted relative L2 error over all body nodes, ‖θ − θ_ref‖/‖θ_ref‖
    /// (classical references only), dimensionless.
    pub l2_rel: Option<f64>,
    /// What it is compared with.
    pub against: String,
}

/// The CSV table of a sweep: one line per row, the varied keys as columns.
pub fn csv(rows: &[Row]) -> String {
    let keys: Vec<String> = rows
        .first()
        .map(|r| r.settings.iter().map(|(k, _)| k.clone()).collect())
        .unwrap_or_default();
    let opt = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
    let mut s = String::from("variant,");
    for k in &keys {
        s.push_str(k);
        s.push(',');
    }
    // h_mean and l2_rel come last: readers of the older columns by position keep working
    s.push_str("nodes,bonds,steps,wall_seconds,delta_min,ratio,time,max_abs,mean_abs,eq13,epsilon,against,h_mean,l2_rel\n");
    for r in rows {
        s.push_str(&r.label);
        s.push(',');
        for (_, v) in &r.settings {
            s.push_str(&v.replace(',', ";"));
            s.push(',');
        }
        s.push_str(&format!(
            "{},{},{},{:.3},{:e},{},{},{:e},{},{},{},{},{:e},{}\n",
            r.nodes,
            r.bonds,
            r.steps,
            r.wall_seconds,
            r.delta_min,
            r.ratio,
            r.time,
            r.max_abs,
            opt(r.mean_abs),
            opt(r.eq13),
            opt(r.epsilon),
            r.against,
            r.h_mean,
            opt(r.l2_rel)
        ));
    }
    s
}

/// The columns and cells of a sweep's table (the varied keys after the label).
pub fn cells(rows: &[Row]) -> (Vec<String>, Vec<Vec<String>>) {
    let keys = rows
        .first()
        .map(|r| r.settings.iter().map(|(k, _)| k.clone()));
    let mut columns = vec!["variant".to_string()];
    columns.extend(keys.into_iter().flatten());
    columns.extend(
        [
            "nodes",
            "bonds",
            "δ_min (m)",
            "δ/Δ",
            "h (m)",
            "wall (s)",
            "t (s)",
            "max abs diff (°C)",
            "mean abs diff (°C)",
            "eq 13",
            "ε (eq 27)",
            "rel. L2",
            "against",
        ]
        .map(String::from),
    );
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.3e}")).unwrap_or_else(|| "-".into());
    let row = |r: &Row| {
        let mut c = vec![r.label.clone()];
        c.extend(r.settings.iter().map(|(_, v)| v.clone()));
        c.extend([
            r.nodes.to_string(),
            r.bonds.to_string(),
            format!("{:.3e}", r.delta_min),
            format!("{:.3}", r.ratio),
            format!("{:.3e}", r.h_mean),
            format!("{:.1}", r.wall_seconds),
            r.time.to_string(),
            format!("{:.3e}", r.max_abs),
            opt(r.mean_abs),
            opt(r.eq13),
            opt(r.epsilon),
            opt(r.l2_rel),
            r.against.clone(),
        ]);
        c
    };
    (columns, rows.iter().map(row).collect())
}

/// The Markdown table of a sweep.
pub fn markdown(rows: &[Row]) -> String {
    let (columns, cells) = cells(rows);
    let mut s = format!(
        "| {} |\n|{}\n",
        columns.join(" | "),
        "---|".repeat(columns.len())
    );
    for row in cells {
        s.push_str(&format!("| {} |\n", row.join(" | ")));
    }
    s
}

/// The measures of a sweep's rows as JSON (sweep.json): per row its variant, time and the
/// differences from what it was compared with (null where not measured).
pub fn json(rows: &[Row]) -> String {
    let row = |r: &Row| {
        serde_json::json!({
            "variant": r.label,
            "time": r.time,
            "max_abs": r.max_abs,
            "mean_abs": r.mean_abs,
            "eq13": r.eq13,
            "epsilon": r.epsilon,
            "l2_rel": r.l2_rel,
        })
    };
    let rows: Vec<serde_json::Value> = rows.iter().map(row).collect();
    serde_json::to_string_pretty(&rows).expect("plain data serialises") + "\n"
}

/// What the variants of a sweep are compared with.
#[derive(Debug, Clone, PartialEq)]
pub enum Against {
    /// Each variant's own `[reference]` (all must have one).
    Reference,
    /// The fields of a finished run (e.g. a fine uniform PD run or `peritherm fem`).
    Run(PathBuf),
    /// The fields of the first variant.
    First,
}

impl Against {
    /// What the options ask for: a run directory (`--against`), the first variant
    /// (`--against-first`), or None to let [`study`] choose.
    pub fn chosen(run: Option<PathBuf>, first: bool) -> Option<Against> {
        match run {
            Some(dir) => Some(Against::Run(dir)),
            None => first.then_some(Against::First),
        }
    }
}

/// Runs every variant into `out/<label>/` and compares it with `against` at each of its
/// output times; nodes within `exclude_tips` (m) of a crack tip are left out of field-to-field
/// comparisons, each run with `options` (the memory budget and the weights cache, so variants
/// that share a cloud share its weights). `progress(k, label)` is called before variant k runs.
pub fn run(
    variants: &[Variant],
    out: &Path,
    against: &Against,
    exclude_tips: f64,
    options: &Options,
    mut progress: impl FnMut(usize, &str),
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for (k, v) in variants.iter().enumerate() {
        progress(k, &v.label);
        let done = VariantRun::run(v, out.join(&v.label), against, options)?;
        let reference_dir = match against {
            Against::Reference => {
                rows.extend(done.reference_rows()?);
                continue;
            }
            Against::Run(d) => d.clone(),
            Against::First => out.join(&variants[0].label),
        };
        rows.extend(done.field_rows(&reference_dir, exclude_tips)?);
    }
    Ok(rows)
}

/// A variant that has run: its summary, its bare cloud and the columns that all its rows
/// share.
struct VariantRun<'a> {
    variant: &'a Variant,
    /// Its output directory.
    dir: PathBuf,
    summary: RunSummary,
    cloud: Cloud,
    /// Its row with the time and the measures left blank.
    base: Row,
}

impl<'a> VariantRun<'a> {
    /// Runs `v` into `dir`; compared with a run (another or the first), a variant's own
    /// [reference.fem] (solved again for every variant, the measures not using it) is left out.
    fn run(
        v: &'a Variant,
        dir: PathBuf,
        against: &Against,
        options: &Options,
    ) -> Result<VariantRun<'a>> {
        let own_fem = v
            .case
            .reference
            .as_ref()
            .is_some_and(|r| matches!(r.source, ReferenceSource::Fem(_)));
        let summary = if own_fem && *against != Against::Reference {
            let mut case = v.case.clone();
            case.reference = None;
            run_case_with(&case, &dir, options, |_, _| {})?
        } else {
            run_case_with(&v.case, &dir, options, |_, _| {})?
        };
        let cloud = v.case.spec.geometry.bare_cloud()?;
        let measure: f64 = cloud.volume[..cloud.n_body].iter().sum::<f64>() / cloud.tau;
        let h_mean = (measure / cloud.n_body.max(1) as f64).powf(1.0 / cloud.dim as f64);
        let finest = (0..cloud.n_body)
            .min_by(|&a, &b| cloud.horizon[a].total_cmp(&cloud.horizon[b]))
            .unwrap_or(0);
        let base = Row {
            label: v.label.clone(),
            settings: v.settings.clone(),
            nodes: summary.nodes,
            bonds: summary.bonds,
            steps: summary.steps,
            wall_seconds: summary.setup_seconds + summary.wall_seconds,
            delta_min: cloud.horizon[finest],
            ratio: cloud.horizon[finest] / cloud.spacing[finest],
            h_mean,
            time: 0.0,
            max_abs: 0.0,
            mean_abs: None,
            eq13: None,
            epsilon: None,
            l2_rel: None,
            against: String::new(),
        };
        Ok(VariantRun {
            variant: v,
            dir,
            summary,
            cloud,
            base,
        })
    }

    /// The rows of the comparisons with the variant's own `[reference]`; an error without one.
    fn reference_rows(&self) -> Result<Vec<Row>> {
        if self.summary.reference.is_empty() {
            return Err(IoError::Case {
                file: self.variant.case.path.clone(),
                key: "reference".into(),
                message: "the case has no [reference]; give the sweep a run to compare with".into(),
            }
            .into());
        }
        Ok(self
            .summary
            .reference
            .iter()
            .map(|c| Row {
                time: c.time,
                max_abs: c.max_abs_diff,
                eq13: Some(c.l2_rel_line),
                epsilon: Some(c.epsilon),
                l2_rel: Some(c.l2_rel_volume),
                against: "reference".into(),
                ..self.base.clone()
            })
            .collect())
    }

    /// The rows of the field-to-field comparisons with the run in `reference_dir` at every
    /// output time, nodes within `exclude_tips` (m) of a crack tip left out.
    fn field_rows(&self, reference_dir: &Path, exclude_tips: f64) -> Result<Vec<Row>> {
        let (summary, cloud) = (&self.summary, &self.cloud);
        let reference = RunSummary::read(reference_dir)?;
        let cracks = crack_cutters(cloud, &self.variant.case.spec.cracks);
        let mut rows = Vec::new();
        for (i, t) in summary.output_times.iter().enumerate() {
            let Some(j) = reference.output_index(*t) else {
                return Err(IoError::Case {
                    file: reference_dir.join("run.json"),
                    key: "output_times".into(),
                    message: format!(
                        "has no output at t = {t} s, which {} writes",
                        self.variant.label
                    ),
                }
                .into());
            };
            let a = summary.read_field(&self.dir, i)?;
            let b = reference.read_field(reference_dir, j)?;
            let tips = tips_at(&cracks, *t);
            let d = field_difference(
                cloud.dim,
                (&a.pos, &a.theta),
                (&b.pos, &b.theta),
                &cracks,
                (&tips, exclude_tips),
            );
            rows.push(Row {
                time: *t,
                max_abs: d.max_abs,
                mean_abs: Some(d.mean_abs),
                epsilon: Some(d.epsilon()),
                against: reference_dir.display().to_string(),
                ..self.base.clone()
            });
        }
        Ok(rows)
    }
}

/// The last component of `path` as text.
fn file_name(path: &Path) -> String {
    path.file_name()
        .unwrap_or_default()
        .to_string_lossy()
        .into_owned()
}

/// The abscissa of a convergence plot: a row's value on it, if any.
type Axis = Box<dyn Fn(&Row) -> Option<f64>>;

/// The abscissae of the convergence plots: each varied key whose values are numbers, δ_min
/// unless a varied key is proportional to it, and the mean spacing h unless a varied key is
/// proportional to it (a spacing sweep).
fn plot_axes(rows: &[Row]) -> Vec<(String, Axis)> {
    let mut axes: Vec<(String, Axis)> = Vec::new();
    let keys: Vec<String> = rows
        .first()
        .map(|r| r.settings.iter().map(|(k, _)| k.clone()).collect())
        .unwrap_or_default();
    for (i, k) in keys.iter().enumerate() {
        axes.push((
            k.clone(),
            Box::new(move |r: &Row| r.settings[i].1.parse::<f64>().ok().filter(|v| *v > 0.0)),
        ));
    }
    // δ_min unless it is proportional to a varied key (the same plot again)
    let proportional = |i: usize| {
        let ratios: Vec<f64> = rows
            .iter()
            .filter_map(|r| Some(r.settings[i].1.parse::<f64>().ok()? / r.delta_min))
            .collect();
        ratios.len() == rows.len() && ratios.iter().all(|q| (q / ratios[0] - 1.0).abs() < 1e-9)
    };
    if !(0..keys.len()).any(proportional) {
        axes.push(("δ_min (m)".into(), Box::new(|r: &Row| Some(r.delta_min))));
    }
    // the mean spacing, unless a varied key is proportional to it (a spacing sweep)
    let follows_h = |i: usize| {
        let ratios: Vec<f64> = rows
            .iter()
            .filter_map(|r| Some(r.settings[i].1.parse::<f64>().ok()? / r.h_mean))
            .collect();
        ratios.len() == rows.len() && ratios.iter().all(|q| (q / ratios[0] - 1.0).abs() < 1e-6)
    };
    if !(0..keys.len()).any(follows_h) {
        axes.push((
            "h = (V/N)^(1/d) (m)".into(),
            Box::new(|r: &Row| Some(r.h_mean)),
        ));
    }
    axes
}

/// Convergence plots of a sweep into `out`, one per output time: the max difference (and
/// eq 13 and the relative L2 error where there are) against each axis of `plot_axes` along
/// which the rows differ, on log–log axes with fitted rates (Bobaru & Duangpanya 2010 Figs 10–12,
/// 2012 Figs 11–12). Returns the stems written and the fitted rates as (stem, series, rate).
pub fn convergence_plots(rows: &[Row], out: &Path) -> Result<Vec<(String, String, f64)>> {
    let axes = plot_axes(rows);
    let times = output_times(rows);
    let mut fitted = Vec::new();
    for (name, x) in &axes {
        for (k, t) in times.iter().enumerate() {
            let at: Vec<&Row> = rows.iter().filter(|r| r.time == *t).collect();
            let xs: Option<Vec<f64>> = at.iter().map(|r| x(r)).collect();
            let Some(xs) = xs else { continue };
            let mut distinct = xs.clone();
            distinct.sort_by(f64::total_cmp);
            distinct.dedup();
            if distinct.len() < 2 || distinct.len() != xs.len() {
                continue;
            }
            let mut series = vec![Series::new(
                "max abs diff (°C)",
                xs.iter().zip(&at).map(|(x, r)| (*x, r.max_abs)).collect(),
            )
            .colour(0)];
            if at.iter().all(|r| r.eq13.is_some_and(|e| e > 0.0)) {
                series.push(
                    Series::new(
                        "eq 13",
                        xs.iter()
                            .zip(&at)
                            .map(|(x, r)| (*x, r.eq13.unwrap_or(0.0)))
                            .collect(),
                    )
                    .colour(1),
                );
            }
            if at.iter().all(|r| r.l2_rel.is_some_and(|e| e > 0.0)) {
                series.push(
                    Series::new(
                        "relative L2",
                        xs.iter()
                            .zip(&at)
                            .map(|(x, r)| (*x, r.l2_rel.unwrap_or(0.0)))
                            .collect(),
                    )
                    .colour(2),
                );
            }
            series.retain(|s| s.points.iter().all(|p| p.1 > 0.0));
            if series.is_empty() {
                continue;
            }
            let short = name.rsplit('.').next().unwrap_or(name);
            let slug: String = if short.starts_with('δ') {
                "delta".into()
            } else if short.starts_with("h = ") {
                "h".into()
            } else {
                short
                    .chars()
                    .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                    .collect()
            };
            let stem = out.join(format!("convergence_{slug}_t{}", k + 1));
            let laws = convergence_plot(
                &stem,
                &Labels::new(
                    format!("Convergence at t = {t} s"),
                    name.clone(),
                    "difference",
                ),
                &series,
                Legend::LowerRight,
            )?;
            let stem = file_name(&stem);
            for (s, law) in series.iter().zip(laws) {
                fitted.push((stem.clone(), s.name.clone(), law.rate));
            }
        }
    }
    Ok(fitted)
}

/// One line plot per output time and probe line with every variant's PD temperatures
/// (markers) and the reference (a line: the first variant's reference column, or the run
/// compared with), into `out/lines_<line>_t<k>` (Wang, Oterkus & Oterkus Figs 5–25: PD for several
/// configurations against FEM). Returns the stems written.
pub fn line_plots(
    variants: &[Variant],
    rows: &[Row],
    out: &Path,
    against: &Against,
) -> Result<Vec<String>> {
    let Some(first) = variants.first() else {
        return Ok(Vec::new());
    };
    let dim = first.case.spec.geometry.bare_cloud()?.dim;
    let mut stems = Vec::new();
    let reference_run = match against {
        Against::Run(d) => Some((d.clone(), RunSummary::read(d)?)),
        _ => None,
    };
    for (k, t) in output_times(rows).iter().enumerate() {
        let mut per_variant = Vec::new();
        for v in variants {
            let dir = out.join(&v.label);
            let s = RunSummary::read(&dir)?;
            if let Some(i) = s.output_index(*t) {
                per_variant.push((v, s.read_field(&dir, i)?));
            }
        }
        let Some((v0, f0)) = per_variant.first() else {
            continue;
        };
        let reference = match &reference_run {
            Some((d, s)) => s.output_index(*t).map(|i| s.read_field(d, i)).transpose()?,
            None => None,
        };
        let at = LinesAt {
            per_variant: &per_variant,
            reference: reference.as_ref(),
            out,
            k,
            t: *t,
        };
        for line in probe_lines(&v0.case, f0, dim) {
            stems.extend(at.draw(&line)?);
        }
    }
    Ok(stems)
}

/// The distinct output times of the rows of a sweep, in increasing order, s.
fn output_times(rows: &[Row]) -> Vec<f64> {
    let mut times: Vec<f64> = rows.iter().map(|r| r.time).collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    times
}

/// The fields of a sweep's variants at one output time, for its line plots.
struct LinesAt<'a> {
    /// Every variant that has this output, with its field.
    per_variant: &'a [(&'a Variant, FieldRows)],
    /// The field of the run compared with at this time, if any.
    reference: Option<&'a FieldRows>,
    out: &'a Path,
    /// Index of the output time (from 0).
    k: usize,
    /// The output time, s.
    t: f64,
}

impl LinesAt<'_> {
    /// Draws the temperatures (and the differences to each variant's reference, when there
    /// are) along `line`; returns the stems written.
    fn draw(&self, line: &ProbeLine) -> Result<Vec<String>> {
        let (k, t) = (self.k, self.t);
        let (series, diffs) = self.series(line);
        if series.is_empty() {
            return Ok(Vec::new());
        }
        let mut stems = Vec::new();
        if !diffs.is_empty() {
            let stem = self
                .out
                .join(format!("differences_{}_t{}", line.slug(), k + 1));
            line_plot(
                &stem,
                &Labels::new(
                    format!("PD − reference along {} at t = {t} s", line.name),
                    ["x (m)", "y (m)", "z (m)"][line.along],
                    "Difference (°C)",
                ),
                &diffs,
                Legend::UpperLeft,
            )?;
            stems.push(file_name(&stem));
        }
        let stem = self.out.join(format!("lines_{}_t{}", line.slug(), k + 1));
        line_plot(
            &stem,
            &Labels::new(
                format!("Temperature along {} at t = {t} s", line.name),
                ["x (m)", "y (m)", "z (m)"][line.along],
                "Temperature (°C)",
            ),
            &series,
            Legend::UpperLeft,
        )?;
        stems.push(file_name(&stem));
        Ok(stems)
    }

    /// The temperature series along `line` (the reference first, then every variant) and
    /// the PD − reference series of the variants that carry a reference.
    fn series(&self, line: &ProbeLine) -> (Vec<Series>, Vec<Series>) {
        let mut series = Vec::new();
        let (_, f0) = &self.per_variant[0];
        let reference_points = match (self.reference, &f0.reference) {
            (Some(r), _) => Some(
                line.nodes(r)
                    .iter()
                    .map(|&(i, s)| (s, r.theta[i]))
                    .collect::<Vec<_>>(),
            ),
            (None, Some(rv)) => Some(line.nodes(f0).iter().map(|&(i, s)| (s, rv[i])).collect()),
            _ => None,
        };
        if let Some(p) = reference_points.filter(|p| !p.is_empty()) {
            series.push(Series::new("reference", p).style(Style::Line).colour(7));
        }
        let mut diffs = Vec::new();
        for (c, (v, f)) in self.per_variant.iter().enumerate() {
            // colour 7 is the reference's
            let colour = if c >= 7 { c + 1 } else { c };
            if let Some(r) = &f.reference {
                let d: Vec<(f64, f64)> = line
                    .nodes(f)
                    .iter()
                    .map(|&(i, s)| (s, f.theta[i] - r[i]))
                    .collect();
                if !d.is_empty() {
                    diffs.push(
                        Series::new(v.label.clone(), d)
                            .style(Style::LineMarkers)
                            .colour(colour),
                    );
                }
            }
            let p: Vec<(f64, f64)> = line
                .nodes(f)
                .iter()
                .map(|&(i, s)| (s, f.theta[i]))
                .collect();
            if !p.is_empty() {
                series.push(
                    Series::new(v.label.clone(), p)
                        .style(Style::Markers)
                        .colour(colour),
                );
            }
        }
        (series, diffs)
    }
}

/// The variants of a study and what they are compared with: every file of `cases` swept over
/// `vary` (labels prefixed with the file's stem when several files are compared), compared as
/// `against` says, else with each variant's own reference when every variant has one, else
/// with the first variant. What `peritherm sweep` and the Python `sweep` run.
pub fn study(
    cases: &[PathBuf],
    vary: &[Vary],
    against: Option<Against>,
) -> Result<(Vec<Variant>, Against)> {
    let mut all = Vec::new();
    for path in cases {
        let text = std::fs::read_to_string(path).map_err(|error| IoError::Io {
            path: path.clone(),
            error,
        })?;
        let prefix = if cases.len() > 1 {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        } else {
            String::new()
        };
        let mut v = variants(&text, path, &prefix, vary)?;
        if v.len() == 1 && v[0].label.is_empty() {
            v[0].label = "run".into();
        }
        all.extend(v);
    }
    let against = match against {
        Some(a) => a,
        None if all.iter().all(|v| v.case.reference.is_some()) => Against::Reference,
        None => Against::First,
    };
    Ok((all, against))
}

/// Writes a finished study into `out`: sweep.csv (one row per variant and output time),
/// sweep.json (its measures) and sweep.md (the table, the fitted convergence rates and the plots, which it draws); returns
/// the Markdown and the CSV text.
pub fn write_study(
    variants: &[Variant],
    rows: &[Row],
    out: &Path,
    against: &Against,
) -> Result<(String, String)> {
    let mut table = markdown(rows);
    let rates = convergence_plots(rows, out)?;
    let lines = line_plots(variants, rows, out, against)?;
    if !rates.is_empty() {
        table.push_str("\n| plot | measure | fitted rate |\n|---|---|---|\n");
        for (stem, series, rate) in &rates {
            table.push_str(&format!("| {stem} | {series} | {rate:.3} |\n"));
        }
    }
    let mut plots: Vec<&String> = rates.iter().map(|r| &r.0).collect();
    plots.dedup();
    plots.extend(lines.iter());
    if !plots.is_empty() {
        table.push('\n');
        for p in plots {
            table.push_str(&format!("![{p}]({p}.png)\n\n"));
        }
    }
    let csv = csv(rows);
    crate::atomic::write_atomic(&out.join("sweep.csv"), csv.as_bytes())?;
    crate::atomic::write_atomic(&out.join("sweep.md"), table.as_bytes())?;
    crate::atomic::write_atomic(&out.join("sweep.json"), json(rows).as_bytes())?;
    Ok((table, csv))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CASE: &str = r#"
dimension = 1
[domain]
min = [0.0]
max = [1.0]
[[region]]
name = "bar"
cells = [20]
horizon = { factor = 3.0 }
[material.m]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[time]
end = 0.01
"#;

    /// `--vary` splits at top-level commas only and refuses empty values.
    #[test]
    fn parses_vary() {
        let v: Vary = "region.0.cells=[10],[20]".parse().unwrap();
        assert_eq!(v.key, "region.0.cells");
        assert_eq!(v.values, vec!["[10]", "[20]"]);
        assert!("region.0.cells".parse::<Vary>().is_err());
        assert!("k=1,,2".parse::<Vary>().is_err());
    }

    /// The product of two keys gives four cases with the values set (an integer for a float
    /// key becomes a float); a key that is not in the file is an error naming it.
    #[test]
    fn makes_the_product() {
        let vary: Vec<Vary> = vec![
            "region.*.horizon.factor=2,4".parse().unwrap(),
            "region.0.cells=[10],[40]".parse().unwrap(),
        ];
        let v = variants(CASE, Path::new("bar.toml"), "", &vary).unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(v[1].label, "factor=2_cells=_40_");
        let set = ["region.*.horizon.factor=2", "region.0.cells=[40]"];
        assert_eq!(v[1].case.settings, set, "run.json lists the keys set");
        let cloud = v[1].case.spec.geometry.bare_cloud().unwrap();
        assert_eq!(cloud.n_body, 40);
        assert!((cloud.horizon[0] / cloud.spacing[0] - 2.0).abs() < 1e-12);
        let bad: Vec<Vary> = vec!["region.0.horizon.nope.x=1".parse().unwrap()];
        let e = variants(CASE, Path::new("bar.toml"), "", &bad)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bar.toml: region.0.horizon.nope.x: no such key"),
            "{e}"
        );
    }
}
