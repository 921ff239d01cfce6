//! Hostile input and interrupted runs (issue 15), as a user meets them on the command line:
//! every example ends with one line naming the file and the key, a non-zero exit, within
//! 5 s and under 1 GiB of address space ([`crate::common::hostile`]), and `--out` never mixes runs.

use crate::common::hostile::{assert_refused, entries, peritherm, wait_for, write_case, PLATE};
use std::path::Path;
use std::time::Duration;

/// A 1D bar of `region` (its spacing or cells line).
fn bar(region: &str) -> String {
    format!(
        "dimension = 1\n[domain]\nmin = [0.0]\nmax = [1.0]\n[[region]]\nname = \"bar\"\n{region}\nhorizon = {{ factor = 3.0 }}\n[material.steel]\nconductivity = 50.0\ndensity = 7850.0\nspecific_heat = 420.0\n[time]\nend = 2.0\n"
    )
}

/// PLATE with its boundary value replaced by the expression `e`.
fn with_value(e: &str) -> String {
    PLATE.replace("value = 100.0", &format!("value = \"{e}\""))
}

/// (what, case text, key) of every refused example of issue 15 that is a case file.
fn refusals() -> Vec<(&'static str, String, &'static str)> {
    let cube = PLATE
        .replace("dimension = 2", "dimension = 3")
        .replace("[0.0, 0.0]", "[0.0, 0.0, 0.0]")
        .replace("[1.0, 1.0]", "[1.0, 1.0, 1.0]")
        .replace("[20, 20]", "[10, 10, 10]")
        .replace("factor = 3.0", "factor = 4294967296.0");
    let crack = |c: &str| format!("{PLATE}[[crack]]\n{c}\n");
    vec![
        ("spacing 1e-9", bar("spacing = 1e-9"), "region[0].spacing"),
        ("cells 99999999999", bar("cells = [99999999999]"), "region[0].cells"),
        ("factor 2^32 in 3D", cube, "region[0].horizon.factor"),
        ("7000 parens", with_value(&format!("{}1{}", "(".repeat(7000), ")".repeat(7000))), "boundary.x_min.value"),
        ("20000-term ^", with_value(&vec!["2"; 20_000].join("^")), "boundary.x_min.value"),
        ("65000 minus", with_value(&format!("{}1", "-".repeat(65_000))), "boundary.x_min.value"),
        ("87000-term sum", with_value(&vec!["1"; 87_000].join("+")), "boundary.x_min.value"),
        ("300 parens", with_value(&format!("{}1{}", "(".repeat(300), ")".repeat(300))), "boundary.x_min.value"),
        ("dt 1e-300", PLATE.replace("end = 2.0", "end = 2.0\ndt = 1e-300"), "time.dt"),
        ("dt 1e-12 to 1 s", PLATE.replace("end = 2.0", "end = 1.0\ndt = 1e-12"), "time.dt"),
        ("factor 1e4", PLATE.replace("factor = 3.0", "factor = 1e4"), "region[0].horizon.factor"),
        (
            "radius 2^32 lattice",
            PLATE
                .replace("factor = 3.0", "radius = 4294967296.0")
                .replace("[time]", "[kernel]\ncalibration = \"lattice\"\n[time]"),
            "region[0].horizon.radius",
        ),
        ("horizon below spacing", PLATE.replace("factor = 3.0", "factor = 0.5"), "region[0].horizon.factor"),
        ("zero-length crack", crack("points = [[0.5, 0.5], [0.5, 0.5]]"), "crack[0].points[1]"),
        ("crack outside", crack("points = [[2.0, 2.0], [3.0, 3.0]]"), "crack[0].points"),
        ("crack along an edge", crack("points = [[0.0, 1.0], [1.0, 1.0]]"), "crack[0].points"),
        (
            "initial_length beyond the path",
            crack("points = [[0.2, 0.5], [0.8, 0.5]]\nspeed = 0.1\ninitial_length = 5.0"),
            "crack[0].initial_length",
        ),
        (
            "duplicate region names",
            PLATE.replace("[material.steel]", "[[region]]\nname = \"plate\"\ncells = [20, 20]\nhorizon = { factor = 3.0 }\n[material.steel]"),
            "region[1].name",
        ),
        ("subnormal density", PLATE.replace("density = 7850.0", "density = 1e-320"), "material.steel.density"),
        ("subnormal specific heat", PLATE.replace("specific_heat = 420.0", "specific_heat = 1e-320"), "material.steel.specific_heat"),
        (
            "reference length 0",
            PLATE.replace("[time]", "[reference.solution]\nkind = \"square_fixed_edges\"\nx0 = 0.0\ny0 = 0.0\nlength = 0.0\ndiffusivity = 1.0\nedge = 0.0\ninitial = 1.0\n[time]"),
            "reference.solution",
        ),
        (
            "reference diffusivity -1",
            PLATE.replace("[time]", "[reference.solution]\nkind = \"square_fixed_edges\"\nx0 = 0.0\ny0 = 0.0\nlength = 1.0\ndiffusivity = -1.0\nedge = 0.0\ninitial = 1.0\n[time]"),
            "reference.solution",
        ),
        (
            "f32 with an implicit integrator",
            PLATE.replace("[time]", "[kernel]\nprecision = \"f32\"\n[time]\nintegrator = \"crank_nicolson\"\ndt = 0.1"),
            "kernel.precision",
        ),
        (
            "an unknown column index",
            PLATE.replace("[time]", "[kernel]\ncolumns = \"u8\"\n[time]"),
            "kernel.columns",
        ),
        (
            "phase change with rk4",
            PLATE.replace("[boundary.x_min]", "[material.steel.phase_change]\ntemperature = 500.0\nlatent_heat = 3e5\nfrozen_conductivity = 40.0\nfrozen_specific_heat = 400.0\n[boundary.x_min]")
                .replace("[time]", "[time]\nintegrator = \"rk4\""),
            "time.integrator",
        ),
    ]
}

