#!/usr/bin/env bash
# Reruns every check of the committed figure files in validation/ (the bundled cases at full
# length, the studies), or of the files named (without .json), and fails when a figure moved
# beyond its stated tolerance or a field file of an explicit run changed by a byte. All of them
# take more than an hour on 2 cores (the accuracy table alone about an hour).
# Usage: bash scripts/check-figures.sh [NAME...]   e.g. bash scripts/check-figures.sh symmetry fields
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -gt 0 ]; then
  PERITHERM_FIGURES="$(IFS=,; echo "$*")"
  export PERITHERM_FIGURES
fi
cargo test --release --test cases figures::committed_figures_hold -- --ignored --nocapture
