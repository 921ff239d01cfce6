#!/usr/bin/env bash
# Reruns every check of every committed figure file in validation/ (the bundled cases at full
# length, the studies) and fails when a figure moved beyond its stated tolerance or a field file
# of an explicit run changed by a byte. About half an hour on 2 cores.
# Usage: bash scripts/check-figures.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release --test cases figures::committed_figures_hold -- --ignored --nocapture
