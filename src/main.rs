//! The `peritherm` command line.

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use peritherm::case::Case;
use peritherm::fem::{run_fem, FemOptions, Scheme};
use peritherm::model::crack_cutters;
use peritherm::output::RunSummary;
use peritherm::report::field_difference;
use peritherm::run::{run_case, run_case_with};
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
    /// Memory a run may plan to use, e.g. 8G or 512M (default: 80% of the machine's
    /// available memory); a case estimated above it is refused before it is built.
    #[arg(long, global = true, value_parser = peritherm::budget::parse_bytes)]
    max_memory: Option<f64>,
    /// Directory of the cache of consistent bond weights, or `off` (default:
    /// $PERITHERM_CACHE, else ~/.cache/peritherm/weights): a run that changes nothing the
    /// weights depend on loads them instead of computing them again.
    #[arg(long, global = true, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Largest size of the weights cache, e.g. 2G (default: $PERITHERM_CACHE_SIZE, else 4G);
    /// the least recently used entries go first.
    #[arg(long, global = true, value_name = "BYTES", value_parser = peritherm::budget::parse_bytes)]
    cache_size: Option<f64>,
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
        /// Set a key of the case before running, as KEY=VALUE (the keys and values of
        /// `sweep --vary`, one value), e.g. `--set time.end=0.5`; repeatable.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<peritherm::sweep::Vary>,
    },
    /// Solve a case with the built-in classical FEM reference and write the same outputs as
    /// `run` (field_<k>.csv, field_<k>.vtu, run.json) into --out.
    Fem {
        /// The case file (TOML).
        case: PathBuf,
        /// Output directory (created if missing).
        #[arg(long, short)]
        out: PathBuf,
        /// Element size of the structured mesh of a box case, m (default: the finest region
        /// spacing); a gmsh case uses its own mesh.
        #[arg(long)]
        h: Option<f64>,
        /// Time scheme (Crank–Nicolson starts with four backward-Euler half steps).
        #[arg(long, value_parser = parse_scheme, default_value = "crank-nicolson")]
        scheme: Scheme,
        /// Time step, s (default: min(end/1000, first output/100)).
        #[arg(long)]
        dt: Option<f64>,
        /// No progress bar.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Print a Markdown table comparing finished runs with their references.
    Table {
        /// Output directories of `peritherm run`.
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Also write the table, the commit and machine it was measured on, and the checks a
        /// rerun must pass, into this figure file (e.g. validation/accuracy.json).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// The command that measured the runs, recorded in the figure file.
        #[arg(long, default_value = "peritherm table")]
        command: String,
        /// The table of the runs' fields (thermal energy and a hash of each field file) instead
        /// of the accuracy against their references.
        #[arg(long)]
        fields: bool,
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
    /// Draw temperature maps (PNG and SVG) of every output of a 2D run, cracks included, into
    /// the run's directory as map_<k>.png/.svg, and damage_<k>.png/.svg for runs with cracks.
    Plot {
        /// Output directory of `peritherm run`.
        run: PathBuf,
    },
    /// Run variants of one or more cases and compare each with a reference: writes every run
    /// into --out/<variant>/, and sweep.csv and sweep.md (one row per variant and output time).
    Sweep {
        /// Case files (each is swept over the --vary values; several files are compared as
        /// one study, e.g. the four (k, m) configurations of Wang, Oterkus & Oterkus).
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
        /// Compare with the first variant's fields even when the cases have their own
        /// [reference] (e.g. a refined mesh against the uniform fine run named first).
        #[arg(long, conflicts_with = "against")]
        against_first: bool,
        /// Leave out the nodes within this distance (m) of a crack tip in field comparisons.
        #[arg(long, value_name = "RADIUS", default_value_t = 0.0)]
        exclude_tips: f64,
        /// Also write the table, the commit and machine, and the checks a rerun must pass into
        /// this figure file (e.g. validation/bar_delta.json).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// The command that measured the sweep, recorded in the figure file.
        #[arg(long, default_value = "peritherm sweep")]
        command: String,
    },
    /// Run cases and write reports: plots of PD against the reference along the probe lines,
    /// the error along them, temperature/damage/flux maps, report.md and index.html.
    Report {
        /// Case files, or directories of case files.
        #[arg(required = true)]
        cases: Vec<PathBuf>,
        /// Output directory: one subdirectory per case, and an index over several.
        #[arg(long, short)]
        out: PathBuf,
        /// Also solve each case with the built-in FEM (into <case>/fem/) and draw it along the
        /// probe lines beside the case's own reference.
        #[arg(long)]
        fem: bool,
        /// No progress lines.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Measure the explicit step against the memory bandwidth (STREAM-like triad), the
    /// neighbour search and assembly, and the bytes per bond; print Markdown tables.
    Bench {
        /// Small problems and few repetitions (a smoke run, not a measurement).
        #[arg(long)]
        quick: bool,
        /// Only the 2D m = 3 plate with about this many nodes (e.g. 1e7).
        #[arg(long, value_parser = parse_count)]
        nodes: Option<usize>,
        /// Also run and time the explicit and implicit crack plate and thermal shock (from the
        /// repository root; minutes), writing their outputs into this directory.
        #[arg(long, value_name = "OUT_DIR")]
        cases: Option<PathBuf>,
        /// Also write each table as a figure file bench_<table>.json into this directory (e.g.
        /// validation/), with the commit and machine.
        #[arg(long, value_name = "DIR")]
        json: Option<PathBuf>,
        /// The command that ran the measurement, recorded in the figure files.
        #[arg(long, default_value = "peritherm bench")]
        command: String,
    },
    /// Validate a case and print its size and stable time step without running it.
    Check {
        /// The case file (TOML).
        case: PathBuf,
    },
    /// Print what each of N MPI ranks would hold and exchange in a run of a case (nodes,
    /// ghosts, bonds, memory, halo bytes) and a time per step from a latency–bandwidth model,
    /// without running it (docs/distributed.md).
    Partition(PartitionArgs),
}

/// The arguments of `peritherm partition`.
#[derive(clap::Args)]
struct PartitionArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// Rank counts, comma-separated (e.g. 1,64,4096).
    #[arg(long, value_delimiter = ',', required = true, value_parser = clap::value_parser!(u32).range(1..=1_048_576))]
    ranks: Vec<u32>,
    /// Memory bandwidth of one rank (its share of a node's), GB/s.
    #[arg(long, default_value_t = 5.0, value_parser = parse_positive)]
    bandwidth: f64,
    /// Latency of a message between ranks, µs.
    #[arg(long, default_value_t = 2.0, value_parser = parse_positive)]
    latency: f64,
    /// Bandwidth of the link between ranks, GB/s.
    #[arg(long, default_value_t = 12.5, value_parser = parse_positive)]
    link: f64,
    /// Also write the plan as partition.json into this directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also write the table, the commit and machine, and the check a rerun must pass into
    /// this figure file (e.g. validation/partition_cube.json).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// The command that planned it, recorded in the figure file.
    #[arg(long, default_value = "peritherm partition")]
    command: String,
}

/// Parses a finite positive number of a model parameter.
fn parse_positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("`{s}` is not a finite positive number")),
    }
}

