//! The `peritherm` command line.

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use peritherm::case::Case;
use peritherm::model::{crack_cutters, Model};
use peritherm::output::read_field;
use peritherm::output::RunSummary;
use peritherm::report::field_difference;
use peritherm::run::run_case;
use peritherm::solve::explicit::choose_dt;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "peritherm",
    version,
    about = "Transient heat conduction with dual-horizon peridynamics"
)]
struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case and write field_<k>.csv and run.json into --out.
    Run {
        /// The case file (TOML).
        case: PathBuf,
        /// Output directory (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Print a Markdown table comparing finished runs with their references.
    Table {
        /// Output directories of `peritherm run`.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
    },
    /// Compare the fields of a run with those of a reference run of the same body (e.g. a
    /// refined mesh against a uniform fine one), output time by output time.
    Compare {
        /// Output directory of the run to judge.
        run: PathBuf,
        /// Output directory of the reference run.
        reference: PathBuf,
        /// Leave out the nodes within this distance (m) of a crack tip (e.g. 2δ).
        #[arg(long, value_name = "RADIUS", default_value_t = 0.0)]
        exclude_tips: f64,
    },
    /// Draw a temperature map (PNG) of every output of a 2D run, cracks included, into the
    /// run's directory as map_<k>.png.
    Plot {
        /// Output directory of `peritherm run`.
        run: PathBuf,
    },
    /// Run variants of one or more cases and compare each with a reference: writes every run
    /// into --out/<variant>/, and sweep.csv and sweep.md (one row per variant and output time).
    Sweep {
        /// Case files (each is swept over the --vary values; several files are compared as
        /// one study, e.g. the four (k, m) configurations of seed 004).
        #[arg(required = true)]
        cases: Vec<PathBuf>,
        /// KEY=V1,V2,...: a dotted key of the case file and its values (array items by index,
        /// or `*` for all: `region.*.horizon.factor=2,3,4,5`). Repeat for a product.
        #[arg(long)]
        vary: Vec<peritherm::sweep::Vary>,
        /// Output directory (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Compare with this finished run's fields instead of the cases' own [reference] (the
        /// default when every case has one; otherwise the first variant).
        #[arg(long, value_name = "RUN_DIR")]
        against: Option<PathBuf>,
        /// Leave out the nodes within this distance (m) of a crack tip in field comparisons.
        #[arg(long, value_name = "RADIUS", default_value_t = 0.0)]
        exclude_tips: f64,
    },
    /// Validate a case and print its size and stable time step without running it.
    Check {
        /// The case file (TOML).
        case: PathBuf,
    },
}

/// Prints a line to stdout; a closed pipe (e.g. `| head`) ends the output quietly.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(cli: Cli) -> anyhow::Result<()> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("--threads")?;
    }
    match cli.command {
        Command::Run { case, out, quiet } => {
            let case = Case::load(&case)?;
            let bar = ProgressBar::new(0);
            if quiet || !std::io::stderr().is_terminal() {
                bar.set_draw_target(ProgressDrawTarget::hidden());
            }
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:40} {pos}/{len} steps  {elapsed_precise} eta {eta}",
                )
                .expect("valid template"),
            );
            let summary = run_case(&case, &out, |done, total| {
                bar.set_length(total);
                bar.set_position(done);
            })?;
            bar.finish_and_clear();
            say!(
                "{}: {} nodes, {} bonds, {} steps of {:.3e} s in {:.2} s -> {}",
                case.path.display(),
                summary.nodes,
                summary.bonds,
                summary.steps,
                summary.dt,
                summary.wall_seconds,
                out.display()
            );
            for c in &summary.reference {
                say!(
                    "  t = {:<8} max|diff| = {:.4e}  eq45 = {:.4e}  eq13 = {:.4e}",
                    c.time,
                    c.max_abs_diff,
                    c.mean_sq_rel_diff,
                    c.l2_rel_line
                );
            }
            Ok(())
        }
        Command::Table { runs } => {
            say!("{}", RunSummary::table_header());
            for dir in runs {
                for row in RunSummary::read(&dir)?.table_rows() {
                    say!("{row}");
                }
            }
            Ok(())
        }
        Command::Compare {
            run,
            reference,
            exclude_tips,
        } => compare(&run, &reference, exclude_tips),
        Command::Plot { run } => plot(&run),
        Command::Sweep {
            cases,
            vary,
            out,
            against,
            exclude_tips,
        } => sweep(&cases, &vary, &out, against, exclude_tips),
        Command::Check { case } => {
            let case = Case::load(&case)?;
            let model =
                Model::build(&case.spec).with_context(|| case.path.display().to_string())?;
            let bound = case.integrator.stable_dt(&model);
            if case.integrator.is_implicit() {
                say!(
                    "{}: {} body nodes, {} fictitious, {} directed bonds, {}: no stability bound (explicit Euler's would be {:.4e} s)",
                    case.path.display(),
                    model.cloud.n_body,
                    model.cloud.n_fictitious(),
                    model.horizons.n_bonds(),
                    case.integrator.name(),
                    peritherm::solve::explicit::Integrator::Euler.stable_dt(&model)
                );
                if let Err(e) = peritherm::solve::implicit::System::build(&model) {
                    anyhow::bail!("{}: {e}", case.path.display());
                }
            } else {
                say!(
                    "{}: {} body nodes, {} fictitious, {} directed bonds, stable dt ({}) = {:.4e} s",
                    case.path.display(),
                    model.cloud.n_body,
                    model.cloud.n_fictitious(),
                    model.horizons.n_bonds(),
                    case.integrator.name(),
                    bound
                );
            }
            match choose_dt(&model, case.integrator, case.dt) {
                Err(peritherm::Error::Model { key, message }) => {
                    anyhow::bail!("{}: {key}: {message}", case.path.display())
                }
                Err(e) => anyhow::bail!("{}: time.dt: {e}", case.path.display()),
                Ok(_) => {}
            }
            Ok(())
        }
    }
}

