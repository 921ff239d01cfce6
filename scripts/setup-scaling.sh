#!/usr/bin/env bash
# The consistent weights' set-up against the cloud's size: cases/large/scale_square.toml (unit
# square of gmsh default triangles, δ = 3Δ, defaults otherwise) on the levels given (default
# L1 L2 of meshes/scale_square_L1..L4.msh, 1.6·10⁴ to 1.0·10⁶ nodes), each run with the weights
# cache off on 2 threads, beside the same model with `kernel.consistency = "none"`: set-up time,
# Newton and CG iterations, peak resident set of both (GNU time). Writes
# validation/setup_scaling.json and the table of docs/performance.md; runs go to
# out/setup-scaling/. About 2 minutes on 2 cores for L1 and L2 (L3 needs about 20 GB).
# Usage: bash scripts/setup-scaling.sh [L1 L2 L3 L4]
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
levels=("$@")
[ $# -gt 0 ] || levels=(L1 L2)
PERITHERM="$bin" python3 - "${levels[@]}" <<'PY'
import json
import os
import subprocess
import sys
sys.path.insert(0, "scripts")
import figure_file

THREADS = 2
rows = []
for level in sys.argv[1:]:
    measured = {}
    for consistency in ["quadratic", "none"]:
        out = f"out/setup-scaling/{level}_{consistency}"
        report = f"{out}.time"
        os.makedirs("out/setup-scaling", exist_ok=True)
        cmd = ["/usr/bin/time", "-o", report, "-f", "%M",
               os.environ["PERITHERM"], "--cache", "off", "--threads", str(THREADS), "run", "-q",
               "cases/large/scale_square.toml", "--out", out,
               "--set", f'mesh.file="../../meshes/scale_square_{level}.msh"',
               "--set", f'kernel.consistency="{consistency}"']
        subprocess.run(cmd, check=True)
        kib = int(open(report).read().split()[-1])
        measured[consistency] = (json.load(open(f"{out}/run.json")), kib * 1024 / 1e9)
    (run, rss), (_, rss_none) = measured["quadratic"], measured["none"]
    c = run["consistency"]
    rows.append([level, str(run["nodes"]), str(run["bonds"]), f"{c['newton']} / {c['iterations']}",
                 f"{run['setup_seconds']:.1f}", f"{1e6 * run['setup_seconds'] / run['nodes']:.0f}",
                 f"{rss:.2f}", f"{rss_none:.2f}", f"{rss / rss_none:.1f}"])
    print(" | ".join(rows[-1]), flush=True)
figure_file.write("setup_scaling", "bash scripts/setup-scaling.sh " + " ".join(sys.argv[1:]),
                  ["level", "nodes", "bonds", "Newton / CG iterations", "set-up (s)",
                   "set-up per node (µs)", "peak resident (GB)", "`none`: peak resident (GB)",
                   "ratio"], rows, threads=THREADS)
PY
bash scripts/update-docs.sh