/// Every case-file example: `check` and `run` refuse it alike (the same one line), within
/// 5 s and 1 GiB, and `run` writes no `--out`.
#[test]
fn every_hostile_case_is_refused_alike_by_check_and_run() {
    refused_alike(refusals(), "hostile", crate::common::hostile::MAX_SECONDS);
}

/// Each of `cases` (what, text, key), written as `<prefix>_<k>.toml`: `run` and `check` end
/// with the same one line naming the file and the key, each within `seconds`, and `run`
/// writes no `--out`.
fn refused_alike(cases: Vec<(&'static str, String, &'static str)>, prefix: &str, seconds: f64) {
    let dir = tempfile::tempdir().unwrap();
    for (k, (what, text, key)) in cases.into_iter().enumerate() {
        let name = format!("{prefix}_{k}.toml");
        let case = write_case(dir.path(), &name, &text);
        let case = case.to_str().unwrap();
        let out = dir.path().join(format!("out_{k}"));
        let run = peritherm(&["run", case, "--out", out.to_str().unwrap()]);
        assert_refused(what, &run, &name, key);
        assert!(!out.exists(), "{what}: --out written");
        let check = peritherm(&["check", case]);
        assert_refused(what, &check, &name, key);
        for (o, command) in [(&run, "run"), (&check, "check")] {
            assert!(
                o.seconds < seconds,
                "{what}: {command} took {:.2} s",
                o.seconds
            );
        }
        // the machine's free memory changes between the two calls: compared without it
        assert_eq!(
            without_free_memory(&check.stderr),
            without_free_memory(&run.stderr),
            "{what}: check and run differ"
        );
    }
}

