#!/usr/bin/env bash
# What the linear-consistency correction buys on the dual-horizon plates (docs/validation.md,
# "Choices that beat the papers"): the Wang, Oterkus & Oterkus plates (k, m) = (1, 2) and
# (0.5, 0.5), each with and without `kernel.linear_consistency`, against the series.
# `peritherm sweep` writes validation/linear_consistency.json (with the checks of
# scripts/check-figures.sh), then the docs' table; runs go to out/linear-consistency/.
# Usage: bash scripts/linear-consistency-study.sh   (about 3 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/dh_plate_k1_m2.toml cases/dh_plate_k0.5_m0.5.toml \
  --vary 'kernel.linear_consistency=true,false' --out out/linear-consistency \
  --json validation/linear_consistency.json --command scripts/linear-consistency-study.sh
bash scripts/update-docs.sh
