#!/usr/bin/env bash
# How much the coarseness of the dual-horizon crack plates' FEM reference moves their figures
# (docs/validation.md): the four Wang, Oterkus & Oterkus §4.3 plates of
# scripts/dh-crack-fem-sweep.sh again, each against an FEM reference of half the element size
# (5e-5 m) and a fifth of the time step (0.5 ms). `peritherm sweep` writes
# validation/dh_crack_fem_fine.json (with the checks of scripts/check-figures.sh), then the
# docs' table; runs go to out/dh-crack-fem-fine/. About 10 minutes on 2 cores.
# Usage: bash scripts/dh-crack-fem-fine.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/dh_crack_plate_k1_m1.toml cases/dh_crack_plate_k1_m0.5.toml \
  cases/dh_crack_plate_k2_m1.toml cases/dh_crack_plate_k2_m2.toml \
  --vary reference.fem.h=5e-5 --vary reference.fem.dt=5e-4 --out out/dh-crack-fem-fine \
  --json validation/dh_crack_fem_fine.json --command scripts/dh-crack-fem-fine.sh
bash scripts/update-docs.sh
