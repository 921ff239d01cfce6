#!/usr/bin/env bash
# The refined-zone study of docs/validation.md: runs the Bobaru & Duangpanya 2012 Example 3 crack plate on
# the refined gmsh mesh and on the uniform fine one, then compares the two fields at every output
# time (`peritherm compare`: the uniform run interpolated at the refined run's nodes by a
# local linear least-squares fit that does not look across the crack).
# Outputs go to out/study/{refined,uniform}/. Usage: scripts/refined-zone-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
./target/release/peritherm run cases/crack_plate_refined.toml --out out/study/refined --quiet >&2
./target/release/peritherm run cases/crack_plate_uniform.toml --out out/study/uniform --quiet >&2
./target/release/peritherm compare out/study/refined out/study/uniform
