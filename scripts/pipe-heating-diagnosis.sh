#!/usr/bin/env bash
# What moves ε of the 2D axisymmetric pipe (docs/validation.md, "2D axisymmetric pipe"):
# cases/pipe_heating_2d.toml to 5 h as bundled, then with one setting changed at a time (the
# time step, the kernel's profile or exponent, the partial volumes, planar instead of
# axisymmetric), each against its own FEM reference. Besides ε and the largest difference, the
# table gives the heat that entered the PD body over the heat that entered the FEM body
# (energies of run.json), so its sign says which is colder. Writes
# validation/pipe_heating_diagnosis.json (with the checks of scripts/check-figures.sh) and the
# docs' table; runs go to out/pipe-heating-diagnosis/. About 3 minutes on 2 cores.
# Usage: bash scripts/pipe-heating-diagnosis.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
PERITHERM="$bin" python3 - <<'PY'
import json
import sys
sys.path.insert(0, "scripts")
from study import FEM_REL_TOL as TOL, Study

CHANGES = [None, "time.dt=2", "kernel.profile=conical", "kernel.p=1",
           "kernel.partial_volume=all_or_nothing", "symmetry=planar"]
s = Study("pipe_heating_diagnosis", "bash scripts/pipe-heating-diagnosis.sh",
          "out/pipe-heating-diagnosis")
for change in CHANGES:
    args = ["sweep", "cases/pipe_heating_2d.toml", "--vary", "time.end=18000.0",
            "--vary", "time.outputs=[18000.0]"] + (["--vary", change] if change else [])
    variant = json.load(open(f"{s.run(args)}/sweep.json"))[0]["variant"]
    heat = {}
    for who, sub in [("pd", variant), ("fem", f"{variant}/fem")]:
        start = s.measure(args, f"{sub}/run.json", "/initial_energy", TOL)
        heat[who] = s.measure(args, f"{sub}/run.json", "/energy/0", TOL) - start
    eps = s.measure(args, "sweep.json", "/0/epsilon", TOL)
    diff = s.measure(args, "sweep.json", "/0/max_abs", TOL)
    s.rows.append([change or "as bundled (Δt = 10 s)", f"{eps * 100:.3f}", f"{diff:.2f}",
                   f"{heat['pd'] / heat['fem'] - 1:+.2%}"])
s.write(["change", "ε at 5 h (%)", "max abs diff (K)", "heat in, PD / FEM − 1"])
PY
bash scripts/update-docs.sh
