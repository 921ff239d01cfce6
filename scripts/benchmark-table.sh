#!/usr/bin/env bash
# Runs every bundled benchmark case in release mode and prints the Markdown table of the
# docs/validation.md ("Accuracy against the classical solutions"). Outputs go to out/bench/<case>/.
# Usage: scripts/benchmark-table.sh [case-name ...]   (default: all of cases/*.toml)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  for f in cases/*.toml; do names+=("$(basename "$f" .toml)"); done
fi
dirs=()
for n in "${names[@]}"; do
  ./target/release/peritherm run "cases/$n.toml" --out "out/bench/$n" --quiet >&2
  dirs+=("out/bench/$n")
done
./target/release/peritherm table "${dirs[@]}"
