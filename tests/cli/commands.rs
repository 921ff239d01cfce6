//! The command line as a user meets it: the output contract and bad input.

use crate::common::case::CaseToml;
use crate::common::cli::{command, peritherm, write_case};
use std::path::{Path, PathBuf};

const SMALL: &str = r#"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 0.5]
thickness = 0.1
[[region]]
name = "plate"
spacing = 0.05
horizon = { factor = 3.0 }
[material.steel]
conductivity = 50.0
density = 7850.0
specific_heat = 420.0
[boundary.x_min]
type = "temperature"
method = "mirror"
value = "100*(1 - exp(-t))"
[boundary.x_max]
type = "convection"
h = 20.0
ambient = 20.0
[time]
end = 2.0
outputs = [1.0, 2.0]
"#;

/// A phase change for SMALL's material (melting at 500 °C, never reached).
const PHASE: &str = "[material.steel.phase_change]\ntemperature = 500.0\nlatent_heat = 3e5\nfrozen_conductivity = 40.0\nfrozen_specific_heat = 400.0\n";

/// A `[history]` for SMALL (one point, every 0.1 s).
const HISTORY: &str = "[history]\npoints = [[0.5, 0.25]]\ninterval = 0.1\nplot = \"temperature\"\n";

/// A `plate_pulse_split` reference for SMALL's rectangle.
const SPLIT: &str = "[reference.solution]\nkind = \"plate_pulse_split\"\nx0 = 0.0\ny0 = 0.0\nlength = 1.0\nwidth = 0.5\ndiffusivity = 1.5e-5\namplitude = 100.0\nrate = 1.0\nsplit = 0.25\nbelow = 1.0\nabove = 0.0\n";

/// A `film_laser_pulse` reference with a reflectivity above 1.
const LASER: &str = "[reference.solution]\nkind = \"film_laser_pulse\"\nx0 = 0.0\nlength = 1.0\ndiffusivity = 1.5e-5\nheat_capacity = 3.3e6\nfluence = 13.4\nreflectivity = 1.5\ndepth = 0.1\nduration = 0.1\nshape = 2.0\n";

/// field_<k>.csv has x,y,z,temperature and one row per body node; run.json has the keys.
#[test]
fn run_honours_the_output_contract() {
    let dir = tempfile::tempdir().unwrap();
    let case = write_case(dir.path(), "small.toml", SMALL);
    let out = dir.path().join("out");
    let o = peritherm(&["run", &case, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    for key in [
        "nodes",
        "bonds",
        "steps",
        "dt",
        "output_times",
        "wall_seconds",
        "energy",
    ] {
        assert!(json.get(key).is_some(), "run.json lacks {key}");
    }
    let nodes = json["nodes"].as_u64().unwrap() as usize;
    assert_eq!(nodes, 20 * 10);
    assert_eq!(json["energy"].as_array().unwrap().len(), 2);
    for k in 1..=2 {
        let text = std::fs::read_to_string(out.join(format!("field_{k}.csv"))).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next().unwrap(),
            "x,y,z,temperature,region,spacing,horizon,volume,damage,qx,qy,qz"
        );
        assert_eq!(lines.count(), nodes);
        // the same fields for ParaView, one vertex per body node
        let vtu = std::fs::read_to_string(out.join(format!("field_{k}.vtu"))).unwrap();
        assert!(vtu.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
        assert!(vtu.contains(&format!(
            "<Piece NumberOfPoints=\"{nodes}\" NumberOfCells=\"{nodes}\">"
        )));
        for name in [
            "temperature",
            "flux",
            "damage",
            "horizon",
            "spacing",
            "region",
        ] {
            assert!(
                vtu.contains(&format!("Name=\"{name}\"")),
                "vtu lacks {name}"
            );
        }
    }
    // and their time series for ParaView
    let pvd = std::fs::read_to_string(out.join("fields.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet timestep=").count(), 2, "{pvd}");
    assert!(pvd.contains("file=\"field_2.vtu\""), "{pvd}");
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .ends_with(".partial")
        })
        .collect();
    assert!(leftovers.is_empty());
}

