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

/// The largest difference between the field files `fields` of the runs in `a` and `b`,
/// relative to the largest magnitude in `a` of the column's quantity (the heat flux's columns
/// qx, qy, qz share theirs; 1 where it is 0); infinite when the files differ in shape or a
/// difference is not a number.
#[allow(dead_code)]
pub fn field_files_differ_by(a: &Path, b: &Path, fields: &[String]) -> f64 {
    let table = |dir: &Path, f: &str| -> (Vec<String>, Vec<Vec<f64>>) {
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        let mut lines = text.lines();
        let head = lines.next().unwrap_or("").split(',').map(str::to_string);
        let rows = lines.map(|l| {
            let cells = l
                .split(',')
                .map(|c| c.trim().parse::<f64>().unwrap_or(f64::NAN));
            cells.collect()
        });
        (head.collect(), rows.collect())
    };
    let mut worst: f64 = 0.0;
    for f in fields {
        let ((head, x), (_, y)) = (table(a, f), table(b, f));
        if x.len() != y.len() || x.iter().zip(&y).any(|(p, q)| p.len() != q.len()) {
            return f64::INFINITY;
        }
        let quantity = |c: usize| {
            if head[c].starts_with('q') {
                "q"
            } else {
                &head[c]
            }
        };
        let largest = |c: usize| x.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
        for col in 0..head.len() {
            let scale = (0..head.len())
                .filter(|&c| quantity(c) == quantity(col))
                .map(largest)
                .fold(0.0, f64::max);
            let scale = if scale > 0.0 { scale } else { 1.0 };
            for (p, q) in x.iter().zip(&y) {
                let d = (p[col] - q[col]).abs() / scale;
                // NaN anywhere makes the comparison fail, never pass
                worst = if d.is_nan() {
                    f64::INFINITY
                } else {
                    worst.max(d)
                };
            }
        }
    }
    worst
}
