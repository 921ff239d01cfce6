#!/usr/bin/env bash
# The δ-convergence of the three pipes of docs/validation.md ("Axial and spherical symmetry:
# cases"): each pipe at Δr = 0.01, 0.005, 0.0025 m (m = 3, Δt = 0.3 s) against its own FEM
# reference on elements of 0.625 mm (Δt = 1 s), at every output time (`peritherm sweep`).
# Writes validation/pipe_delta.json and the docs' table from it; runs go to out/pipe-delta/.
# Usage: bash scripts/pipe-delta-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/pipe_cooling_dirichlet.toml cases/pipe_cooling_flux.toml \
  cases/pipe_cooling_convective.toml --vary 'region.*.spacing=0.01,0.005,0.0025' \
  --vary 'time.dt=0.3' --vary 'reference.fem.h=0.000625' --vary 'reference.fem.dt=1.0' \
  --out out/pipe-delta --json validation/pipe_delta.json --command scripts/pipe-delta-study.sh
bash scripts/update-docs.sh