/// Parses a time scheme of `peritherm fem` by its run.json name ([`Scheme::from_name`]).
fn parse_scheme(s: &str) -> Result<Scheme, String> {
    Scheme::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = Scheme::ALL.iter().map(|s| s.name()).collect();
        format!("`{s}` is not one of {}", names.join(", "))
    })
}

/// Parses a count such as `1000000` or `1e7`.
fn parse_count(s: &str) -> Result<usize, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v >= 1.0 {
        Ok(v.round() as usize)
    } else {
        Err(format!("`{s}` is not a positive count"))
    }
}

/// Prints a line to stdout; a closed pipe (e.g. `| head`) ends the output quietly.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// Set on the ranks of a distributed run other than 0: rank 0 reports the error.
static SILENT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn main() -> ExitCode {
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(_) if SILENT.load(std::sync::atomic::Ordering::Relaxed) => ExitCode::FAILURE,
        Err(e) => {
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

fn real_main(cli: Cli) -> anyhow::Result<()> {
    // SIGINT/SIGTERM: the run under way leaves a run.json saying so and no partial file
    ctrlc::set_handler(|| peritherm::staging::interrupt()).context("signal handler")?;
    let cache =
        peritherm::weights_cache::WeightsCache::configured(cli.cache.as_deref(), cli.cache_size)
            .map_err(anyhow::Error::msg)?;
    let options = peritherm::prepare::Options {
        max_memory: cli.max_memory,
        cache,
    };
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("--threads")?;
    }
    dispatch(cli.command, &options, cli.threads)
}

/// Runs the subcommand `command` with the run options and the worker threads asked for.
fn dispatch(
    command: Command,
    options: &peritherm::prepare::Options,
    threads: Option<usize>,
) -> anyhow::Result<()> {
    match command {
        Command::Run {
            case,
            out,
            quiet,
            set,
        } => run(&case, &set, &out, quiet, options),
        Command::Fem {
            case,
            out,
            h,
            scheme,
            dt,
            quiet,
        } => fem(&case, &out, &fem_options(h, scheme, dt), quiet),
        Command::Table {
            runs,
            json,
            command,
            fields,
        } => table(&runs, json.as_deref(), fields, &command),
        Command::Compare {
            run,
            reference,
            exclude_tips,
        } => compare(&run, &reference, exclude_tips),
        Command::Plot { run } => plot(&run),
        Command::Report {
            cases,
            out,
            fem,
            quiet,
        } => report(&cases, &out, fem, quiet),
        Command::Sweep {
            cases,
            vary,
            out,
            against,
            against_first,
            exclude_tips,
            json,
            command,
        } => {
            let figures = json.map(|path| (path, command));
            let against = peritherm::sweep::Against::chosen(against, against_first);
            sweep(&cases, &vary, &out, against, exclude_tips, figures, options)
        }
        Command::Bench {
            quick,
            nodes,
            cases,
            json,
            command,
        } => {
            let opts = peritherm::bench::BenchOptions {
                quick,
                nodes,
                threads: threads.unwrap_or_else(rayon::current_num_threads),
                cases,
            };
            bench(&opts, json.as_deref(), &command)
        }
        Command::Check { case } => check(&case, options),
        Command::Partition(args) => partition(&args),
    }
}

/// `peritherm partition`: the plan of a case on each rank count, as a Markdown table, and as
/// partition.json and a figure file when asked.
fn partition(a: &PartitionArgs) -> anyhow::Result<()> {
    use peritherm::planner;
    let machine = &planner::Machine {
        bandwidth: a.bandwidth,
        latency: a.latency,
        link: a.link,
    };
    let ranks: Vec<usize> = a.ranks.iter().map(|&n| n as usize).collect();
    let path = &a.case;
    let case = Case::load(path)?;
    let rows = planner::plan(&case, &ranks, machine)?;
    let table = planner::markdown(&case, &rows, machine);
    say!("{table}");
    let json = planner::json(machine, &rows);
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        peritherm::atomic::write_atomic(&dir.join("partition.json"), json.as_bytes())?;
    }
    if let Some(file) = &a.json {
        let list: Vec<String> = ranks.iter().map(|n| n.to_string()).collect();
        let mut args = vec!["partition".into(), path.display().to_string()];
        args.extend(["--ranks".into(), list.join(",")]);
        args.extend(["--bandwidth".into(), machine.bandwidth.to_string()]);
        args.extend(["--latency".into(), machine.latency.to_string()]);
        args.extend(["--link".into(), machine.link.to_string()]);
        let name = file
            .file_stem()
            .map_or("partition".into(), |s| s.to_string_lossy());
        let f = planner::figures(&name, &a.command, &table, args, &json);
        peritherm::atomic::write_atomic(file, f.to_json().as_bytes())?;
        say!("-> {}", file.display());
    }
    Ok(())
}

