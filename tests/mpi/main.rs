//! Distributed runs under `mpiexec` (the `mpi` build only: `cargo test --release --features
//! mpi --test mpi`, with MPICH or Open MPI installed; CI uses MPICH, and the suite passed with
//! Open MPI 4.1 too). Each run is launched as
//! `mpiexec -n N peritherm run ...` for N = 1, 2 and 3 (3 oversubscribes a 2-core machine),
//! asserts the communicator size it ran on (run.json `ranks.size`) and compares its fields
//! with a serial run of the same binary on one thread: byte for byte, except the fixed-step
//! implicit runs that step by rows, whose distributed CG agrees with the serial direct solve
//! to [`IMPLICIT_AGREEMENT`].
//!
//! The in-process ranks of `tests/cases/distributed.rs` check every bundled case with the same
//! protocol without MPI; `scripts/mpi-check.sh` runs every bundled case under `mpiexec`.

#[path = "../common"]
#[allow(dead_code)]
mod common {
    pub mod cli;
    pub mod runs;
}

use common::cli::{command, EXE};
use common::runs::{field_files_differ_by, same_field_files};
use std::path::Path;
use std::process::{Command, Output};

/// `mpiexec -n ranks peritherm --threads 1 args...` to its end: one thread per rank, as the
/// serial run it is compared with (the consistent weights' and the FEM reference's sparse
/// Cholesky factorisations are not the same bits on every thread count).
fn mpiexec(ranks: usize, args: &[&str]) -> Output {
    Command::new("mpiexec")
        .env(common::cli::CACHE_VAR, "off")
        .args(open_mpi_flags())
        .args(["-n", &ranks.to_string(), EXE, "--threads", "1"])
        .args(args)
        .output()
        .expect("mpiexec (install MPICH: `apt-get install mpich libmpich-dev libclang-dev`)")
}

/// What Open MPI's `mpiexec` needs to run these tests (MPICH's needs nothing): more ranks
/// than cores (3 on a 2-core machine), and, as root (a CI container), its consent.
fn open_mpi_flags() -> Vec<&'static str> {
    let version = Command::new("mpiexec").arg("--version").output();
    let open_mpi = version.is_ok_and(|o| {
        let said = String::from_utf8_lossy(&o.stdout);
        ["Open MPI", "OpenRTE", "open-mpi"]
            .iter()
            .any(|n| said.contains(n))
    });
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    match (open_mpi, root) {
        (true, true) => vec!["--oversubscribe", "--allow-run-as-root"],
        (true, false) => vec!["--oversubscribe"],
        (false, _) => Vec::new(),
    }
}

/// Settings that keep a heavy set-up light where the test is about the ranks, not the weights:
/// the uniform crack plate's quadratic weights take about a minute and 4.6 GB per process
/// (every rank builds a corrected model whole); the linear order takes the same whole-model
/// path in seconds.
fn light(case: &str) -> Option<String> {
    (case == "crack_plate_uniform.toml").then(|| "kernel.consistency=\"linear\"".to_string())
}

/// The settings that shorten a bundled case to a hundredth of its first output (as the
/// fields figure does), three steps at least.
fn short(case: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(case).unwrap();
    let table: toml::Table = text.parse().unwrap();
    let time = table["time"].as_table().unwrap();
    let first = match time.get("outputs") {
        Some(o) => o.as_array().unwrap()[0].as_float().unwrap(),
        None => time["end"].as_float().unwrap(),
    };
    let end = first / 100.0;
    let mut set = vec![
        format!("time.end={end:?}"),
        format!("time.outputs=[{end:?}]"),
    ];
    if time
        .get("dt")
        .and_then(|d| d.as_float())
        .is_some_and(|dt| dt > end / 3.0)
    {
        set.push(format!("time.dt={:?}", end / 3.0));
    }
    set
}

/// Relative agreement of a distributed fixed-step implicit run with the serial one (per
/// quantity, of its largest magnitude): the 1e-12 the issue allows. Its CG stops at 1e-15
/// relative residual; the serial run factorises.
const IMPLICIT_AGREEMENT: f64 = 1e-12;

