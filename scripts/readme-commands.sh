#!/usr/bin/env bash
# The README's two commands, each from a fresh output directory (no cached FEM reference),
# timed three times. Writes validation/readme_commands.json (docs/performance.md shows it)
# and the docs' tables; runs go to out/readme-commands/. About a minute on 2 cores.
# Usage: bash scripts/readme-commands.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
out=out/readme-commands
python3 scripts/timed-commands.py readme_commands --repeat 3 \
  --by "bash scripts/readme-commands.sh" \
  --label "\`peritherm run cases/dh_plate_k0.5_m1.toml --out DIR\`" \
  --label "\`peritherm report cases/dh_crack_plate_k2_m1.toml --out DIR\`" -- \
  "rm -rf $out/run && $bin run cases/dh_plate_k0.5_m1.toml --out $out/run --quiet" \
  "rm -rf $out/report && $bin report cases/dh_crack_plate_k2_m1.toml --out $out/report --quiet"
bash scripts/update-docs.sh
