#!/usr/bin/env bash
# The README's picture: runs the README's report command (the dual-horizon crack plate with
# k = 2, m = 1 against its FEM reference) and copies its temperature map at t = 0.1 s (the second
# output) to docs/images/crack_plate_map.png. Usage: bash scripts/readme-picture.sh [OUT]
# (default out/report; about 15 s on 2 cores once built)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/report}"
cargo build --release --quiet
./target/release/peritherm report cases/dh_crack_plate_k2_m1.toml --out "$out"
cp "$out/dh_crack_plate_k2_m1/map_2.png" docs/images/crack_plate_map.png
