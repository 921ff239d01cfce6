//! The `peritherm` binary that cargo built for this test target, run the one way every test
//! runs it (the hostile-input runner of `hostile.rs` adds its limits around [`EXE`]).

use std::path::Path;
use std::process::{Command, Output};

/// Path of the `peritherm` binary.
pub const EXE: &str = env!("CARGO_BIN_EXE_peritherm");

/// A command for the binary, for a test that adds arguments one by one or spawns it; the
/// weights cache is off (`--cache` overrides it), so that every test computes what it checks
/// and none writes outside its directories.
pub fn command() -> Command {
    let mut cmd = Command::new(EXE);
    cmd.env(CACHE_VAR, "off");
    cmd
}

/// The environment variable of the weights cache's directory.
pub const CACHE_VAR: &str = "PERITHERM_CACHE";

/// Runs `peritherm` with `args` to its end and returns its exit status and output.
pub fn peritherm(args: &[&str]) -> Output {
    command().args(args).output().unwrap()
}

/// Writes `text` as `dir/name` and returns the path, as an argument of [`peritherm`].
pub fn write_case(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}
