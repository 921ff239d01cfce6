//! Figures that a test measures, kept in the committed figure files of `validation/` so that the
//! docs show them without pasting. A test gives its row of a table; with `PERITHERM_RECORD=1`
//! the row is written into `validation/<table>.json` (with the commit and machine), and
//! `bash scripts/update-docs.sh` renders the docs' block from it. Without it the test checks
//! that the committed row still says what it measured, so a table cannot go stale.

use peritherm_post::figures::{Figures, DIR};
use std::path::PathBuf;
use std::sync::Mutex;

/// Serialises the read-modify-write of a figure file between the tests of one binary.
static LOCK: Mutex<()> = Mutex::new(());

/// A table whose rows several tests measure.
pub struct Table {
    /// File stem under `validation/` and name of the docs' block.
    pub name: &'static str,
    /// The command that measures every row (from the repository root).
    pub command: &'static str,
    /// Column headings.
    pub columns: &'static [&'static str],
    /// The first cell of every row, in the order the table shows them.
    pub keys: &'static [&'static str],
    /// Columns of wall times or memory: recorded, never checked (they depend on the machine
    /// and its load, which the figure file names).
    pub timed: &'static [usize],
}

impl Table {
    /// Records (`PERITHERM_RECORD=1`) or checks the row whose first cell is `cells[0]`. Checking:
    /// the text between the numbers must match, and each number must be within `rel_tol` of the
    /// committed one, plus one unit of its last printed digit (a figure that moves across a
    /// rounding boundary by round-off). `rel_tol` is the test's statement of how much the figure
    /// may move on another machine.
    pub fn row(&self, cells: &[impl AsRef<str>], rel_tol: f64) {
        assert_eq!(cells.len(), self.columns.len(), "{}: cells", self.name);
        let cells: Vec<String> = cells.iter().map(|c| c.as_ref().to_string()).collect();
        let key = cells[0].clone();
        assert!(
            self.keys.contains(&key.as_str()),
            "{}: unknown row {key}",
            self.name
        );
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let path = self.path();
        let committed = Figures::read(&path).ok();
        if std::env::var_os("PERITHERM_RECORD").is_some() {
            self.write(committed, cells);
            return;
        }
        let committed = committed.unwrap_or_else(|| {
            panic!(
                "{}: missing; run the test with PERITHERM_RECORD=1",
                path.display()
            )
        });
        let old = committed
            .rows
            .iter()
            .find(|r| r.first() == Some(&key))
            .unwrap_or_else(|| panic!("{}: no row {key}; record it", path.display()));
        let checked = old.iter().zip(&cells).enumerate();
        for (_, (o, n)) in checked.filter(|(c, _)| !self.timed.contains(c)) {
            assert!(
                same_figures(o, n, rel_tol),
                "{}, row {key}: committed `{o}`, measured `{n}`; if the change is meant, \
                 rerun with PERITHERM_RECORD=1 and `bash scripts/update-docs.sh`",
                path.display()
            );
        }
    }

    fn path(&self) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(DIR)
            .join(format!("{}.json", self.name))
    }

    /// Writes the table with `cells` in its place (other rows as committed).
    fn write(&self, committed: Option<Figures>, cells: Vec<String>) {
        let mut rows = committed.map(|f| f.rows).unwrap_or_default();
        rows.retain(|r| r.first() != Some(&cells[0]));
        rows.push(cells);
        let rank = |r: &Vec<String>| {
            self.keys
                .iter()
                .position(|k| Some(*k) == r.first().map(|s| s.as_str()))
        };
        rows.retain(|r| rank(r).is_some());
        rows.sort_by_key(rank);
        let figures = Figures {
            name: self.name.into(),
            command: self.command.into(),
            provenance: peritherm::figures::provenance(rayon::current_num_threads()),
            columns: self.columns.iter().map(|c| c.to_string()).collect(),
            rows,
            checks: Vec::new(),
        };
        std::fs::write(self.path(), figures.to_json()).unwrap();
    }
}

/// A cell split into its text and its numbers.
fn split(cell: &str) -> (String, Vec<(f64, f64)>) {
    let b = cell.as_bytes();
    let (mut text, mut nums) = (String::new(), Vec::new());
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() || (b[i] == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
        if !starts {
            let c = cell[i..].chars().next().unwrap();
            text.push(c);
            i += c.len_utf8();
            continue;
        }
        let s = i;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        let mantissa_end = i;
        if i + 1 < b.len() && b[i] == b'e' {
            let j = i + 1 + usize::from(b[i + 1] == b'-' || b[i + 1] == b'+');
            if b.get(j).is_some_and(u8::is_ascii_digit) {
                i = j;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
        }
        let Ok(v) = cell[s..i].parse::<f64>() else {
            text.push_str(&cell[s..i]);
            continue;
        };
        // one unit of the last printed digit of the mantissa, scaled by the exponent
        let decimals = cell[s..mantissa_end]
            .split_once('.')
            .map_or(0, |(_, d)| d.len());
        let exponent: i32 = cell[mantissa_end..i]
            .get(1..)
            .and_then(|e| e.parse().ok())
            .unwrap_or(0);
        nums.push((v, 10f64.powi(exponent - decimals as i32)));
        text.push('#');
    }
    (text, nums)
}

/// Whether the measured cell `new` says what the committed cell `old` says (see [`Table::row`]).
fn same_figures(old: &str, new: &str, rel_tol: f64) -> bool {
    let ((to, no), (tn, nn)) = (split(old), split(new));
    to == tn
        && no.len() == nn.len()
        && no
            .iter()
            .zip(&nn)
            // the unit itself is a decimal that binary floats round: allow it to 1e-9
            .all(|(&(o, unit), &(n, _))| (n - o).abs() <= rel_tol * o.abs() + unit * (1.0 + 1e-9))
}

#[test]
fn figures_match_within_a_printed_unit_and_the_tolerance() {
    assert!(same_figures("0.45 °C at 1e-3", "0.46 °C at 1e-3", 0.0));
    assert!(!same_figures("0.45 °C at 1e-3", "0.47 °C at 1e-3", 0.0));
    assert!(same_figures("0.45 °C", "0.47 °C", 0.05));
    assert!(!same_figures("0.45 °C", "0.45 K", 1.0));
    assert!(same_figures(
        "rates **2.03, 2.01**",
        "rates **2.02, 2.01**",
        0.0
    ));
    assert!(!same_figures("1.2e-3", "1.4e-3", 0.0));
    assert!(same_figures("1.2e-3", "1.3e-3", 0.0));
    assert!(!same_figures("2D: 3", "2D: NaN", 1.0));
}
