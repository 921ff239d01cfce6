//! The gmsh MSH 4.1 reader on real gmsh output (fixtures from `tests/data/make_fixtures.py`).

use std::path::{Path, PathBuf};

use peritherm::gmsh;
use peritherm::mesh::{measure_and_centroid, ElementKind, Mesh};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn load(name: &str) -> Mesh {
    gmsh::read(&data(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// The error message of reading a fixture that must be refused.
fn refusal(name: &str) -> String {
    match gmsh::read(&data(name)) {
        Ok(_) => panic!("{name} was accepted"),
        Err(e) => e.to_string(),
    }
}

/// Names of the groups of dimension `dim`, in the mesh's order.
fn names(mesh: &Mesh, dim: usize) -> Vec<&str> {
    let groups = mesh.groups.iter().filter(|g| g.dim == dim);
    groups.map(|g| g.name.as_str()).collect()
}

/// Number of elements of `kind` in group `name` (of the kind's dimension).
fn count(mesh: &Mesh, kind: ElementKind, name: &str) -> usize {
    let Some(g) = mesh.group(kind.dim(), name) else {
        return 0;
    };
    let of_group = |e: &&peritherm::mesh::Element| e.groups.contains(&(g as u16));
    mesh.elements
        .iter()
        .filter(|e| e.kind == kind)
        .filter(of_group)
        .count()
}

/// ASCII and binary files of the same gmsh mesh decode to identical meshes.
#[test]
fn ascii_and_binary_agree() {
    let ascii = load("square_tri_ascii.msh");
    assert!(ascii.elements.len() > 200, "{}", ascii.elements.len());
    assert_eq!(ascii, load("square_tri_binary.msh"));
}

/// The top-dimension elements tile the domain: their measures sum to its length/area/volume.
#[test]
fn measures_sum_to_the_domain() {
    for (file, dim, count, domain) in [
        ("square_tri_ascii.msh", 2, None, 1.0),
        ("square_quad.msh", 2, Some(64), 1.0),
        ("line.msh", 1, Some(10), 1.0),
        ("cube_hex.msh", 3, Some(8), 1.0),
        ("cube_tet.msh", 3, None, 1.0),
    ] {
        let mesh = load(file);
        assert_eq!(mesh.dim(), dim, "{file}");
        let top: Vec<_> = mesh
            .elements
            .iter()
            .filter(|e| e.kind.dim() == dim)
            .collect();
        if let Some(n) = count {
            assert_eq!(top.len(), n, "{file}");
        }
        let total: f64 = top
            .iter()
            .map(|e| measure_and_centroid(e.kind, &mesh.corners(e)).0)
            .sum();
        assert!((total - domain).abs() <= 1e-12 * domain, "{file}: {total}");
    }
}

/// Group names/dimensions are gmsh's, in (dim, tag) order; boundary elements carry their side.
#[test]
fn groups_and_boundary_elements() {
    let square = load("square_tri_ascii.msh");
    assert_eq!(names(&square, 1), ["bottom", "right", "top", "left"]);
    assert_eq!(names(&square, 2), ["plate"]);
    let on_side = |m: &Mesh, name: &str, coord: usize, value: f64| {
        let g = m.group(1, name).expect("side group") as u16;
        let sides: Vec<_> = m.elements.iter().filter(|e| *e.groups == [g]).collect();
        assert!(!sides.is_empty(), "{name}");
        for e in sides {
            assert_eq!(e.kind, ElementKind::Line);
            assert!(m.corners(e).iter().all(|p| p[coord] == value), "{name}");
        }
    };
    for mesh in [&square, &load("square_quad.msh")] {
        on_side(mesh, "bottom", 1, 0.0);
        on_side(mesh, "right", 0, 1.0);
        on_side(mesh, "top", 1, 1.0);
        on_side(mesh, "left", 0, 0.0);
        let plate = mesh.group(2, "plate").expect("plate");
        let body = mesh.elements.iter().filter(|e| e.kind.dim() == 2);
        assert!(body.clone().all(|e| *e.groups == [plate as u16]));
    }
    assert_eq!(count(&load("square_quad.msh"), ElementKind::Line, "top"), 8);

    let line = load("line.msh");
    assert_eq!(
        (names(&line, 0), names(&line, 1)),
        (vec!["left", "right"], vec!["bar"])
    );
    for (name, x) in [("left", 0.0), ("right", 1.0)] {
        let g = line.group(0, name).expect("end group") as u16;
        let ends: Vec<_> = line.elements.iter().filter(|e| *e.groups == [g]).collect();
        assert_eq!(ends.len(), 1, "{name}");
        assert_eq!(ends[0].kind, ElementKind::Point);
        assert_eq!(line.corners(ends[0])[0].x, x, "{name}");
    }

    let cube = load("cube_hex.msh");
    assert_eq!(
        (names(&cube, 2), names(&cube, 3)),
        (vec!["bottom"], vec!["block"])
    );
    assert_eq!(count(&cube, ElementKind::Quad, "bottom"), 4);
    assert_eq!(count(&cube, ElementKind::Hex, "block"), 8);
    let bottom = cube.elements.iter().filter(|e| e.kind == ElementKind::Quad);
    assert!(bottom
        .clone()
        .all(|e| cube.corners(e).iter().all(|p| p.z == 0.0)));
    assert_eq!(names(&load("cube_tet.msh"), 3), ["block"]);
}

/// Each malformed class is refused with a one-line message naming the file and the problem.
#[test]
fn unusable_meshes_are_refused() {
    for (file, phrase) in [
        ("msh22.msh", "MSH 4.1"),
        ("no_groups.msh", "physical groups"),
        ("second_order.msh", "not supported"),
        ("unmeshed.msh", "no nodes"),
    ] {
        let message = refusal(file);
        assert!(message.contains(phrase), "{file}: {message}");
        assert!(message.contains(file), "{file}: {message}");
        assert!(!message.contains('\n'), "{file}: {message}");
    }
    assert!(refusal("msh22.msh").contains("MSH 2.2"));
    assert!(refusal("second_order.msh").contains("(gmsh type 8)"));
}

/// A file cut anywhere before the end of $Elements is an error (never a panic), on one line.
#[test]
fn truncated_files_are_refused() {
    for file in ["square_tri_ascii.msh", "square_tri_binary.msh"] {
        let bytes = std::fs::read(data(file)).expect("fixture");
        let end = bytes
            .windows(12)
            .position(|w| w == b"$EndElements")
            .expect("$EndElements")
            + 12;
        for i in 0..40 {
            let cut = i * end / 40;
            match gmsh::parse(&bytes[..cut], &data(file)) {
                Ok(_) => panic!("{file} cut at {cut} of {end} was accepted"),
                Err(e) => {
                    let message = e.to_string();
                    assert!(!message.contains('\n'), "{file} cut at {cut}: {message}");
                    assert!(message.len() < 400, "{file} cut at {cut}: {message}");
                }
            }
        }
    }
}

/// Bytes that are not a mesh, or a valid header followed by noise, are errors.
#[test]
fn garbage_is_refused() {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let noise: Vec<u8> = (0..4000)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 24) as u8
        })
        .collect();
    let path = Path::new("noise.msh");
    for header in [
        &b""[..],
        b"$MeshFormat\n4.1 0 8\n",
        b"$MeshFormat\n4.1 1 8\n\x01\0\0\0",
    ] {
        let bytes = [header, &noise].concat();
        let message = gmsh::parse(&bytes, path).expect_err("noise").to_string();
        assert!(!message.contains('\n'), "{message}");
    }
    let message = gmsh::parse(b"hello", path).expect_err("text").to_string();
    assert!(message.contains("not a gmsh mesh file"), "{message}");
}

/// A file that does not exist is an error that names it.
#[test]
fn missing_file_is_refused() {
    let path = data("does_not_exist.msh");
    let message = gmsh::read(&path).expect_err("missing").to_string();
    assert!(message.contains("does_not_exist.msh"), "{message}");
}
