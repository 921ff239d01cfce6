#!/usr/bin/env bash
# The built-in FEM reference against the series solutions (docs/validation.md, "FEM reference:
# the bars"): `peritherm fem` on the three Bobaru & Duangpanya 2010 bars with its defaults
# (Crank–Nicolson), and on square_dirichlet with Crank–Nicolson and backward Euler at
# Δt = 1e-4 s. Writes validation/fem_bars.json (with the checks of scripts/check-figures.sh)
# and the docs' table; runs go to out/fem-bars/. About a minute on 2 cores.
# Usage: bash scripts/fem-bars.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
PERITHERM="$bin" python3 - <<'PY'
import json
import sys
sys.path.insert(0, "scripts")
from study import FEM_REL_TOL as TOL, Study

s = Study("fem_bars", "bash scripts/fem-bars.sh", "out/fem-bars")
runs = [(c, []) for c in ["bar_dirichlet", "bar_insulated_left", "bar_flux"]]
runs += [("square_dirichlet", ["--scheme", sch, "--dt", "1e-4"]) for sch in ["crank-nicolson", "backward-euler"]]
for case, extra in runs:
    args = ["fem", f"cases/{case}.toml", "--quiet", *extra]
    run = s.run(args)
    summary = json.load(open(f"{run}/run.json"))
    for k, entry in enumerate(summary["reference"]):
        diff = s.measure(args, "run.json", f"/reference/{k}/max_abs_diff", TOL)
        eq45 = s.measure(args, "run.json", f"/reference/{k}/mean_sq_rel_diff", TOL)
        s.rows.append([case, summary["integrator"], f"{summary['dt']:g}", str(summary["nodes"]),
                       f"{entry['time']:g}", f"{diff:.2e}", f"{eq45:.2e}"])
s.write(["case", "scheme", "Δt (s)", "nodes", "t (s)", "max abs diff from the series (°C)", "eq 45"])
PY
bash scripts/update-docs.sh
