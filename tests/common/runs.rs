//! Comparing the files of two runs.

use std::path::Path;

/// The field files of `fields` (`field_<k>.csv`, as run.json lists them) in the serial run
/// `a` and the run `b` are equal byte for byte, and so are their `.vtu` files; where `b` is
/// distributed (`field_<k>.pvtu` over one piece per rank), its pieces hold as many nodes as
/// `a`'s `.vtu` (the VTK reader's check is tests/mpi/read_pvd.py). `what` names the runs in
/// the failure.
pub fn same_field_files(a: &Path, b: &Path, fields: &[String], what: &str) {
    for f in fields {
        let x = std::fs::read(a.join(f)).unwrap();
        let y = std::fs::read(b.join(f)).unwrap();
        assert!(x == y, "{what}: {f} differs");
        let vtu = f.replace(".csv", ".vtu");
        let x = std::fs::read(a.join(&vtu)).unwrap();
        let pvtu = b.join(f.replace(".csv", ".pvtu"));
        if !pvtu.exists() {
            let y = std::fs::read(b.join(&vtu)).unwrap();
            assert!(x == y, "{what}: {vtu} differs");
            continue;
        }
        let text = std::fs::read_to_string(&pvtu).unwrap();
        let pieces: usize = text
            .split("<Piece Source=\"")
            .skip(1)
            .map(|s| {
                let name = &s[..s.find('"').unwrap()];
                points(&std::fs::read_to_string(b.join(name)).unwrap())
            })
            .sum();
        let whole = points(&String::from_utf8_lossy(&x));
        assert_eq!(
            pieces,
            whole,
            "{what}: the pieces of {} hold every node once",
            pvtu.display()
        );
    }
}

/// The `NumberOfPoints` of a `.vtu` file's piece.
fn points(vtu: &str) -> usize {
    let at = vtu.find("NumberOfPoints=\"").expect("a piece") + "NumberOfPoints=\"".len();
    vtu[at..at + vtu[at..].find('"').unwrap()].parse().unwrap()
}
