#!/usr/bin/env bash
# The Bobaru & Duangpanya 2010 δ-convergence of the bar with both ends held (docs/validation.md):
# `peritherm sweep` over four horizons, each against the series solution, written into
# validation/bar_delta.json (table, commit, machine and the checks of scripts/check-figures.sh),
# then the docs' blocks. Outputs (sweep.md with the fitted rates and plots) go to out/bar-delta/.
# Usage: bash scripts/bar-delta-study.sh   (about 10 s on 2 cores once built)
# PERITHERM=target/release/peritherm skips the build and uses that binary.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/bar_dirichlet.toml \
  --vary 'region.*.horizon.radius=0.3,0.15,0.075,0.0375' --out out/bar-delta \
  --json validation/bar_delta.json --command scripts/bar-delta-study.sh
bash scripts/update-docs.sh
