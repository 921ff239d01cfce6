//! Comparing the files of two runs.

use std::path::Path;

/// The field files of `fields` (`field_<k>.csv`, as run.json lists them, and their `.vtu`)
/// in `a` and `b` are equal byte for byte; `what` names the runs in the failure.
pub fn same_field_files(a: &Path, b: &Path, fields: &[String], what: &str) {
    for f in fields {
        for name in [f.clone(), f.replace(".csv", ".vtu")] {
            let x = std::fs::read(a.join(&name)).unwrap();
            let y = std::fs::read(b.join(&name)).unwrap();
            assert!(x == y, "{what}: {name} differs");
        }
    }
}