/// Each class of bad input: non-zero exit, one line naming the file and the key, no panic,
/// and no output directory.
#[test]
fn bad_input_fails_with_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, String, &str)] = &[
        (
            "unknown key",
            SMALL.replace("[time]", "[time]\nstep = 1"),
            "step",
        ),
        ("missing field", SMALL.replace("end = 2.0\n", ""), "end"),
        (
            "negative conductivity",
            SMALL.replace("conductivity = 50.0", "conductivity = -50.0"),
            "material.steel.conductivity",
        ),
        (
            "unstable dt",
            SMALL.replace("[time]", "[time]\ndt = 1e6"),
            "time.dt",
        ),
        (
            "bad expression",
            SMALL.replace("100*(1 - exp(-t))", "100*(1 - exq(-t))"),
            "boundary.x_min.value",
        ),
        (
            "wrong coordinates",
            SMALL.replace("min = [0.0, 0.0]", "min = [0.0]"),
            "domain.min",
        ),
        (
            "spacing",
            SMALL.replace("spacing = 0.05", "spacing = 0.03"),
            "region[0].spacing",
        ),
        (
            "unknown face",
            SMALL.replace("[boundary.x_max]", "[boundary.z_max]"),
            "boundary.z_max",
        ),
        ("not toml", "dimension = = 2".to_string(), "line 1"),
        (
            "nan initial",
            SMALL.replace("[time]", "[initial]\nvalue = \"ln(x - 1)\"\n[time]"),
            "initial",
        ),
        (
            "output time",
            SMALL.replace("outputs = [1.0, 2.0]", "outputs = [2.0, 1.0]"),
            "time.outputs[1]",
        ),
        (
            "negative latent heat",
            SMALL
                .replace("[boundary.x_min]", &format!("{PHASE}[boundary.x_min]"))
                .replace("latent_heat = 3e5", "latent_heat = -3e5"),
            "material.steel.phase_change.latent_heat",
        ),
        (
            "phase change with rk4",
            SMALL
                .replace("[boundary.x_min]", &format!("{PHASE}[boundary.x_min]"))
                .replace("[time]", "[time]\nintegrator = \"rk4\""),
            "time.integrator",
        ),
        (
            "axisymmetric with thickness",
            SMALL.replace(
                "dimension = 2",
                "dimension = 2\nsymmetry = \"axisymmetric\"",
            ),
            "domain.thickness",
        ),
        (
            "spherical in 2D",
            SMALL
                .replace("dimension = 2", "dimension = 2\nsymmetry = \"spherical\"")
                .replace("thickness = 0.1\n", ""),
            "symmetry",
        ),
        (
            "layer at the axis",
            SMALL
                .replace(
                    "dimension = 2",
                    "dimension = 2\nsymmetry = \"axisymmetric\"",
                )
                .replace("thickness = 0.1\n", ""),
            "symmetry",
        ),
        (
            "unknown history plot",
            format!("{SMALL}{}", HISTORY.replace("temperature", "log")),
            "history.plot",
        ),
        (
            "history point",
            format!("{SMALL}{}", HISTORY.replace("[0.5, 0.25]", "[0.5]")),
            "history.points[0]",
        ),
        (
            "history interval",
            format!("{SMALL}{}", HISTORY.replace("0.1", "-0.1")),
            "history.interval",
        ),
        (
            "too many history samples",
            format!("{SMALL}{}", HISTORY.replace("0.1", "1e-9")),
            "history.interval",
        ),
        (
            "probe lines",
            format!("{SMALL}[reference]\nlines_x = [0.5, nan]\n{SPLIT}"),
            "reference.lines_x",
        ),
        (
            "split outside the plate",
            format!(
                "{SMALL}[reference]\n{}",
                SPLIT.replace("split = 0.25", "split = 0.75")
            ),
            "reference.solution",
        ),
        (
            "reflectivity",
            format!("{SMALL}[reference]\n{LASER}"),
            "reference.solution",
        ),
        (
            "unknown reference kind",
            format!(
                "{SMALL}[reference]\n{}",
                SPLIT.replace("plate_pulse_split", "plate_split")
            ),
            "line",
        ),
    ];
    for (what, text, key) in cases {
        let case = write_case(dir.path(), "bad.toml", text);
        let out = dir.path().join(format!("out_{}", what.replace(' ', "_")));
        let o = peritherm(&["run", &case, "--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{what}: {err}");
        assert!(
            err.contains("bad.toml") && err.contains(key),
            "{what}: {err}"
        );
        assert!(
            !err.contains("panicked") && !err.contains("backtrace"),
            "{what}: {err}"
        );
        assert!(!out.exists(), "{what}: output written");
    }
    // a source infinite at a node: refused before the time loop with the place and time
    // (issue 36; a state that turns non-finite during the loop: tests/cli/hostile.rs)
    let case = write_case(
        dir.path(),
        "inf.toml",
        &SMALL.replace("[time]", "[source]\nvalue = \"1/(x - 0.025)\"\n[time]"),
    );
    let out = dir.path().join("out_inf");
    let o = peritherm(&["run", &case, "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("inf.toml: source.value: not finite (inf) at (0.025, 0.025, 0) m, t = 0 s"),
        "{err}"
    );
    assert!(!out.exists(), "a refused run wrote {}", out.display());
    let o = peritherm(&["run", "/nonexistent/case.toml", "--out", "x"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/case.toml"));
}

/// A gmsh case runs unchanged: fields with one row per mesh element, run.json; `compare`
/// of a run with itself reports zero differences; a mesh that does not parse ends with one
/// line naming the case, the key and the mesh file, and writes no output directory.
#[test]
fn gmsh_cases_run_compare_and_refuse_bad_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mesh = root.join("meshes/l_shape.msh");
    let l_shape = |mesh: &Path| {
        CaseToml::new(2)
            .mesh(&mesh.display().to_string())
            .region("plate", "", 3.0)
            .material("m", 1.0, 1.0, 1.0)
            .section(
                "[boundary.left]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 10.0\n\
                 [boundary.top]\ntype = \"convection\"\nh = 100.0\nambient = 0.0",
            )
            .end(1e-6)
            .time_key("outputs = [5e-7, 1e-6]")
            .text()
    };
    let case = write_case(dir.path(), "l.toml", &l_shape(&mesh));
    let out = dir.path().join("out");
    let o = peritherm(&["run", &case, "--out", out.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let field = std::fs::read_to_string(out.join("field_2.csv")).unwrap();
    assert!(field.starts_with("x,y,z,temperature,region,spacing,horizon,volume,damage,qx,qy,qz\n"));
    assert_eq!(field.lines().count(), 1 + 4422, "one row per triangle");
    let o = peritherm(&["compare", out.to_str().unwrap(), out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("| 0.000001 | 0.000e0 | 0.000e0 |"),
        "{table}"
    );

    let broken = dir.path().join("broken.msh");
    let bytes = std::fs::read(&mesh).unwrap();
    std::fs::write(&broken, &bytes[..bytes.len() / 2]).unwrap();
    let bad = write_case(dir.path(), "bad.toml", &l_shape(&broken));
    let out2 = dir.path().join("out2");
    let o = peritherm(&["run", &bad, "--out", out2.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("bad.toml") && err.contains("mesh.file") && err.contains("broken.msh"),
        "{err}"
    );
    assert!(!out2.exists(), "no output for a failed run");
}

/// `peritherm sweep` over the horizon of the Bobaru & Duangpanya 2010 bar (δ halved twice at fixed
/// Δ, to t = 0.1 s) writes one row per variant and output, and the max difference to the series
/// falls as δ falls (the δ-convergence of Bobaru & Duangpanya 2010 Fig. 10, measured 31.2 → 15.2 →
/// 5.3 °C at t = 0.1 s, where the steep initial layer makes the error large). Against the first
/// variant instead (its run directory, or `--against-first` although the case has a reference),
/// that variant's own row is zero.
#[test]
fn sweep_writes_a_table_and_converges_in_delta() {
    let dir = tempfile::tempdir().unwrap();
    let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/bar_dirichlet.toml");
    // sweeps the bar's horizon radii to t = 0.1 s into dir/NAME; returns sweep.csv
    let sweep = |radii: &str, name: &str, extra: &[&str]| -> String {
        let out = dir.path().join(name);
        let vary = format!("region.*.horizon.radius={radii}");
        let mut args = vec!["sweep", case.to_str().unwrap(), "--vary", &vary];
        args.extend([
            "--vary",
            "time.outputs=[0.1]",
            "--out",
            out.to_str().unwrap(),
        ]);
        args.extend(extra);
        let o = peritherm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(out.join("sweep.csv")).unwrap()
    };
    // the max abs difference of every row (the 11th column with two varied keys)
    let max_abs = |csv: &str| -> Vec<f64> {
        let rows = csv.lines().skip(1);
        rows.map(|l| l.split(',').nth(10).unwrap().parse().unwrap())
            .collect()
    };
    let csv = sweep("0.3,0.15,0.075", "sweep", &[]);
    assert!(csv.starts_with("variant,region.*.horizon.radius,time.outputs,nodes"));
    let d = max_abs(&csv);
    assert!(d.len() == 3 && d[0] > d[1] && d[1] > d[2], "{csv}");
    let first_run = dir.path().join("sweep/radius=0.3_outputs=_0.1_");
    assert!(first_run.join("run.json").exists());
    let csv = sweep(
        "0.3,0.15",
        "first",
        &["--against", first_run.to_str().unwrap()],
    );
    assert!(max_abs(&csv)[0] < 1e-12, "{csv}");
    // the case has its own reference (the series); --against-first compares with the first
    // variant instead: its row is zero, the second's is not, and both name the first's run
    let csv = sweep("0.3,0.15", "against-first", &["--against-first"]);
    let d = max_abs(&csv);
    assert!(d.len() == 2 && d[0] == 0.0 && d[1] > 1.0, "{csv}");
    let md = std::fs::read_to_string(dir.path().join("against-first/sweep.md")).unwrap();
    let against = md
        .lines()
        .filter(|l| l.ends_with("radius=0.3_outputs=_0.1_ |"));
    assert_eq!(against.count(), 2, "{md}");
    let o = peritherm(&[
        "sweep",
        case.to_str().unwrap(),
        "--vary",
        "region.*.nope=1",
        "--out",
        dir.path().join("bad").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(
        e.contains("bar_dirichlet.toml: --vary region.*.nope=1: unknown field `nope`"),
        "{e}"
    );
}

/// `peritherm report --fem` on two small cases (one cracked, with a series reference and a
/// probe line) writes each report's line plots (PD, series and FEM), error, map and damage
/// plots, report.md with the metrics table, index.html, and one index over both; a case that
/// does not exist is one line.
#[test]
fn report_writes_plots_pages_and_an_index() {
    let dir = tempfile::tempdir().unwrap();
    let square = |crack: &str| {
        let mut c = CaseToml::new(2)
            .key("title = \"small square\"")
            .domain("[0.0, 0.0]", "[1.0, 1.0]")
            .region("square", "cells = [16, 16]", 3.0)
            .material("m", 1.14, 1.0, 1.0);
        for face in ["x_min", "x_max", "y_min", "y_max"] {
            c = c.section(&format!(
                "[boundary.{face}]\ntype = \"temperature\"\nvalue = 0.0"
            ));
        }
        c.section(crack)
            .section(
                "[reference]\nline_y = 0.46875\n\
                 [reference.solution]\nkind = \"square_fixed_edges\"\nx0 = 0.0\ny0 = 0.0\n\
                 length = 1.0\ndiffusivity = 1.14\nedge = 0.0\ninitial = 40.0",
            )
            .initial_value(40.0)
            .end(0.02)
            .time_key("outputs = [0.01, 0.02]")
            .text()
    };
    let a = write_case(dir.path(), "plain.toml", &square(""));
    let b = write_case(
        dir.path(),
        "cracked.toml",
        &square("[[crack]]\npoints = [[0.3, 0.5], [0.7, 0.5]]"),
    );
    let out = dir.path().join("reports");
    let o = peritherm(&[
        "report",
        &a,
        &b,
        "--out",
        out.to_str().unwrap(),
        "--fem",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["line_y_0.46875", "error_y_0.46875", "map_1", "map_2"] {
        for ext in ["png", "svg"] {
            let p = out.join(format!("plain/{f}.{ext}"));
            assert!(
                std::fs::metadata(&p).unwrap().len() > 1000,
                "{}",
                p.display()
            );
        }
    }
    assert!(out.join("cracked/damage_2.png").exists());
    assert!(out.join("cracked/fem/field_2.csv").exists());
    let svg = std::fs::read_to_string(out.join("plain/line_y_0.46875.svg")).unwrap();
    assert!(svg.contains("FEM, t = 0.02 s") && svg.contains("series, t = 0.02 s"));
    assert!(!out.join("plain/damage_2.png").exists());
    let md = std::fs::read_to_string(out.join("plain/report.md")).unwrap();
    assert!(md.contains("| t (s) | max abs diff (°C) |") && md.contains("![map_1](map_1.png)"));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("plain/index.html") && html.contains("cracked/index.html"));
    let field = std::fs::read_to_string(out.join("plain/run/field_1.csv")).unwrap();
    assert!(field.lines().next().unwrap().ends_with(",qz,reference"));
    let o = peritherm(&["report", "nope.toml", "--out", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert_eq!(String::from_utf8_lossy(&o.stderr).lines().count(), 1);
}

/// A run's directory stands on its own: run from the case's folder with relative paths (the
/// case's mesh path relative too), `compare` and `plot` started from another directory read
/// the run's `case.toml` copy and work; once the mesh file changes they refuse with one line
/// naming it.
#[test]
fn compare_and_plot_work_from_any_directory() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let work = dir.path().join("work");
    std::fs::create_dir_all(work.join("meshes")).unwrap();
    std::fs::copy(root.join("meshes/l_shape.msh"), work.join("meshes/l.msh")).unwrap();
    let text = "dimension = 2\n[mesh]\nfile = \"meshes/l.msh\"\n[[region]]\nname = \"plate\"\nhorizon = { factor = 3 }\n[material.m]\nconductivity = 1.0\ndensity = 1.0\nspecific_heat = 1.0\n[boundary.left]\ntype = \"temperature\"\nmethod = \"mirror\"\nvalue = 10.0\n[time]\nend = 1e-6\noutputs = [1e-6]\n";
    write_case(&work, "l.toml", text);
    let run = |cwd: &Path, args: &[&str]| command().current_dir(cwd).args(args).output().unwrap();
    let o = run(&work, &["run", "l.toml", "--out", "out", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(work.join("out/case.toml")).unwrap(),
        text,
        "the run keeps the case's text"
    );
    let elsewhere = dir.path();
    let o = run(elsewhere, &["compare", "work/out", "work/out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(elsewhere, &["plot", "work/out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(work.join("out/map_1.png").exists());

    let mut bytes = std::fs::read(work.join("meshes/l.msh")).unwrap();
    bytes.extend_from_slice(b"\n");
    std::fs::write(work.join("meshes/l.msh"), bytes).unwrap();
    let o = run(elsewhere, &["plot", "work/out"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("l.msh") && err.contains("changed"), "{err}");
}

/// docs/case-reference.md names every key of the case schema: each field of a struct that
/// the case file is read into (`deny_unknown_fields` in crates/io/src/case/*.rs, among them the
/// boundary types' structs, crates/core/src/material.rs, crates/analytic/src/lib.rs) appears in
/// backticks, alone or as the last part of a dotted key.
#[test]
fn the_case_reference_lists_every_schema_key() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/case-reference.md")).unwrap();
    let mut missing = Vec::new();
    let mut checked = 0;
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("crates/io/src/case"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    files.sort();
    assert!(
        files.iter().any(|f| f.ends_with("boundary.rs")),
        "{files:?}"
    );
    files.push(root.join("crates/core/src/material.rs"));
    files.push(root.join("crates/analytic/src/lib.rs"));
    for path in &files {
        let file = path.strip_prefix(root).unwrap().display();
        let text = std::fs::read_to_string(path).unwrap();
        for key in schema_keys(&text) {
            checked += 1;
            // a key (`key`, `section.key`) or a section (`[key]`, `[[key]]`, `[key.<name>]`)
            let forms = [
                format!("`{key}`"),
                format!(".{key}`"),
                format!("`[{key}]"),
                format!("`[[{key}]]"),
                format!("`[{key}."),
            ];
            if !forms.iter().any(|f| doc.contains(f.as_str())) {
                missing.push(format!("{file}: {key}"));
            }
        }
    }
    assert!(
        checked > 60,
        "only {checked} keys found: the parser below missed the schema"
    );
    assert!(
        missing.is_empty(),
        "not in docs/case-reference.md: {missing:?}"
    );
}

/// The serde names of the fields of every `deny_unknown_fields` struct in `text`.
fn schema_keys(text: &str) -> Vec<String> {
    let mut keys = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        if !line.contains("deny_unknown_fields") {
            continue;
        }
        let mut rename = None;
        for l in lines.by_ref() {
            let l = l.trim();
            // the end of the struct, or a struct without fields (`pub struct FreeBc {}`)
            if l.starts_with('}') || l.ends_with("{}") {
                break;
            }
            if let Some(r) = l.strip_prefix("#[serde(rename = \"") {
                rename = r.split('"').next().map(str::to_string);
            }
            if let Some(field) = l.strip_prefix("pub ").and_then(|f| f.split_once(':')) {
                if !field.0.contains(' ') && !field.0.contains('(') {
                    keys.push(rename.take().unwrap_or_else(|| field.0.to_string()));
                }
            }
        }
    }
    keys
}

/// A build without MPI started by `mpiexec -n 2` refuses to run: two copies would each run the
/// whole case into the same directory. (The launcher's environment, without the launcher.)
#[cfg(not(feature = "mpi"))]
#[test]
fn a_build_without_mpi_refuses_to_run_as_ranks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/bar_flux.toml");
    for (rank, says) in [("0", true), ("1", false)] {
        let o = crate::common::cli::command()
            .args(["run", case, "--out", out.to_str().unwrap()])
            .env("PMI_SIZE", "2")
            .env("PMI_RANK", rank)
            .output()
            .unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            err.contains("built without MPI"),
            says,
            "rank {rank}: {err}"
        );
        assert!(!out.exists());
    }
}

/// `peritherm partition` plans without running: the plan of one rank holds the model's bonds
/// (as `run` counts them), two ranks split the nodes and the bonds, `--out` writes partition.json with the
/// same bytes each time, and a rank count of 0 or a missing case is refused with one line.
#[test]
fn partition_plans_the_ranks_without_running() {
    let dir = tempfile::tempdir().unwrap();
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/dh_plate_k0.5_m1.toml");
    let run = dir.path().join("run");
    let o = crate::common::cli::peritherm(&["run", case, "--out", run.to_str().unwrap(), "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = peritherm::output::RunSummary::read(&run).unwrap();
    let plan = |out: &Path| {
        let o = crate::common::cli::peritherm(&[
            "partition",
            case,
            "--ranks",
            "1,2",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(out.join("partition.json")).unwrap()
    };
    let (a, b) = (plan(&dir.path().join("a")), plan(&dir.path().join("b")));
    assert_eq!(a, b, "the same plan twice");
    let v: serde_json::Value = serde_json::from_str(&a).unwrap();
    assert_eq!(v["rows"][0]["bonds"].as_u64(), Some(summary.bonds as u64));
    let half = v["rows"][1]["nodes"].as_array().unwrap();
    let (lo, hi) = (half[0].as_u64().unwrap(), half[1].as_u64().unwrap());
    assert_eq!(
        lo + hi,
        summary.nodes as u64,
        "two ranks hold every node once"
    );
    // cut by pairs, not nodes (the fine region's rows are longer): neither rank holds more
    // than 60 % of the bonds
    let most = v["rows"][1]["bonds"].as_u64().unwrap() as f64;
    assert!(
        most <= 0.6 * summary.bonds as f64,
        "{most} of {} bonds",
        summary.bonds
    );
    assert!(v["rows"][1]["ghosts"].as_u64().unwrap() > 0);
    for args in [
        vec!["partition", case, "--ranks", "0"],
        vec!["partition", "no-such-case.toml", "--ranks", "2"],
    ] {
        let o = crate::common::cli::peritherm(&args);
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(
            err.lines().filter(|l| l.starts_with("error")).count(),
            1,
            "{err}"
        );
    }
}