/// The settings of `peritherm fem`: the element size `h` (m) of a box case, the scheme and the
/// step `dt` (s); a gmsh case's own mesh.
fn fem_options(h: Option<f64>, scheme: Scheme, dt: Option<f64>) -> FemOptions {
    FemOptions {
        h,
        scheme,
        dt,
        mesh: None,
    }
}

/// The progress bar of `run` and `fem` (steps done of all), hidden when `quiet` or when
/// stderr is not a terminal.
fn step_bar(quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new(0);
    if quiet || !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} eta {eta}")
            .expect("valid template"),
    );
    bar
}

/// `peritherm run`: runs the case into `out` and prints its sizes, time and comparisons.
fn run(
    path: &std::path::Path,
    set: &[peritherm::sweep::Vary],
    out: &std::path::Path,
    quiet: bool,
    options: &peritherm::prepare::Options,
) -> anyhow::Result<()> {
    #[cfg(feature = "mpi")]
    if let Some(env) = peritherm::distributed::Environment::init() {
        return run_mpi(&env, path, set, out, quiet, options);
    }
    #[cfg(not(feature = "mpi"))]
    refuse_as_ranks()?;
    let case = peritherm::sweep::load_with(path, set)?;
    let bar = step_bar(quiet);
    let setup = SetupBar::new(quiet);
    let summary = run_case_with(&case, out, options, |done, total| {
        setup.stepping(&bar);
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    print_run(&case, &summary, out);
    Ok(())
}

/// The set-up's progress on a terminal (the consistent weights' Newton steps and residual),
/// until the first step ([`SetupBar::stepping`]) or until it is dropped (a failed set-up,
/// `check`).
struct SetupBar {
    bar: ProgressBar,
    done: std::cell::Cell<bool>,
}

impl SetupBar {
    fn new(quiet: bool) -> SetupBar {
        let bar = ProgressBar::new_spinner();
        if quiet || !std::io::stderr().is_terminal() {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        bar.set_style(
            ProgressStyle::with_template("{spinner} set-up {elapsed_precise}  {msg}")
                .expect("valid template"),
        );
        bar.set_message("reading and building the cloud");
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        let shown = bar.clone();
        let sink = move |e: &peritherm::progress::Event| {
            use peritherm::progress::Event;
            let msg = match *e {
                Event::WeightsStart { nodes, pairs } => {
                    format!("consistent weights of {nodes} nodes, {pairs} pairs")
                }
                Event::Newton {
                    step,
                    residual,
                    iterations,
                } => format!(
                    "consistent weights: Newton step {step}, moment residual {residual:.1e} (to {:.0e}), {iterations} CG iterations so far",
                    peritherm::weights::TOLERANCE
                ),
                Event::WeightsLoaded => "consistent weights loaded from the cache".into(),
            };
            shown.set_message(msg);
        };
        peritherm::progress::set_sink(Some(std::sync::Arc::new(sink)));
        SetupBar {
            bar,
            done: std::cell::Cell::new(false),
        }
    }

    /// Ends the set-up display and, the first time, starts the step bar's clock, so that its
    /// elapsed time and ETA count the stepping only.
    fn stepping(&self, steps: &ProgressBar) {
        if !self.done.replace(true) {
            self.finish();
            steps.reset();
        }
    }

    /// Stops reporting and clears the display.
    fn finish(&self) {
        peritherm::progress::set_sink(None);
        self.bar.finish_and_clear();
    }
}

impl Drop for SetupBar {
    fn drop(&mut self) {
        self.finish();
    }
}

/// `peritherm run` as one rank of `mpiexec -n N` (or a singleton, N = 1): each rank takes its
/// share of the node's cores unless `--threads` says otherwise; rank 0 shows the progress,
/// writes the outputs and prints; the other ranks print no error of their own.
#[cfg(feature = "mpi")]
fn run_mpi(
    env: &peritherm::distributed::Environment,
    path: &std::path::Path,
    set: &[peritherm::sweep::Vary],
    out: &std::path::Path,
    quiet: bool,
    options: &peritherm::prepare::Options,
) -> anyhow::Result<()> {
    let root = env.rank() == 0;
    if !root {
        SILENT.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    // fails when --threads built the pool already: that choice stands
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(env.threads_per_rank())
        .build_global();
    let case = peritherm::sweep::load_with(path, set)?;
    let bar = step_bar(quiet || !root);
    let setup = SetupBar::new(quiet || !root);
    let summary = env.run(&case, out, options, |done, total| {
        setup.stepping(&bar);
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    if let Some(summary) = summary {
        print_run(&case, &summary, out);
        if let Some(r) = &summary.ranks {
            say!(
                "  {} ranks ({}): {}..{} nodes and {} ghosts each at most, {} B per halo exchange",
                r.size,
                r.mode,
                r.nodes.iter().min().unwrap_or(&0),
                r.nodes.iter().max().unwrap_or(&0),
                r.ghosts.iter().max().unwrap_or(&0),
                r.halo_bytes
            );
        }
    }
    Ok(())
}

/// Refuses to run when an MPI launcher started this build, which has no MPI, as one of
/// several ranks: N copies would each run the whole case into the same directory.
#[cfg(not(feature = "mpi"))]
fn refuse_as_ranks() -> anyhow::Result<()> {
    let size = launcher_says(&["PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "SLURM_STEP_NUM_TASKS"]);
    if let Some(n) = size.filter(|&n| n > 1) {
        // N copies would each run the whole case into the same directory; the first says so
        let rank = launcher_says(&["PMI_RANK", "OMPI_COMM_WORLD_RANK", "SLURM_PROCID"]);
        if rank.is_some_and(|r| r > 0) {
            SILENT.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        anyhow::bail!(
            "started as one of {n} MPI ranks, but this peritherm was built without MPI: build it with `cargo build --release --features mpi` (docs/distributed.md)"
        );
    }
    Ok(())
}

/// A number an MPI launcher (`mpiexec` of MPICH or Open MPI, Slurm's `srun`) sets in the
/// environment under one of `keys` (the size or the rank); None outside one.
#[cfg(not(feature = "mpi"))]
fn launcher_says(keys: &[&str]) -> Option<usize> {
    keys.iter()
        .find_map(|k| std::env::var(k).ok()?.parse().ok())
}

/// What `run` prints of a finished run: sizes, steps, time, the implicit counters and the
/// comparisons with the reference.
fn print_run(case: &Case, summary: &RunSummary, out: &std::path::Path) {
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
    if let Some(c) = &summary.consistency {
        let how = match c.reused {
            true => "loaded from the weights cache".to_string(),
            false => format!("{} Newton steps, {} CG iterations", c.newton, c.iterations),
        };
        say!(
            "  consistent weights at {} nodes: {how}; set-up {:.2} s",
            c.corrected,
            summary.setup_seconds
        );
    }
    if let Some(st) = &summary.implicit {
        say!(
            "  {} accepted and {} rejected steps ({:.3e} to {:.3e} s), {} solves ({} by CG), {} factorisations",
            st.accepted,
            st.rejected,
            st.min_step,
            st.max_step,
            st.solves,
            st.cg_solves,
            st.factorisations
        );
    }
    print_comparisons(summary);
}

/// `peritherm fem`: the classical FEM solve of the case into `out`, with its sizes, time
/// and comparisons.
fn fem(
    path: &std::path::Path,
    out: &std::path::Path,
    opts: &FemOptions,
    quiet: bool,
) -> anyhow::Result<()> {
    let case = Case::load(path)?;
    let bar = step_bar(quiet);
    let summary = run_fem(&case, out, opts, |done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    say!(
        "{}: FEM, {} nodes, {} matrix entries, {} {} steps of {:.3e} s in {:.2} s (set-up {:.2} s) -> {}",
        case.path.display(),
        summary.nodes,
        summary.pairs,
        summary.steps,
        summary.integrator,
        summary.dt,
        summary.wall_seconds,
        summary.setup_seconds,
        out.display()
    );
    print_comparisons(&summary);
    Ok(())
}

/// `peritherm table`: the accuracy (or, with `fields`, the fields) table of finished runs,
/// also written as a figure file when `json` is given.
fn table(
    runs: &[PathBuf],
    json: Option<&std::path::Path>,
    fields: bool,
    command: &str,
) -> anyhow::Result<()> {
    use peritherm::figures::TableKind;
    let kind = if fields {
        TableKind::Fields
    } else {
        TableKind::Accuracy
    };
    say!("{}", peritherm::figures::table(runs, json, kind, command)?);
    Ok(())
}

/// `peritherm bench`: the tables printed and, with `json`, written as figure files there.
fn bench(
    opts: &peritherm::bench::BenchOptions,
    json: Option<&std::path::Path>,
    command: &str,
) -> anyhow::Result<()> {
    let report = peritherm::bench::run(opts, |line| eprintln!("bench: {line}"))?;
    say!("{}", report.markdown());
    if let Some(dir) = json {
        for figures in report.figures(command) {
            let path = dir.join(format!("{}.json", figures.name));
            peritherm::atomic::write_atomic(&path, figures.to_json().as_bytes())?;
            say!("-> {}", path.display());
        }
    }
    Ok(())
}

/// `peritherm check`: everything `run` does before its time loop (the budget, the model, the
/// semantic checks, the step and its count, the steppers' set-up), and the sizes.
fn check(path: &std::path::Path, options: &peritherm::prepare::Options) -> anyhow::Result<()> {
    use peritherm::solve::Integrator;
    let case = Case::load(path)?;
    say!("{}: {}", case.path.display(), case.budget.line());
    let setup = SetupBar::new(false);
    let model = peritherm::prepare::build_for_check(&case, options)?;
    drop(setup);
    let pending =
        model.correction.is_none() && peritherm::model::corrects(&case.spec, &model.cloud);
    if let Some(c) = &model.correction {
        say!(
            "{}: consistent weights at {} nodes loaded from the weights cache",
            case.path.display(),
            c.corrected
        );
    } else if pending {
        say!("{}", weights_estimate(&case, &model));
    }
    let plan = peritherm::prepare::plan(&case, &model)?;
    let sizes = format!(
        "{}: {} body nodes, {} fictitious, {} directed bonds",
        case.path.display(),
        model.cloud.n_body,
        model.cloud.n_fictitious(),
        model.bonds
    );
    let euler = Integrator::Euler.stable_dt(&model);
    match (case.integrator.is_implicit(), plan.adaptive) {
        (true, Some(a)) => say!(
            "{sizes}, {}: adaptive steps of tolerance {:e} K (explicit Euler's bound would be {euler:.4e} s)",
            case.integrator.name(),
            a.tolerance
        ),
        (true, None) => say!(
            "{sizes}, {}: no stability bound (explicit Euler's would be {euler:.4e} s), {} steps",
            case.integrator.name(),
            plan.total
        ),
        (false, _) => say!(
            "{sizes}, stable dt ({}) = {:.4e} s, {} steps of {:.4e} s",
            case.integrator.name(),
            case.integrator.stable_dt(&model),
            plan.total,
            plan.dt
        ),
    }
    Ok(())
}

/// The line of `check` for consistent weights it did not solve: the estimated set-up.
fn weights_estimate(case: &Case, model: &peritherm::model::Model) -> String {
    use peritherm::weights::{estimate, Path};
    let order = case.spec.consistency;
    let (nodes, pairs) = (model.cloud.n_body, model.conductance.vals.len());
    let e = estimate(model.cloud.dim, order, nodes as f64, pairs as f64);
    let how = match e.path {
        Path::Direct => format!(
            "one sparse factor of about {}",
            peritherm::budget::human(e.bytes)
        ),
        Path::TwoLevel => "two-level CG".to_string(),
    };
    format!(
        "{}: consistent weights not in the weights cache: `run` will solve them for up to {nodes} nodes and {pairs} pairs ({how}), estimated {} on 2 threads; the stable dt below is that of K before them",
        case.path.display(),
        human_seconds(e.seconds)
    )
}

/// Seconds as a short duration (s, min or h).
fn human_seconds(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// Prints a run's comparison with its reference, one line per output time.
fn print_comparisons(summary: &RunSummary) {
    for c in &summary.reference {
        say!(
            "  t = {:<8} max|diff| = {:.4e}  eq45 = {:.4e}  eq13 = {:.4e}  ε(eq27) = {:.4e}  L2rel(V) = {:.4e}",
            peritherm::output::number_label(c.time),
            c.max_abs_diff,
            c.mean_sq_rel_diff,
            c.l2_rel_line,
            c.epsilon,
            c.l2_rel_volume
        );
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
    if !(exclude_tips.is_finite() && exclude_tips >= 0.0) {
        anyhow::bail!("--exclude-tips: must be a distance >= 0 m, got {exclude_tips}");
    }
    let a = RunSummary::read(run)?;
    let b = RunSummary::read(reference)?;
    let case = peritherm::provenance::case_of_run(run, &a)?;
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
    say!("| t (s) | max abs diff (°C) | mean abs diff (°C) | ε (eq 27) | where (m) |");
    say!("|---|---|---|---|---|");
    for (k, t) in a.output_times.iter().enumerate() {
        let Some(kb) = b.output_index(*t) else {
            anyhow::bail!("{}: has no output at t = {t} s", reference.display());
        };
        let fa = a.read_field(run, k)?;
        let fb = b.read_field(reference, kb)?;
        same_body(cloud.dim, (&fa.pos, run), (&fb.pos, reference))?;
        let tips = peritherm::crack::tips_at(&cracks, *t);
        let d = field_difference(
            cloud.dim,
            (&fa.pos, &fa.theta),
            (&fb.pos, &fb.theta),
            &cracks,
            (&tips, exclude_tips),
        );
        say!(
            "| {t} | {:.3e} | {:.3e} | {:.3e} | ({:.4e}, {:.4e}, {:.4e}) |",
            d.max_abs,
            d.mean_abs,
            d.epsilon(),
            d.at.x,
            d.at.y,
            d.at.z
        );
    }
    Ok(())
}

/// Refuses to compare fields of different dimension or of bodies that do not overlap: the
/// nodes' coordinates span the same axes and each bounding box lies within the other's,
/// up to 1% of the larger extent (node placement differs by half a spacing).
fn same_body(
    dim: usize,
    a: (&[peritherm::math::Point], &std::path::Path),
    b: (&[peritherm::math::Point], &std::path::Path),
) -> anyhow::Result<()> {
    let bounds = |pts: &[peritherm::math::Point]| {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in pts {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    };
    let ((alo, ahi), (blo, bhi)) = (bounds(a.0), bounds(b.0));
    let extent = (0..3)
        .map(|k| (ahi[k] - alo[k]).max(bhi[k] - blo[k]))
        .fold(0.0, f64::max);
    let tol = 0.01 * extent.max(f64::MIN_POSITIVE);
    for k in 0..3 {
        let (sa, sb) = (ahi[k] - alo[k] > tol, bhi[k] - blo[k] > tol);
        if sa != sb || (k >= dim && (sa || sb)) {
            anyhow::bail!(
                "{} and {}: the runs' nodes span different axes (a {dim}D run against another dimension); compare runs of the same body",
                a.1.display(),
                b.1.display()
            );
        }
        if (alo[k] - blo[k]).abs() > tol + 0.05 * extent
            || (ahi[k] - bhi[k]).abs() > tol + 0.05 * extent
        {
            anyhow::bail!(
                "{} and {}: the runs' bodies differ along axis {k} ({:e}..{:e} m against {:e}..{:e} m); compare runs of the same body",
                a.1.display(),
                b.1.display(),
                alo[k],
                ahi[k],
                blo[k],
                bhi[k]
            );
        }
    }
    Ok(())
}

/// `peritherm sweep`: the variants of every case, run and compared; the table printed and
/// written as sweep.csv and sweep.md.
fn sweep(
    cases: &[PathBuf],
    vary: &[peritherm::sweep::Vary],
    out: &std::path::Path,
    against: Option<peritherm::sweep::Against>,
    exclude_tips: f64,
    figures: Option<(PathBuf, String)>,
    options: &peritherm::prepare::Options,
) -> anyhow::Result<()> {
    use peritherm::sweep;
    // a sweep against a run directory cannot be repeated by its arguments alone
    let first = against == Some(sweep::Against::First);
    let args = (!matches!(against, Some(sweep::Against::Run(_))))
        .then(|| sweep_args(cases, vary, first, exclude_tips));
    if !(exclude_tips.is_finite() && exclude_tips >= 0.0) {
        anyhow::bail!("--exclude-tips: must be a distance >= 0 m, got {exclude_tips}");
    }
    let (variants, against) = sweep::study(cases, vary, against)?;
    let n = variants.len();
    let rows = sweep::run(
        &variants,
        out,
        &against,
        exclude_tips,
        options,
        |k, label| {
            eprintln!("[{}/{n}] {label}", k + 1);
        },
    )?;
    let (table, _) = sweep::write_study(&variants, &rows, out, &against)?;
    say!("{table}");
    say!("-> {}", out.join("sweep.md").display());
    if let Some((path, command)) = figures {
        let name = path.file_stem().unwrap_or_default().to_string_lossy();
        let provenance = peritherm::figures::provenance(rayon::current_num_threads());
        let f = peritherm::figures::sweep_figures(&name, &command, provenance, args, &rows);
        peritherm::atomic::write_atomic(&path, f.to_json().as_bytes())?;
        say!("-> {}", path.display());
    }
    Ok(())
}

/// The arguments of `peritherm sweep` that repeat a sweep (without `--out`).
fn sweep_args(
    cases: &[PathBuf],
    vary: &[peritherm::sweep::Vary],
    against_first: bool,
    exclude_tips: f64,
) -> Vec<String> {
    let mut args = vec!["sweep".to_string()];
    args.extend(cases.iter().map(|c| c.display().to_string()));
    for v in vary {
        args.extend(["--vary".into(), format!("{}={}", v.key, v.values.join(","))]);
    }
    if against_first {
        args.push("--against-first".into());
    }
    if exclude_tips > 0.0 {
        args.extend(["--exclude-tips".into(), exclude_tips.to_string()]);
    }
    args
}

/// `peritherm plot`: per output a temperature map (one colour range for all outputs, cracks as
/// they are at that time, region boundaries, flux arrows when the run has cracks) and, for runs
/// with damage, a damage map; PNG and SVG.
fn plot(run: &std::path::Path) -> anyhow::Result<()> {
    let summary = RunSummary::read(run)?;
    let case = peritherm::provenance::case_of_run(run, &summary)?;
    if case.spec.geometry.bare_cloud()?.dim != 2 {
        anyhow::bail!(
            "{}: maps are drawn for 2D runs; open the field_<k>.vtu files in ParaView",
            run.display()
        );
    }
    let fields = (0..summary.fields.len())
        .map(|k| summary.read_field(run, k))
        .collect::<Result<Vec<_>, _>>()?;
    for stem in peritherm::report::page::draw_maps(&case, &summary, &fields, run)? {
        say!("{}.png/.svg", stem.display());
    }
    Ok(())
}

/// `peritherm report`: runs each case (directories: every case file in them) and writes its
/// report into --out/<case>/; with several cases, one index over all of them.
fn report(inputs: &[PathBuf], out: &std::path::Path, fem: bool, quiet: bool) -> anyhow::Result<()> {
    use peritherm::case::ReferenceSource;
    use peritherm::report::page::{write_index, write_report};
    let mut cases = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("{}: cannot list", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "toml"))
                .collect();
            found.sort();
            cases.extend(found);
        } else {
            cases.push(p.clone());
        }
    }
    let mut written = Vec::new();
    for path in &cases {
        let case = Case::load(path)?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "case".into());
        let dir = out.join(&stem);
        let run = dir.join("run");
        if !quiet {
            eprintln!("{}: running into {}", path.display(), run.display());
        }
        run_case(&case, &run, |_, _| {})?;
        let reference = match case.reference.as_ref().map(|r| &r.source) {
            Some(ReferenceSource::Analytic(_)) => "series",
            Some(ReferenceSource::Table(_)) => "reference table",
            Some(ReferenceSource::Fem(_)) => "FEM",
            None => "none",
        };
        let fem_dir = dir.join("fem");
        let extra = if fem && reference != "FEM" {
            if !quiet {
                eprintln!("{}: FEM into {}", path.display(), fem_dir.display());
            }
            peritherm::fem::run_fem(&case, &fem_dir, &Default::default(), |_, _| {})?;
            Some((fem_dir.as_path(), "FEM"))
        } else {
            None
        };
        let w = write_report(&case, &run, &dir, reference, extra)?;
        say!("{}: {}", path.display(), dir.join("index.html").display());
        written.push(w);
    }
    if written.len() > 1 {
        write_index(out, &written)?;
        say!("index: {}", out.join("index.html").display());
    }
    Ok(())
}
