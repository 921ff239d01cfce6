//! The case schema's typed sections: what each boundary type accepts, and the one-line
//! errors naming the file and the key of what it refuses.

use super::*;
use peritherm_core::bc::{FaceBc, Layer};

/// The text of a 2D box case, `c.toml`, built from parts: the test's changes to one plate of
/// one steel region ending at t = 1 s.
#[derive(Clone, Copy)]
struct Text<'a> {
    /// The lines of the one `[[region]]` that divide it (spacing or cells).
    resolution: &'a str,
    /// The `[boundary]` tables, verbatim.
    boundary: &'a str,
    /// Further tables before `[time]`, verbatim.
    sections: &'a str,
    /// Further `[time]` keys after `end`.
    time: &'a str,
}

impl<'a> Text<'a> {
    /// The case with no boundary table and nothing else.
    const PLAIN: Text<'static> = Text {
        resolution: "spacing = 0.1",
        boundary: "",
        sections: "",
        time: "",
    };

    /// The case with `boundary` as the `[boundary.x_min]` table's body.
    fn x_min(boundary: &str) -> String {
        let table = format!("[boundary.x_min]\n{boundary}");
        Text {
            boundary: &table,
            ..Text::PLAIN
        }
        .text()
    }

    /// The case file's text (the parts left empty leave no line).
    fn text(&self) -> String {
        let head = "dimension = 2\n[domain]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n[[region]]\nname = \"plate\"";
        let body = "horizon = { factor = 3.0 }\n[material.steel]\nconductivity = 50.0\ndensity = 7850.0\nspecific_heat = 420.0";
        let parts = [
            head,
            self.resolution,
            body,
            self.boundary,
            self.sections,
            "[time]\nend = 1.0",
            self.time,
        ];
        let lines: Vec<&str> = parts.into_iter().filter(|p| !p.is_empty()).collect();
        lines.join("\n") + "\n"
    }
}

/// The case of `text`, as `c.toml`.
fn parse(text: &str) -> Result<Case> {
    Case::parse(text, Path::new("c.toml"))
}

/// The condition on x_min of [`Text::x_min`]`(boundary)`.
fn face(boundary: &str) -> FaceBc {
    let c = parse(&Text::x_min(boundary)).unwrap();
    c.spec.faces[0].clone()
}

/// The one-line error of the case `text`, naming the file.
fn error_of(text: &str) -> String {
    let e = parse(text).unwrap_err().to_string();
    assert!(!e.contains('\n') && e.starts_with("c.toml: "), "{e}");
    e
}

/// The one-line error of [`Text::x_min`]`(boundary)`.
fn error(boundary: &str) -> String {
    error_of(&Text::x_min(boundary))
}

/// Asserts that the error of [`Text::x_min`]`(boundary)` says each of `parts`.
fn refused(boundary: &str, parts: &[&str]) {
    let e = error(boundary);
    for part in parts {
        assert!(e.contains(part), "{e}\n  lacks: {part}");
    }
}

#[test]
fn each_type_and_method_gives_its_condition() {
    let t = "type = \"temperature\"\nvalue = 100";
    assert!(matches!(face(t), FaceBc::NodalTemperature { layers, .. } if layers == 1.0));
    assert!(matches!(
        face(&format!("{t}\nlayers = 2")),
        FaceBc::NodalTemperature { layers, .. } if layers == 2.0
    ));
    for (m, layer) in [("mirror", Layer::Mirror), ("naive", Layer::Naive)] {
        assert!(matches!(
            face(&format!("{t}\nmethod = \"{m}\"")),
            FaceBc::LayerTemperature { layer: l, .. } if l == layer
        ));
    }
    assert_eq!(face("type = \"free\""), FaceBc::Free);
    assert_eq!(face("type = \"insulated\""), FaceBc::LayerInsulated);
    assert_eq!(
        face("type = \"insulated\"\nmethod = \"free\""),
        FaceBc::Free
    );
    assert!(matches!(
        face("type = \"flux\"\nvalue = \"10*t\""),
        FaceBc::LayerFlux { .. }
    ));
    assert!(matches!(
        face("type = \"flux\"\nvalue = 5.0\nmethod = \"relation\""),
        FaceBc::RelationFlux { .. }
    ));
    let c = "type = \"convection\"\nh = 10\nambient = 20.0";
    assert!(matches!(face(c), FaceBc::Convection { h, .. } if h == 10.0));
    assert!(matches!(
        face(&format!("{c}\nmethod = \"mirror\"")),
        FaceBc::LayerConvection { .. }
    ));
}

#[test]
fn an_inline_table_is_the_same_condition() {
    let text = Text {
        boundary: "[boundary]\nx_min = { type = \"flux\", value = 1.0, method = \"relation\" }",
        ..Text::PLAIN
    };
    let c = parse(&text.text()).unwrap();
    assert!(matches!(c.spec.faces[0], FaceBc::RelationFlux { .. }));
}

