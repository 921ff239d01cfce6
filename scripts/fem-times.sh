#!/usr/bin/env bash
# Run times of the built-in FEM reference (`peritherm fem`, default Δt) on four bundled cases
# of different sizes. Writes validation/fem_times.json (docs/performance.md shows it) and
# the docs' tables; runs go to out/fem-times/. About 2 minutes on 2 cores.
# Usage: bash scripts/fem-times.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
cmds=()
for c in bar_dirichlet crack_plate square_dirichlet thermal_shock_k0.5_m1; do
  cmds+=("$bin fem cases/$c.toml --out out/fem-times/$c --quiet")
done
python3 scripts/timed-commands.py fem_times --by "bash scripts/fem-times.sh" \
  --label bar_dirichlet --label crack_plate --label square_dirichlet \
  --label thermal_shock_k0.5_m1 -- "${cmds[@]}"
python3 - <<'PY'
import json
for c in ["bar_dirichlet", "crack_plate", "square_dirichlet", "thermal_shock_k0.5_m1"]:
    r = json.load(open(f"out/fem-times/{c}/run.json"))
    print(f"{c}: {r['nodes']} nodes, {r['steps']} steps")
PY
bash scripts/update-docs.sh