/// Runs `case` shortened serially on one thread into `dir/serial`, then under `mpiexec -n
/// 1, 2, 3` into `dir/ranks-N`, and compares.
fn same_under_mpiexec(case: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(case);
    let dir = tempfile::tempdir().unwrap();
    let mut args: Vec<String> = vec!["run".into(), path.display().to_string(), "-q".into()];
    for s in short(&path).into_iter().chain(light(case)) {
        args.extend(["--set".into(), s]);
    }
    let with_out = |out: &Path| {
        let mut a = args.clone();
        a.extend(["--out".into(), out.display().to_string()]);
        a
    };
    let serial = dir.path().join("serial");
    let o = command()
        .arg("--threads")
        .arg("1")
        .args(with_out(&serial))
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{case}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let serial_run = peritherm::output::RunSummary::read(&serial).unwrap();
    let fields = serial_run.fields.clone();
    // a shareable case is built one share per rank, the others whole on every rank
    let setup = match peritherm::prepare::shares(&peritherm::case::Case::load(&path).unwrap()) {
        true => "share",
        false => "whole",
    };
    for ranks in [1, 2, 3] {
        let out = dir.path().join(format!("ranks-{ranks}"));
        let a = with_out(&out);
        let o = mpiexec(ranks, &a.iter().map(String::as_str).collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{case} on {ranks} ranks: {err}");
        let s = peritherm::output::RunSummary::read(&out).unwrap();
        let r = s.ranks.expect("run.json of an MPI run lists its ranks");
        assert_eq!(r.size, ranks, "{case}: the communicator's size");
        assert_eq!(r.nodes.iter().sum::<usize>(), s.nodes, "{case}");
        let setup = if ranks == 1 { "whole" } else { setup };
        assert_eq!(r.setup, setup, "{case} on {ranks} ranks");
        assert_eq!(
            (s.bonds, s.pairs),
            (serial_run.bonds, serial_run.pairs),
            "{case}"
        );
        let what = format!("{case} on {ranks} ranks ({}, {setup})", r.mode);
        let implicit_rows = r.mode == "rows" && s.implicit.is_some();
        if implicit_rows {
            let d = field_files_differ_by(&serial, &out, &fields);
            assert!(
                d <= IMPLICIT_AGREEMENT,
                "{what}: the fields differ by {d:e}"
            );
        } else {
            same_field_files(&serial, &out, &fields, &what);
        }
        planned_as_run(&path, ranks, &r, &what);
    }
}

/// `peritherm partition` plans what the run held: the most nodes, ghosts and bonds of a rank
/// are those run.json reports for the same rank count.
fn planned_as_run(case: &Path, ranks: usize, run: &peritherm::output::Ranks, what: &str) {
    let dir = tempfile::tempdir().unwrap();
    let o = command()
        .args([
            "partition",
            case.to_str().unwrap(),
            "--ranks",
            &ranks.to_string(),
        ])
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(dir.path().join("partition.json")).unwrap();
    let plan: serde_json::Value = serde_json::from_str(&text).unwrap();
    let row = &plan["rows"][0];
    let most = |v: &[usize]| *v.iter().max().unwrap() as u64;
    assert_eq!(
        row["nodes"][1].as_u64(),
        Some(most(&run.nodes)),
        "{what}: nodes"
    );
    assert_eq!(
        row["ghosts"].as_u64(),
        Some(most(&run.ghosts)),
        "{what}: ghosts"
    );
    assert_eq!(
        row["bonds"].as_u64(),
        Some(most(&run.bonds)),
        "{what}: bonds"
    );
}

#[test]
fn explicit_cases_give_the_serial_bits() {
    // Euler and RK4; a crack, growing cracks, dual horizon, a gmsh cloud, a flux relation,
    // loads (a laser source and convection), a sphere
    for case in [
        "bar_flux.toml",
        "crack_plate_uniform.toml",
        "growing_cracks.toml",
        "dh_plate_k0.5_m1.toml",
        "dh_plate_gmsh_k0.5_m1.toml",
        "laser_film.toml",
        "sphere_cooling.toml",
    ] {
        same_under_mpiexec(case);
    }
}

#[test]
fn phase_change_and_implicit_steppers_give_the_serial_bits() {
    // phase change (the enthalpy stepper steps each rank's rows, ghost enthalpies exchanged),
    // in a plane and axisymmetric; implicit schemes at a fixed step (by rows, block-Jacobi
    // CG) and adaptive (every rank steps the whole model; the adaptive solver's choice
    // between CG and a factorisation counts work, not seconds, so every rank and the serial
    // run take the same path)
    for case in [
        "ice_in_water.toml",
        "pipe_freezing.toml",
        "thermal_shock_k1_m1_implicit.toml",
        "dh_crack_plate_k1_m1_implicit.toml",
        "dh_crack_plate_k1_m1_adaptive.toml",
    ] {
        same_under_mpiexec(case);
    }
}

#[test]
fn a_bad_case_fails_once_on_every_rank_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("bad.toml");
    std::fs::write(&case, "title = \"x\"\n[time]\nend = -1\n").unwrap();
    let out = dir.path().join("out");
    let o = mpiexec(
        2,
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "one error line from rank 0: {err}");
    assert!(lines[0].contains("bad.toml"), "{err}");
    assert!(!out.exists(), "no output directory");
}

/// ParaView's data, as VTK's Python reader sees it: a 3-rank run's `fields.pvd` lists one
/// `.pvtu` per output, each opens as one dataset with every body node once, and its positions
/// and temperatures are those of the CSV (tests/mpi/read_pvd.py). Needs VTK's Python package
/// (`pip install vtk numpy`, which .ci/run does in its virtual environment).
#[test]
fn paraview_reads_a_three_rank_run_as_one_dataset() {
    let python = std::env::var("PERITHERM_PYTHON").unwrap_or_else(|_| "python3".into());
    let has_vtk = std::process::Command::new(&python)
        .args(["-c", "import vtk, numpy"])
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        has_vtk,
        "{python} has no VTK: pip install vtk numpy (README: Contributing), or set PERITHERM_PYTHON"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/crack_plate_uniform.toml");
    let o = mpiexec(
        3,
        &[
            "run",
            case.to_str().unwrap(),
            "--set",
            "time.end=0.001",
            "--set",
            "time.outputs=[0.0005,0.001]",
            "--set",
            &light("crack_plate_uniform.toml").unwrap(),
            "-q",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mpi/read_pvd.py");
    let o = std::process::Command::new(&python)
        .arg(&script)
        .arg(&out)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{said}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(said.lines().count(), 2, "{said}");
    assert!(
        said.contains("field_2.pvtu: t = 0.001 s, 59732 nodes"),
        "{said}"
    );
}
