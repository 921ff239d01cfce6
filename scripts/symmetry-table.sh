#!/usr/bin/env bash
# The table "Axial and spherical symmetry: cases" of docs/validation.md: the three pipes, the
# sphere and the 2D pipe of the axisymmetric phase-change paper, each against its own reference
# (FEM or series) at every output time (`peritherm sweep`), with ε of that paper's eq. 27.
# Writes validation/symmetry.json and the docs' table from it; runs go to out/symmetry/.
# Usage: bash scripts/symmetry-table.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/pipe_cooling_dirichlet.toml cases/pipe_cooling_flux.toml \
  cases/pipe_cooling_convective.toml cases/sphere_cooling.toml cases/pipe_heating_2d.toml \
  --out out/symmetry --json validation/symmetry.json --command scripts/symmetry-table.sh
bash scripts/update-docs.sh