/// `peritherm compare`: max and mean |Δθ| per output time, the reference interpolated at the
/// run's nodes without looking across the run's cracks; nodes within `exclude_tips` (m) of a
/// crack tip are left out.
fn compare(
    run: &std::path::Path,
    reference: &std::path::Path,
    exclude_tips: f64,
) -> anyhow::Result<()> {
    let a = RunSummary::read(run)?;
    let b = RunSummary::read(reference)?;
    let case = Case::load(std::path::Path::new(&a.case))?;
    let cloud = case
        .spec
        .geometry
        .bare_cloud()
        .with_context(|| case.path.display().to_string())?;
    let cracks = crack_cutters(&cloud, &case.spec.cracks);
    say!("| run | nodes | bonds | steps | set-up (s) | wall (s) |");
    say!("|---|---|---|---|---|---|");
    for s in [&a, &b] {
        say!(
            "| {} | {} | {} | {} | {:.1} | {:.1} |",
            s.case,
            s.nodes,
            s.bonds,
            s.steps,
            s.setup_seconds,
            s.wall_seconds
        );
    }
    say!();
    say!("| t (s) | max abs diff (°C) | mean abs diff (°C) | where (m) |");
    say!("|---|---|---|---|");
    for (k, t) in a.output_times.iter().enumerate() {
        let Some(kb) = b
            .output_times
            .iter()
            .position(|tb| (tb - t).abs() <= 1e-9 * t.abs())
        else {
            anyhow::bail!("{}: has no output at t = {t} s", reference.display());
        };
        let fa = read_field(&run.join(&a.fields[k]))?;
        let fb = read_field(&reference.join(&b.fields[kb]))?;
        let tips = peritherm::crack::tips_at(&cracks, *t);
        let d = field_difference(
            cloud.dim,
            (&fa.pos, &fa.theta),
            (&fb.pos, &fb.theta),
            &cracks,
            (&tips, exclude_tips),
        );
        say!(
            "| {t} | {:.3e} | {:.3e} | ({:.4e}, {:.4e}, {:.4e}) |",
            d.max_abs,
            d.mean_abs,
            d.at.x,
            d.at.y,
            d.at.z
        );
    }
    Ok(())
}

/// `peritherm sweep`: the variants of every case, run and compared; the table printed and
/// written as sweep.csv and sweep.md.
fn sweep(
    cases: &[PathBuf],
    vary: &[peritherm::sweep::Vary],
    out: &std::path::Path,
    against: Option<PathBuf>,
    exclude_tips: f64,
) -> anyhow::Result<()> {
    use peritherm::sweep::{self, Against};
    let mut variants = Vec::new();
    for path in cases {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let prefix = if cases.len() > 1 {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        } else {
            String::new()
        };
        let mut v = sweep::variants(&text, path, &prefix, vary)?;
        if v.len() == 1 && v[0].label.is_empty() {
            v[0].label = "run".into();
        }
        variants.extend(v);
    }
    let against = match against {
        Some(dir) => Against::Run(dir),
        None if variants.iter().all(|v| v.case.reference.is_some()) => Against::Reference,
        None => Against::First,
    };
    let n = variants.len();
    let rows = sweep::run(&variants, out, &against, exclude_tips, |k, label| {
        eprintln!("[{}/{n}] {label}", k + 1);
    })?;
    let table = sweep::markdown(&rows);
    peritherm::output::write_atomic(&out.join("sweep.csv"), sweep::csv(&rows).as_bytes())?;
    peritherm::output::write_atomic(&out.join("sweep.md"), table.as_bytes())?;
    say!("{table}");
    say!("-> {}", out.join("sweep.csv").display());
    Ok(())
}

/// `peritherm plot`: one temperature map per output, on a colour range shared by all of them.
fn plot(run: &std::path::Path) -> anyhow::Result<()> {
    let summary = RunSummary::read(run)?;
    let case = Case::load(std::path::Path::new(&summary.case))?;
    if case.spec.geometry.bare_cloud()?.dim != 2 {
        anyhow::bail!(
            "{}: maps are drawn for 2D runs; open the field_<k>.vtu files in ParaView",
            run.display()
        );
    }
    let cloud = case.spec.geometry.bare_cloud()?;
    let cutters = crack_cutters(&cloud, &case.spec.cracks);
    let fields = summary
        .fields
        .iter()
        .map(|f| read_field(&run.join(f)))
        .collect::<Result<Vec<_>, _>>()?;
    let (lo, hi) = fields
        .iter()
        .flat_map(|f| f.theta.iter())
        .fold((f64::MAX, f64::MIN), |(a, b), &t| (a.min(t), b.max(t)));
    for (k, (f, t)) in fields.iter().zip(&summary.output_times).enumerate() {
        let path = run.join(format!("map_{}.png", k + 1));
        let cracks = peritherm::crack::segments_at(&cutters, *t);
        peritherm::plot::temperature_map(&path, &f.pos, &f.theta, &f.spacing, (lo, hi), &cracks)?;
        say!(
            "t = {t} s: {} (blue {lo:.2} °C … white … red {hi:.2} °C)",
            path.display()
        );
    }
    Ok(())
}
