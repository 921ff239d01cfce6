#!/usr/bin/env bash
# The refined-zone study of docs/validation.md: the Bobaru & Duangpanya 2012 Example 3 crack
# plate on the refined gmsh mesh against the same model on the uniform fine mesh, at every
# output time (`peritherm sweep --against-first`: the uniform run, named first, interpolated at
# the refined run's nodes by a local linear least-squares fit that does not look across the
# crack). Writes validation/refined_zone.json and the docs' table from it; runs go to
# out/refined-zone/. About 3 minutes on 2 cores. Usage: bash scripts/refined-zone-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/crack_plate_uniform.toml cases/crack_plate_refined.toml --against-first \
  --out out/refined-zone --json validation/refined_zone.json \
  --command scripts/refined-zone-study.sh
bash scripts/update-docs.sh
