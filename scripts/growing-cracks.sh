#!/usr/bin/env bash
# The shielding of two growing cracks (Bobaru & Duangpanya 2012 Example 5; docs/validation.md,
# "Growing cracks"): runs cases/growing_cracks.toml and reads, at every output, the
# temperatures of the nodes nearest 2 mm above and below the centre, where the cracks cross.
# Writes validation/growing_cracks.json (its checks: the field files, byte for byte) and the
# docs' table; the run goes to out/growing-cracks/. About a minute on 2 cores.
# Usage: bash scripts/growing-cracks.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
PERITHERM="$bin" python3 - <<'PY'
import sys
sys.path.insert(0, "scripts")
from study import Study

POINTS = [(0.0, 0.002), (0.0, -0.002)]  # m: above and below the crossing
s = Study("growing_cracks", "bash scripts/growing-cracks.sh", "out/growing-cracks")
args = ["run", "cases/growing_cracks.toml", "--quiet"]
for t, rows in s.fields(args):
    nodes = [(float(r["x"]), float(r["y"]), float(r["temperature"])) for r in rows]
    near = [min(nodes, key=lambda n: (n[0] - px) ** 2 + (n[1] - py) ** 2) for px, py in POINTS]
    s.rows.append([f"{t:g}"] + [f"({n[0] * 1e3:.2f}, {n[1] * 1e3:.2f})" for n in near]
                  + [f"{n[2]:.1f}" for n in near])
s.write(["t (s)", "node above (mm)", "node below (mm)", "θ above (°C)", "θ below (°C)"])
PY
bash scripts/update-docs.sh