#[test]
fn keys_of_another_type_are_unknown_fields() {
    refused(
        "type = \"temperature\"\nvalue = 1.0\nh = 5.0",
        &[
            "line 13: unknown field `h`",
            "`value`, `method`, `layers` (in boundary.x_min)",
        ],
    );
    refused(
        "type = \"insulated\"\nvalue = 1.0",
        &["unknown field `value`, expected `method` (in boundary.x_min)"],
    );
    refused(
        "type = \"free\"\nmethod = \"mirror\"",
        &["unknown field `method`", "boundary.x_min"],
    );
}

#[test]
fn missing_and_mistyped_keys_name_the_key() {
    refused(
        "type = \"flux\"",
        &["missing field `value` (in boundary.x_min)"],
    );
    refused(
        "type = \"convection\"\nambient = 1.0",
        &["missing field `h` (in boundary.x_min)"],
    );
    refused("value = 1.0", &["missing field `type` (in boundary.x_min)"]);
    refused(
        "type = \"hot\"\nvalue = 1.0",
        &["unknown variant `hot`, expected one of `free`, `temperature`, `insulated`, `flux`, `convection` (in boundary.x_min.type)"],
    );
    refused(
        "type = \"temperature\"\nvalue = 1.0\nmethod = \"mirrored\"",
        &["unknown variant `mirrored`, expected one of `nodal`, `mirror`, `naive` (in boundary.x_min.method)"],
    );
    refused(
        "type = \"temperature\"\nvalue = true",
        &["expected a number or an expression string (in boundary.x_min.value)"],
    );
    refused(
        "type = \"temperature\"\nvalue = 1.0\nlayers = \"two\"",
        &["(in boundary.x_min.layers)"],
    );
}

#[test]
fn values_are_checked_after_parsing() {
    refused(
        "type = \"temperature\"\nvalue = 1.0\nmethod = \"mirror\"\nlayers = 2",
        &["c.toml: boundary.x_min.layers: does not apply to method = \"mirror\""],
    );
    refused(
        "type = \"temperature\"\nvalue = 1.0\nlayers = 1.5",
        &["boundary.x_min.layers: must be a whole number >= 1, got 1.5"],
    );
    refused(
        "type = \"convection\"\nh = -1.0\nambient = 1.0",
        &["boundary.x_min.h: must be a positive number, got -1"],
    );
    refused(
        "type = \"flux\"\nvalue = \"exq(t)\"",
        &["boundary.x_min.value: expression `exq(t)`"],
    );
}

#[test]
fn an_unknown_key_names_its_line_and_table() {
    let free = Text {
        boundary: "[boundary.x_min]\ntype = \"free\"",
        ..Text::PLAIN
    };
    let e = error_in(Text {
        time: "step = 1",
        ..free
    });
    assert!(
        e.starts_with("c.toml: line 17: unknown field `step`"),
        "{e}"
    );
    assert!(e.ends_with("(in time)"), "{e}");
    let history = "[history]\npoints = [[0.5, 0.5]]\ninterval = 0.1\nplot = \"log\"";
    let e = error_in(Text {
        sections: history,
        ..free
    });
    assert!(
        e.contains(
            "unknown variant `log`, expected `temperature` or `normalised` (in history.plot)"
        ),
        "{e}"
    );
}

/// The one-line error of the case [`Text`] `text`.
fn error_in(text: Text) -> String {
    error_of(&text.text())
}

/// The one-line error of the case with `sections` before `[time]`.
fn error_with(sections: &str) -> String {
    error_in(Text {
        sections,
        ..Text::PLAIN
    })
}

/// Keys of which exactly one (or at most one) may be given: the same messages, keyed to
/// the file and the dotted key, whichever way the rule is broken.
#[test]
fn one_of_several_keys() {
    let resolution = |resolution| Text {
        resolution,
        ..Text::PLAIN
    };
    let cases = [
        (
            error_with("[mesh]\nfile = \"plate.msh\""),
            "mesh: give [domain] (a built-in box) or [mesh] (a gmsh file), not both",
        ),
        (
            error_in(resolution("spacing = 0.1\ncells = [10, 10]")),
            "region[0].spacing: give spacing or cells, not both",
        ),
        (
            error_in(resolution("")),
            "region[0].spacing: missing: give spacing or cells",
        ),
        (
            error_with("[[crack]]"),
            "crack[0]: give either group or points",
        ),
        (
            error_with("[[crack]]\ngroup = \"a\"\npoints = [[0.5, 0.0], [0.5, 0.5]]"),
            "crack[0]: give either group or points",
        ),
        (
            error_with("[kernel]\nlinear_consistency = true\nconsistency = \"linear\""),
            "kernel.linear_consistency: give either linear_consistency or consistency, not both",
        ),
        (
            error_with("[reference]\nline_y = 0.5"),
            "reference: give exactly one of `solution` (analytical), `file` (a CSV table) or `fem`",
        ),
        (
            error_with("[reference]\nfile = \"t.csv\"\nfem = {}"),
            "reference: give exactly one of `solution`",
        ),
    ];
    for (e, says) in cases {
        assert!(e.contains(&format!("c.toml: {says}")), "{e}");
    }
    assert!(parse(&resolution("cells = [10, 10]").text()).is_ok());
}
