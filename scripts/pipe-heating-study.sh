#!/usr/bin/env bash
# The axisymmetric phase-change paper (doi:10.1007/s42102-022-00092-3) §3.4, Fig. 11: the global
# error ε (the paper's eq. 27) of the 2D axisymmetric pipe heating at t = 5 h for particle
# sizes Δ = 0.04, 0.02, 0.01 m and horizon ratios m = δ/Δ = 2 … 8, against the FEM solution on
# the graded triangles of meshes/pipe_heating_fem.msh (cases/pipe_heating_2d.toml's own
# reference, solved again for each variant). The 21 variants (mesh pipe_heating_d<Δ>.msh ×
# horizon factor m) run to 5 h with Δt = 2.5 s (stable for all of them: the bound is 2.88 s at
# Δ = 0.01, m = 2). Writes validation/pipe_heating_eps.json and the docs' table from it; runs go
# to OUT/<variant>/ (default out/pipe-heating-study). About 10 minutes on 2 cores.
# Usage: bash scripts/pipe-heating-study.sh [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/pipe-heating-study}"
. scripts/peritherm-bin.sh
"$bin" sweep cases/pipe_heating_2d.toml \
  --vary 'mesh.file=../meshes/pipe_heating_d0.04.msh,../meshes/pipe_heating_d0.02.msh,../meshes/pipe_heating_d0.01.msh' \
  --vary 'region.*.horizon.factor=2,3,4,5,6,7,8' \
  --vary 'time.dt=2.5' --vary 'time.end=18000.0' --vary 'time.outputs=[18000.0]' \
  --out "$out" --json validation/pipe_heating_eps.json --command scripts/pipe-heating-study.sh
bash scripts/update-docs.sh