/// Issue 36's examples, which `check` passed and `run` refused (the expressions only after
/// stepping to the first output): (what, case text, key).
fn check_passed_run_refused() -> Vec<(&'static str, String, &'static str)> {
    let insulated = PLATE.replace(
        "type = \"temperature\"\nvalue = 100.0",
        "type = \"insulated\"",
    );
    vec![
        (
            "boundary value 1/0",
            with_value("1/0"),
            "boundary.x_min.value",
        ),
        (
            "boundary value ln(0)",
            with_value("ln(0)"),
            "boundary.x_min.value",
        ),
        (
            "source sqrt(-1)",
            format!("{PLATE}[source]\nvalue = \"sqrt(-1)\"\n"),
            "source.value",
        ),
        (
            "steady, every boundary insulated",
            insulated.replace("end = 2.0", "end = 2.0\nintegrator = \"steady\""),
            "time.integrator",
        ),
        (
            "adaptive, dt_max 1e-300",
            PLATE.replace(
                "end = 2.0",
                "end = 2.0\nintegrator = \"crank_nicolson\"\ntolerance = 1e-3\ndt_max = 1e-300",
            ),
            "time.dt_max",
        ),
    ]
}

/// Each of them: `check` and `run` end with the same one line within 2 s (issue 36), and
/// `run` writes nothing.
#[test]
fn what_run_refuses_check_refuses_within_two_seconds() {
    refused_alike(check_passed_run_refused(), "refused", 2.0);
}

/// The message with the "(machine: … available" figure of the memory budget cut out (the
/// " of " searched after it: the message says "80% of the available memory" before it).
fn without_free_memory(msg: &str) -> String {
    let Some(a) = msg.find("(machine:") else {
        return msg.to_string();
    };
    match msg[a..].find(" of ") {
        Some(b) => format!("{}{}", &msg[..a], &msg[a + b..]),
        None => msg.to_string(),
    }
}

