#!/usr/bin/env bash
# A 10⁷-node 2D case end to end (issue 7: "a 10⁷-node 2D case runs within the machine's
# 24 GB"): a 3163 × 3163 square, δ = 3Δ, all edges held at 0 °C by mirrored layers, 20
# explicit Euler steps, one output (CSV + VTU of 10⁷ rows, ~2 GB on disk). Prints the run's
# summary and the peak resident set of the process (GNU time's "Maximum resident set size").
# Usage: bash scripts/ten-million.sh [OUT_DIR]   (default out/ten_million; ~3 min on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/ten_million}"
mkdir -p "$out"
cargo build --release --quiet
cat > "$out/case.toml" <<'TOML'
title = "10⁷-node square, δ = 3Δ, 20 explicit steps"
dimension = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
placement = "cell"
[[region]]
name = "square"
cells = [3163, 3163]
horizon = { factor = 3 }
[material.unit]
conductivity = 1.0
density = 1.0
specific_heat = 1.0
[kernel]
p = 1
profile = "constant"
calibration = "lattice"
[boundary.x_min]
type = "temperature"
method = "mirror"
value = 0.0
[boundary.x_max]
type = "temperature"
method = "mirror"
value = 0.0
[boundary.y_min]
type = "temperature"
method = "mirror"
value = 0.0
[boundary.y_max]
type = "temperature"
method = "mirror"
value = 0.0
[initial]
value = "sin(pi*x)*sin(pi*y)"
[time]
end = 1.8e-6
dt = 9.0e-8                      # the stable bound is 9.7e-8 s
integrator = "euler"
TOML
/usr/bin/time -v ./target/release/peritherm run "$out/case.toml" --out "$out/run" 2> "$out/time.txt"
grep -E 'Maximum resident set size|Elapsed' "$out/time.txt"
