//! The case schema's typed sections: what each boundary type accepts, and the one-line
//! errors naming the file and the key of what it refuses.

use super::*;
use peritherm_core::bc::{FaceBc, Layer};

/// A 2D box case with `boundary` as the `[boundary.x_min]` table's body.
fn case(boundary: &str) -> String {
    format!(
        "dimension = 2\n[domain]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n[[region]]\nname = \"plate\"\nspacing = 0.1\nhorizon = {{ factor = 3.0 }}\n[material.steel]\nconductivity = 50.0\ndensity = 7850.0\nspecific_heat = 420.0\n[boundary.x_min]\n{boundary}\n[time]\nend = 1.0\n"
    )
}

/// The condition on x_min of [`case`]`(boundary)`.
fn face(boundary: &str) -> FaceBc {
    let c = Case::parse(&case(boundary), Path::new("c.toml")).unwrap();
    c.spec.faces[0].clone()
}

/// The one-line error of [`case`]`(boundary)`.
fn error(boundary: &str) -> String {
    let e = Case::parse(&case(boundary), Path::new("c.toml"))
        .unwrap_err()
        .to_string();
    assert!(!e.contains('\n') && e.starts_with("c.toml: "), "{e}");
    e
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
    let text = case("type = \"flux\"\nvalue = 1.0").replace(
        "[boundary.x_min]\ntype = \"flux\"\nvalue = 1.0",
        "[boundary]\nx_min = { type = \"flux\", value = 1.0, method = \"relation\" }",
    );
    let c = Case::parse(&text, Path::new("c.toml")).unwrap();
    assert!(matches!(c.spec.faces[0], FaceBc::RelationFlux { .. }));
}

#[test]
fn keys_of_another_type_are_unknown_fields() {
    let e = error("type = \"temperature\"\nvalue = 1.0\nh = 5.0");
    assert!(e.contains("line 13: unknown field `h`"), "{e}");
    assert!(
        e.contains("`value`, `method`, `layers` (in boundary.x_min)"),
        "{e}"
    );
    let e = error("type = \"insulated\"\nvalue = 1.0");
    assert!(
        e.contains("unknown field `value`, expected `method` (in boundary.x_min)"),
        "{e}"
    );
    let e = error("type = \"free\"\nmethod = \"mirror\"");
    assert!(
        e.contains("unknown field `method`") && e.contains("boundary.x_min"),
        "{e}"
    );
}

#[test]
fn missing_and_mistyped_keys_name_the_key() {
    let e = error("type = \"flux\"");
    assert!(
        e.contains("missing field `value` (in boundary.x_min)"),
        "{e}"
    );
    let e = error("type = \"convection\"\nambient = 1.0");
    assert!(e.contains("missing field `h` (in boundary.x_min)"), "{e}");
    let e = error("value = 1.0");
    assert!(
        e.contains("missing field `type` (in boundary.x_min)"),
        "{e}"
    );
    let e = error("type = \"hot\"\nvalue = 1.0");
    assert!(
        e.contains("unknown variant `hot`, expected one of `free`, `temperature`, `insulated`, `flux`, `convection` (in boundary.x_min.type)"),
        "{e}"
    );
    let e = error("type = \"temperature\"\nvalue = 1.0\nmethod = \"mirrored\"");
    assert!(
        e.contains("unknown variant `mirrored`, expected one of `nodal`, `mirror`, `naive` (in boundary.x_min.method)"),
        "{e}"
    );
    let e = error("type = \"temperature\"\nvalue = true");
    assert!(
        e.contains("expected a number or an expression string (in boundary.x_min.value)"),
        "{e}"
    );
    let e = error("type = \"temperature\"\nvalue = 1.0\nlayers = \"two\"");
    assert!(e.contains("(in boundary.x_min.layers)"), "{e}");
}

#[test]
fn values_are_checked_after_parsing() {
    let e = error("type = \"temperature\"\nvalue = 1.0\nmethod = \"mirror\"\nlayers = 2");
    assert!(
        e.contains("c.toml: boundary.x_min.layers: does not apply to method = \"mirror\""),
        "{e}"
    );
    let e = error("type = \"temperature\"\nvalue = 1.0\nlayers = 1.5");
    assert!(
        e.contains("boundary.x_min.layers: must be a whole number >= 1, got 1.5"),
        "{e}"
    );
    let e = error("type = \"convection\"\nh = -1.0\nambient = 1.0");
    assert!(
        e.contains("boundary.x_min.h: must be a positive number, got -1"),
        "{e}"
    );
    let e = error("type = \"flux\"\nvalue = \"exq(t)\"");
    assert!(
        e.contains("boundary.x_min.value: expression `exq(t)`"),
        "{e}"
    );
}

#[test]
fn an_unknown_key_names_its_line_and_table() {
    let text = case("type = \"free\"").replace("end = 1.0", "end = 1.0\nstep = 1");
    let e = Case::parse(&text, Path::new("c.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("c.toml: line 17: unknown field `step`"),
        "{e}"
    );
    assert!(e.ends_with("(in time)"), "{e}");
    let text = case("type = \"free\"").replace(
        "[time]",
        "[history]\npoints = [[0.5, 0.5]]\ninterval = 0.1\nplot = \"log\"\n[time]",
    );
    let e = Case::parse(&text, Path::new("c.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "unknown variant `log`, expected `temperature` or `normalised` (in history.plot)"
        ),
        "{e}"
    );
}
