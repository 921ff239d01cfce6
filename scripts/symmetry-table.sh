#!/usr/bin/env bash
# Runs the axisymmetric phase-change paper §3.1–3.4 cases (axisymmetric and spherical) and prints
# the Markdown table of docs/validation.md ("Axial and spherical symmetry: cases"): ε (the axisymmetric
# phase-change paper, doi:10.1007/s42102-022-00092-3, eq. 27) and the largest nodal difference
# against each case's reference at every output time. Outputs go to out/symmetry/<case>/ (each FEM
# reference in <case>/fem/). Usage (from the repository root): bash scripts/symmetry-table.sh
# (about 25 s on 2 cores once built)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
cases=(pipe_cooling_dirichlet pipe_cooling_flux pipe_cooling_convective sphere_cooling pipe_heating_2d)
for c in "${cases[@]}"; do
  ./target/release/peritherm run "cases/$c.toml" --out "out/symmetry/$c" --quiet >&2
done
python3 - "${cases[@]}" <<'PY'
import json, sys
print("| case | t | nodes | reference | max abs diff (K) | ε (eq 27) |")
print("|---|---|---|---|---|---|")
for c in sys.argv[1:]:
    s = json.load(open(f"out/symmetry/{c}/run.json"))
    ref = "series" if c == "sphere_cooling" else "FEM"
    for r in s["reference"]:
        t = r["time"]
        when = f"{t / 3600:g} h" if t >= 3600 else f"{t:g} s"
        print(f"| {c} | {when} | {s['nodes']} | {ref} | {r['max_abs_diff']:.3f} | {r['epsilon']:.2e} |")
PY
