#!/usr/bin/env bash
# Ice in boiling water (the axisymmetric phase-change paper §3.5; docs/validation.md, "Phase
# change"): runs cases/ice_in_water.toml and reads, at every output, the coldest node and the
# volume-mean temperature (ring volumes), beside the all-liquid mixing temperature of the
# energy balance worked out here from the case's material and initial fields. Writes
# validation/ice_in_water.json (its checks: the field files, byte for byte) and the docs'
# table; the run goes to out/ice-in-water/. A few seconds.
# Usage: bash scripts/ice-in-water.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
PERITHERM="$bin" python3 - <<'PY'
import sys
sys.path.insert(0, "scripts")
from study import Study

# cases/ice_in_water.toml: one density for both phases, so volumes weigh like masses.
T_ICE, T_WATER, T_F = 268.15, 373.15, 273.15  # K
C_L, C_S, L = 4182.0, 2060.0, 333e3  # J/(kg K), J/(kg K), J/kg
s = Study("ice_in_water", "bash scripts/ice-in-water.sh", "out/ice-in-water")
args = ["run", "cases/ice_in_water.toml", "--quiet"]
for t, table in s.fields(args):
    rows = [(float(r["volume"]), float(r["temperature"]), r["region"]) for r in table]
    v_ice = sum(v for v, _, region in rows if region == "0")
    v_all = sum(v for v, _, _ in rows)
    mean = sum(v * theta for v, theta, _ in rows) / v_all
    coldest = min(theta for _, theta, _ in rows)
    # Σ V (heat to warm the ice, melt it and bring it to T) = Σ V (heat the water gives down to T)
    mixing = (C_L * (v_all - v_ice) * T_WATER + v_ice * (C_L * T_F - C_S * (T_F - T_ICE) - L)) / (C_L * v_all)
    s.rows.append([f"{t / 60:g}", f"{coldest:.1f}", f"{mean:.1f}", f"{mixing:.1f}"])
s.write(["t (min)", "coldest node (K)", "volume-mean temperature (K)",
         "all-liquid mixing temperature of the energy balance (K)"])
PY
bash scripts/update-docs.sh
