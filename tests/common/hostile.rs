//! Helpers of the hostile-input tests (`tests/cli/hostile.rs`, `tests/cli/fuzz.rs`): a small case,
//! the CLI under a memory limit and a clock, and a seeded mutation generator.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// A 20 × 20 plate held on one side: every hostile example is an edit of it.
pub const PLATE: &str = r#"dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
[[region]]
name = "plate"
cells = [20, 20]
horizon = { factor = 3.0 }
[material.steel]
conductivity = 50.0
density = 7850.0
specific_heat = 420.0
[boundary.x_min]
type = "temperature"
value = 100.0
[time]
end = 2.0
"#;

/// Limits of every refusal (issue 15's "done when"): wall time and resident memory.
pub const MAX_SECONDS: f64 = 5.0;
/// Resident-memory limit of a refusal, KiB (1 GiB), measured by `/usr/bin/time`.
pub const MAX_KIB: u64 = 1 << 20;
/// Address-space limit of the CLI under test, KiB (8 GiB): a safety net that makes a run
/// trying to fill the machine fail; it is above 1 GiB because the dense kernels reserve
/// (without touching) large per-thread workspaces.
pub const ADDRESS_KIB: u64 = 8 << 20;

/// The outcome of one CLI call.
pub struct Outcome {
    /// Exit code (None: killed by a signal).
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
    /// Wall time, s.
    pub seconds: f64,
    /// Peak resident memory, KiB (0 where `/usr/bin/time` is missing).
    pub max_kib: u64,
}

/// Runs the `peritherm` binary with `args` under [`ADDRESS_KIB`] of address space
/// (`ulimit -v`), measuring its peak resident memory with `/usr/bin/time` when present.
pub fn peritherm(args: &[&str]) -> Outcome {
    let started = Instant::now();
    let report = tempfile::NamedTempFile::new().unwrap();
    let timed = Path::new("/usr/bin/time").exists();
    let mut cmd = Command::new("sh");
    cmd.arg("-c");
    if timed {
        cmd.arg(format!(
            "ulimit -v {ADDRESS_KIB}; exec /usr/bin/time -q -o \"{}\" -f %M \"$0\" \"$@\"",
            report.path().display()
        ));
    } else {
        cmd.arg(format!("ulimit -v {ADDRESS_KIB}; exec \"$0\" \"$@\""));
    }
    cmd.env(super::cli::CACHE_VAR, "off");
    let o = cmd.arg(super::cli::EXE).args(args).output().unwrap();
    let max_kib = std::fs::read_to_string(report.path())
        .ok()
        .and_then(|s| s.lines().last().and_then(|l| l.trim().parse().ok()))
        .unwrap_or(0);
    Outcome {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        seconds: started.elapsed().as_secs_f64(),
        max_kib,
    }
}

/// Writes `text` as `dir/name` and returns the path.
pub fn write_case(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Asserts a refusal: exit code 1, one line on stderr naming `file` and `key`, no panic,
/// within [`MAX_SECONDS`].
pub fn assert_refused(what: &str, o: &Outcome, file: &str, key: &str) {
    let err = o.stderr.trim_end();
    assert_eq!(o.code, Some(1), "{what}: {err}");
    assert_eq!(err.lines().count(), 1, "{what}: {err}");
    assert!(err.contains(file), "{what}: names no file `{file}`: {err}");
    assert!(err.contains(key), "{what}: names no key `{key}`: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert!(
        o.seconds < MAX_SECONDS,
        "{what}: took {:.1} s: {err}",
        o.seconds
    );
    assert!(o.max_kib < MAX_KIB, "{what}: used {} KiB: {err}", o.max_kib);
}

/// Names of the entries of `dir`, sorted (hidden ones included).
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// Waits up to `limit` for `f` to hold, polling every 50 ms.
pub fn wait_for(limit: Duration, mut f: impl FnMut() -> bool) -> bool {
    let started = Instant::now();
    while started.elapsed() < limit {
        if f() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    f()
}

/// A seeded xorshift64* generator: reproducible mutations without a dependency.
pub struct Rng(u64);

impl Rng {
    /// A generator from a nonzero seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    /// The next 64 random bits.
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// A uniform index below `n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    /// One of `items`.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// Values that have broken parsers and solvers: zero, signs, subnormals, extremes,
/// non-finite TOML floats, huge counts, and hostile expressions.
pub const HOSTILE_NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e-320",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "4294967296",
    "99999999999",
    "1e-9",
    "0.5",
    "3",
    "1e4",
    "\"x/0\"",
    "\"ln(x - 10)\"",
    "\"((((((((((((((((((((((((((((((((((((((((1))))))))))))))))))))))))))))))))))))))))\"",
    "\"1e308*1e308\"",
    "\"t^-1\"",
    "[]",
    "[1e308, 1e308]",
    "[0.5, 0.5]",
    "\"\"",
    "true",
];

/// Mutates a text file (a case or a gmsh mesh) once: a number replaced by a hostile value, a
/// line dropped, duplicated or swapped, the text cut short, or bytes flipped.
pub fn mutate(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() {
        return String::new();
    }
    let mut out: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    match rng.below(10) {
        8 | 9 => {
            // a benign change: a number scaled by 2, 1/2 or 3/2 (often still a valid case)
            let k = rng.below(out.len());
            let factor = *rng.pick(&[2.0, 0.5, 1.5]);
            let scaled: Vec<String> = out[k]
                .split(' ')
                .map(|w| match w.trim_end_matches(',').parse::<f64>() {
                    Ok(v) if w.ends_with(',') => format!("{},", v * factor),
                    Ok(v) => format!("{}", v * factor),
                    Err(_) => w.to_string(),
                })
                .collect();
            out[k] = scaled.join(" ");
        }
        0..=2 => {
            // a value after `=` (case) or a number on a line (mesh) replaced
            let k = rng.below(out.len());
            let line = out[k].clone();
            let value = rng.pick(HOSTILE_NUMBERS).to_string();
            out[k] = match line.find('=') {
                Some(eq) => format!("{} = {value}", &line[..eq].trim_end()),
                None => {
                    let mut words: Vec<String> =
                        line.split_whitespace().map(str::to_string).collect();
                    if !words.is_empty() {
                        let w = rng.below(words.len());
                        words[w] = value.trim_matches('"').to_string();
                    }
                    words.join(" ")
                }
            };
        }
        3 => {
            out.remove(rng.below(out.len()));
        }
        4 => {
            let k = rng.below(out.len());
            let l = out[k].clone();
            out.insert(k, l);
        }
        5 => {
            let (a, b) = (rng.below(out.len()), rng.below(out.len()));
            out.swap(a, b);
        }
        6 => {
            let joined = out.join("\n");
            let mut cut = rng.below(joined.len().max(1));
            while !joined.is_char_boundary(cut) {
                cut -= 1;
            }
            return joined[..cut].to_string();
        }
        _ => {
            // 7: bytes flipped
            let mut bytes = out.join("\n").into_bytes();
            for _ in 0..1 + rng.below(4) {
                let k = rng.below(bytes.len().max(1));
                if let Some(b) = bytes.get_mut(k) {
                    *b = *rng.pick(b"0123456789.-e[]=\"{},x( )");
                }
            }
            return String::from_utf8_lossy(&bytes).into_owned();
        }
    }
    out.join("\n") + "\n"
}