/// `peritherm fem --h 1e-9` is refused by the budget, and `--max-memory` overrides the
/// machine's memory both ways (a tiny limit refuses the small plate, naming its key).
#[test]
fn the_budget_is_printed_and_overridden() {
    let dir = tempfile::tempdir().unwrap();
    let case = write_case(dir.path(), "bar.toml", &bar("cells = [10]"));
    let out = dir.path().join("fem");
    let o = peritherm(&[
        "fem",
        case.to_str().unwrap(),
        "--h",
        "1e-9",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_refused("fem --h 1e-9", &o, "bar.toml", "--h");
    assert!(!out.exists());
    let plate = write_case(dir.path(), "plate.toml", PLATE);
    let plate = plate.to_str().unwrap();
    let o = peritherm(&["check", plate]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(o.stdout.contains("estimate: 4.000e2 nodes"), "{}", o.stdout);
    assert!(o.stdout.contains("available"), "{}", o.stdout);
    let o = peritherm(&["check", plate, "--max-memory", "1K"]);
    assert_refused("--max-memory 1K", &o, "plate.toml", "region[0].cells");
    assert!(o.stderr.contains("--max-memory"), "{}", o.stderr);
    let o = peritherm(&["check", plate, "--max-memory", "1T"]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

/// A run of PLATE with these outputs into `out` (end at the last).
fn run_plate(
    dir: &Path,
    name: &str,
    outputs: &str,
    extra: &str,
    out: &Path,
) -> crate::common::hostile::Outcome {
    let last = outputs.rsplit(',').next().unwrap().trim();
    let text = PLATE.replace("end = 2.0", &format!("end = {last}\noutputs = [{outputs}]")) + extra;
    let case = write_case(dir, name, &text);
    peritherm(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ])
}

/// A rerun replaces `--out` whole: a shorter rerun leaves no stale field, a rerun that fails
/// at its third output leaves its own two fields and a run.json saying it failed (which
/// `table` refuses); a directory holding other files is not touched.
#[test]
fn output_directories_are_transactional() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = run_plate(dir.path(), "five.toml", "1, 2, 3, 4, 5", "", &out);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert_eq!(
        entries(&out)
            .iter()
            .filter(|e| e.starts_with("field_"))
            .count(),
        10
    );
    let o = run_plate(dir.path(), "two.toml", "1, 2", "", &out);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let want = [
        "case.toml",
        "field_1.csv",
        "field_1.vtu",
        "field_2.csv",
        "field_2.vtu",
        "fields.pvd",
        "run.json",
    ];
    assert_eq!(entries(&out), want, "stale files after a shorter rerun");
    assert!(std::fs::read_to_string(out.join("run.json"))
        .unwrap()
        .contains("two.toml"));
    // a source that is finite at every output time (which `check` and the set-up evaluate)
    // but infinite at t = 2.5 s, the midpoint stage of RK4's step from 2 to 3 s: fields 1 and
    // 2 are written, then the state turns non-finite before the third output
    let blow = "[source]\nvalue = \"1/(t - 2.5)\"\n";
    let o = run_plate(dir.path(), "blow.toml", "1, 2, 3, 4, 5", blow, &out);
    assert_refused("non-finite", &o, "blow.toml", "source.value");
    let json = std::fs::read_to_string(out.join("run.json")).unwrap();
    assert!(
        json.contains("\"failed\"") && json.contains("blow.toml"),
        "{json}"
    );
    assert_eq!(entries(&out), want, "mixed output after a failed rerun");
    let o = peritherm(&["table", out.to_str().unwrap()]);
    assert_refused("table of a failed run", &o, "run.json", "failed");
    // nothing staged is left beside --out
    assert_eq!(
        entries(dir.path())
            .iter()
            .filter(|e| e.starts_with('.'))
            .count(),
        0
    );
    // a directory of other files is refused, untouched
    let mine = dir.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let o = run_plate(dir.path(), "two.toml", "1, 2", "", &mine);
    assert_refused("foreign --out", &o, "mine", "--out");
    assert_eq!(entries(&mine), ["notes.txt"]);
}

/// SIGTERM during a long run: exit 130, `--out` holds the complete fields and a run.json
/// saying the run was interrupted and when, no `.partial` file and nothing staged beside it.
#[test]
fn an_interrupted_run_says_so_and_leaves_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // 1e7 steps of 1e-3 s: far longer than the test waits
    let text = PLATE.replace(
        "end = 2.0",
        "end = 1e4\ndt = 1e-3\noutputs = [0.01, 0.02, 1e4]",
    );
    let case = write_case(dir.path(), "long.toml", &text);
    let mut child = crate::common::cli::command()
        .args([
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // wait until the second field is in the staged directory
    let staged = || {
        entries(dir.path())
            .iter()
            .filter(|e| e.starts_with(".out.staged"))
            .any(|e| dir.path().join(e).join("field_2.vtu").exists())
    };
    assert!(
        wait_for(Duration::from_secs(20), staged),
        "the run never wrote field_2"
    );
    let kill = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(json["status"], "interrupted");
    let t = json["time"].as_f64().unwrap();
    assert!(t >= 0.02, "interrupted at {t}");
    let names = entries(&out);
    assert!(names.iter().all(|n| !n.ends_with(".partial")), "{names:?}");
    for f in json["fields"].as_array().unwrap() {
        assert!(out.join(f.as_str().unwrap()).exists(), "{f}");
    }
    assert_eq!(entries(dir.path()), ["long.toml", "out"]);
    let o = peritherm(&["table", out.to_str().unwrap()]);
    assert_refused("table of an interrupted run", &o, "run.json", "interrupted");
}

/// `compare`, `plot` and `table` refuse what they cannot read honestly: a field cut mid-number,
/// a header-only field, NaN nodes, a 1D run against a 2D run, `--exclude-tips nan`.
#[test]
fn comparisons_refuse_incomplete_or_mismatched_fields() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let o = run_plate(dir.path(), "a.toml", "1, 2", "", &a);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let field = std::fs::read_to_string(a.join("field_1.csv")).unwrap();
    let copy = |name: &str, text: &str| {
        let d = dir.path().join(name);
        std::fs::create_dir(&d).unwrap();
        for f in entries(&a) {
            std::fs::copy(a.join(&f), d.join(&f)).unwrap();
        }
        std::fs::write(d.join("field_1.csv"), text).unwrap();
        d
    };
    let half = copy("half", &field[..field.len() / 2]);
    let header = copy(
        "header",
        &(field.lines().next().unwrap().to_string() + "\n"),
    );
    let mut rows: Vec<String> = field.lines().map(str::to_string).collect();
    let mut cells: Vec<&str> = rows[5].split(',').collect();
    cells[3] = "NaN";
    rows[5] = cells.join(",");
    let nan = copy("nan", &(rows.join("\n") + "\n"));
    let (a_s, run) = (a.to_str().unwrap(), |d: &Path| {
        d.to_str().unwrap().to_string()
    });
    for (what, d) in [
        ("cut mid-number", &half),
        ("header only", &header),
        ("NaN node", &nan),
    ] {
        let o = peritherm(&["compare", a_s, &run(d)]);
        assert_refused(what, &o, "field_1.csv", "");
        let o = peritherm(&["compare", &run(d), a_s]);
        assert_refused(what, &o, "field_1.csv", "");
        let o = peritherm(&["plot", &run(d)]);
        assert_refused(what, &o, "field_1.csv", "");
    }
    let o = peritherm(&["compare", a_s, a_s, "--exclude-tips", "nan"]);
    assert_refused("--exclude-tips nan", &o, "--exclude-tips", "");
    let line = dir.path().join("line");
    let case = write_case(
        dir.path(),
        "line.toml",
        &bar("cells = [20]").replace("end = 2.0", "end = 2.0\noutputs = [1.0, 2.0]"),
    );
    let o = peritherm(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        &run(&line),
        "--quiet",
    ]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    let o = peritherm(&["compare", a_s, &run(&line)]);
    assert_refused("2D against 1D", &o, "line", "axes");
    let o = peritherm(&["compare", a_s, a_s]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

/// A reference table of 1e308 temperatures never compares as an exact match: the run is
/// refused naming the table, or its difference is reported as huge.
#[test]
fn an_overflowing_reference_is_not_an_exact_match() {
    let dir = tempfile::tempdir().unwrap();
    let mut table = String::from("time,x,y,temperature\n");
    for t in [1.0, 2.0] {
        for i in 0..=10 {
            for j in 0..=10 {
                table += &format!("{t},{},{},1e308\n", i as f64 / 10.0, j as f64 / 10.0);
            }
        }
    }
    std::fs::write(dir.path().join("ref.csv"), table).unwrap();
    let out = dir.path().join("out");
    let o = run_plate(
        dir.path(),
        "ref.toml",
        "1, 2",
        "[reference]\nfile = \"ref.csv\"\n",
        &out,
    );
    if o.code == Some(0) {
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
        let d = json["reference"][0]["max_abs_diff"].as_f64().unwrap();
        assert!(d > 1e300, "max|diff| = {d}");
    } else {
        // the table's interpolation (naming ref.csv) or the comparison (naming ref.toml)
        assert_refused("1e308 reference", &o, "ref.", "reference");
    }
}

/// A case on the mesh file `file` (absolute path) with one region `plate`, or `regions`.
fn mesh_case(file: &Path, regions: &str) -> String {
    format!(
        "dimension = 2\n[mesh]\nfile = \"{}\"\n{regions}[material.steel]\nconductivity = 50.0\n\
         density = 7850.0\nspecific_heat = 420.0\n[boundary.left]\ntype = \"temperature\"\n\
         value = 100.0\n[time]\nend = 2.0\n",
        file.display()
    )
}

const PLATE_REGION: &str = "[[region]]\nname = \"plate\"\nhorizon = { factor = 3.0 }\n";

/// Text replacements in a file: (from, to), each made once.
type Edits = Vec<(&'static str, &'static str)>;

/// Issue 36's mesh examples, which ran without a word, edited from `tests/data/square_quad.msh`
/// into `dir`: an element counted twice, a node tag given twice, two boundaries named `left`.
fn silently_wrong_meshes(dir: &Path) -> Vec<(&'static str, String, &'static str)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/square_quad.msh");
    let mesh = std::fs::read_to_string(src).unwrap();
    let edits: [(&str, &str, Edits); 3] = [
        (
            "duplicated element",
            "dup.msh",
            vec![
                ("$Elements\n5 96 1 96\n", "$Elements\n5 97 1 97\n"),
                ("2 1 3 64\n", "2 1 3 65\n"),
                ("33 1 5 33 32 \n", "33 1 5 33 32 \n97 1 5 33 32 \n"),
            ],
        ),
        (
            "duplicated node tag",
            "dupnode.msh",
            vec![("\n5\n6\n7\n", "\n5\n5\n7\n")],
        ),
        (
            "two groups named left",
            "dupname.msh",
            vec![("1 2 \"bottom\"", "1 2 \"left\"")],
        ),
    ];
    let mut cases = Vec::new();
    for (what, name, replacements) in edits {
        let mut text = mesh.clone();
        for (from, to) in replacements {
            assert!(
                text.contains(from),
                "{what}: the fixture changed: update this edit"
            );
            text = text.replacen(from, to, 1);
        }
        std::fs::write(dir.join(name), text).unwrap();
        cases.push((what, mesh_case(&dir.join(name), PLATE_REGION), "mesh.file"));
    }
    cases
}

// Each of issue 36's silently wrong meshes is refused alike by check and run, within 2 s,
// naming the mesh file and the entity, with nothing written.
#[test]
fn silently_wrong_meshes_are_refused_alike() {
    let dir = tempfile::tempdir().unwrap();
    let cases = silently_wrong_meshes(dir.path());
    let entities = [
        "elements 33 and 97",
        "node tag 5 appears twice",
        "named `left`",
    ];
    for ((what, text, _), entity) in cases.iter().zip(entities) {
        let case = write_case(dir.path(), "named.toml", text);
        let o = peritherm(&["check", case.to_str().unwrap()]);
        assert!(
            o.stderr.contains(".msh: "),
            "{what}: names no mesh file: {}",
            o.stderr
        );
        assert!(
            o.stderr.contains(entity),
            "{what}: names no `{entity}`: {}",
            o.stderr
        );
    }
    refused_alike(cases, "mesh", 2.0);
}

#[test]
fn an_empty_region_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/square_quad.msh");
    let mesh = std::fs::read_to_string(src).unwrap();
    let empty = mesh.replace("5\n1 2 \"bottom\"", "6\n2 9 \"hole\"\n1 2 \"bottom\"");
    assert_ne!(empty, mesh, "the fixture changed: update this edit");
    std::fs::write(dir.path().join("empty.msh"), empty).unwrap();
    let hole = format!("{PLATE_REGION}[[region]]\nname = \"hole\"\nhorizon = {{ factor = 3.0 }}\n");
    let c = write_case(
        dir.path(),
        "empty.toml",
        &mesh_case(&dir.path().join("empty.msh"), &hole),
    );
    let o = peritherm(&["check", c.to_str().unwrap()]);
    assert_refused("empty region", &o, "empty.toml", "region[1].name");
}

/// `check` accepts the bundled cases whose set-up is quick (the adaptive crack plate among
/// them: it has time.tolerance and no time.dt); `tests/cases/bundled.rs` takes every bundled case
/// through the same validation path ([`peritherm::prepare`]) before it runs a few steps.
#[test]
fn check_accepts_the_quick_bundled_cases() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for name in [
        "bar_dirichlet",
        "bar_flux",
        "bar_insulated_left",
        "crack_plate",
        "dh_crack_plate_k1_m1",
        "dh_crack_plate_k1_m1_adaptive",
        "dh_crack_plate_k1_m1_implicit",
        "growing_cracks",
        "ice_in_water",
        "pipe_cooling_convective",
        "pipe_freezing",
        "planar_freezing",
        "sphere_cooling",
        "two_inclined_cracks",
    ] {
        let path = root.join("cases").join(format!("{name}.toml"));
        let o = peritherm(&["check", path.to_str().unwrap()]);
        assert_eq!(o.code, Some(0), "{name}: {}", o.stderr);
        assert!(o.stdout.contains("estimate:"), "{name}: {}", o.stdout);
    }
}
