#!/usr/bin/env bash
# Runs every bundled benchmark case in release mode and writes the accuracy table of
# docs/validation.md ("Accuracy against the classical solutions"): the figure file
# validation/accuracy.json (the table, the commit and machine, and the checks a rerun must pass:
# every measure, and the field files of the explicit runs byte for byte), then the docs' blocks
# from it (scripts/update-docs.sh). Outputs go to out/bench/<case>/.
# Usage: scripts/benchmark-table.sh [case-name ...]   (default: every case with a classical
# reference; about 25 minutes on 2 cores)
# PERITHERM=target/release/peritherm skips the build and uses that binary.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(bar_dirichlet bar_flux bar_insulated_left
         dh_plate_k0.5_m0.5 dh_plate_k0.5_m1 dh_plate_k1_m1 dh_plate_k1_m2
         square_dirichlet square_one_hot_edge
         thermal_shock_k0.5_m0.5 thermal_shock_k0.5_m1 thermal_shock_k1_m1 thermal_shock_k1_m2
         annulus_steady block_refined dh_plate_gmsh_k0.5_m1 laser_film thermal_shock_split)
fi
dirs=()
for n in "${names[@]}"; do
  "$bin" run "cases/$n.toml" --out "out/bench/$n" --quiet >&2
  dirs+=("out/bench/$n")
done
"$bin" table "${dirs[@]}" --json validation/accuracy.json \
  --command "scripts/benchmark-table.sh"
python3 scripts/papers-table.py
bash scripts/update-docs.sh
