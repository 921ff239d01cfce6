#!/usr/bin/env bash
# The consistent weights' set-up against the cloud's size, beside what `peritherm check`
# estimated for it: in 2D cases/large/scale_square.toml (unit square of gmsh default triangles,
# δ = 3Δ, defaults otherwise) on meshes/scale_square_L1..L4.msh (1.6·10⁴ to 1.0·10⁶ nodes), in
# 3D cases/large/scale_cube.toml on meshes/conv_cube_tet_L1..L4.msh (712 to 287 757 nodes). Each
# level is run with the weights cache off on 2 threads, beside the same model with
# `kernel.consistency = "none"`: set-up time, check's estimate, Newton and CG iterations, peak
# resident set of both (GNU time). Writes validation/setup_scaling.json and the table of
# docs/performance.md; runs go to out/setup-scaling/. About 3 minutes on 2 cores for the default
# levels (square L1 L2, cube L2 L3); square L3 needs about 20 GB.
# Usage: bash scripts/setup-scaling.sh [square:L1 square:L2 cube:L3 ...]
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
levels=("$@")
[ $# -gt 0 ] || levels=(square:L1 square:L2 cube:L2 cube:L3)
PERITHERM="$bin" python3 - "${levels[@]}" <<'PY'
import json
import os
import re
import subprocess
import sys
sys.path.insert(0, "scripts")
import figure_file

THREADS = 2
FAMILIES = {
    "square": ("cases/large/scale_square.toml", "../../meshes/scale_square_{}.msh"),
    "cube": ("cases/large/scale_cube.toml", "../../meshes/conv_cube_tet_{}.msh"),
}
UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}


def estimated(case, mesh):
    """Seconds that `peritherm check` estimates for the set-up (a copy of the case beside it
    with the mesh set, since check takes no --set)."""
    text = open(case).read()
    text = re.sub(r'(?m)^file = ".*"$', f'file = "{mesh}"', text, count=1)
    copy = os.path.join(os.path.dirname(case), ".setup-scaling-check.toml")
    open(copy, "w").write(text)
    try:
        out = subprocess.run([os.environ["PERITHERM"], "--cache", "off", "--threads",
                              str(THREADS), "check", copy], capture_output=True, text=True,
                             check=True).stdout
    finally:
        os.remove(copy)
    m = re.search(r"estimated ([0-9.]+) (s|min|h) on", out)
    return float(m.group(1)) * UNITS[m.group(2)]


rows = []
for name in sys.argv[1:]:
    family, level = name.split(":")
    case, mesh = FAMILIES[family]
    mesh = mesh.format(level)
    measured = {}
    for consistency in ["quadratic", "none"]:
        out = f"out/setup-scaling/{family}_{level}_{consistency}"
        report = f"{out}.time"
        os.makedirs("out/setup-scaling", exist_ok=True)
        cmd = ["/usr/bin/time", "-o", report, "-f", "%M",
               os.environ["PERITHERM"], "--cache", "off", "--threads", str(THREADS), "run", "-q",
               case, "--out", out, "--set", f'mesh.file="{mesh}"',
               "--set", f'kernel.consistency="{consistency}"']
        subprocess.run(cmd, check=True)
        kib = int(open(report).read().split()[-1])
        measured[consistency] = (json.load(open(f"{out}/run.json")), kib * 1024 / 1e9)
    (run, rss), (_, rss_none) = measured["quadratic"], measured["none"]
    c = run["consistency"]
    guess = estimated(case, mesh)
    rows.append([f"{family} {level}", str(run["nodes"]), str(run["bonds"]),
                 f"{c['newton']} / {c['iterations']}", f"{run['setup_seconds']:.1f}",
                 f"{guess:.0f}", f"{1e6 * run['setup_seconds'] / run['nodes']:.0f}",
                 f"{rss:.2f}", f"{rss_none:.2f}", f"{rss / rss_none:.1f}"])
    print(" | ".join(rows[-1]), flush=True)
figure_file.write("setup_scaling", "bash scripts/setup-scaling.sh " + " ".join(sys.argv[1:]),
                  ["mesh", "nodes", "bonds", "Newton / CG iterations", "set-up (s)",
                   "`check`'s estimate (s)", "set-up per node (µs)", "peak resident (GB)",
                   "`none`: peak resident (GB)", "ratio"], rows, threads=THREADS)
PY
bash scripts/update-docs.sh
