#!/usr/bin/env bash
# 10⁷ nodes on one machine (docs/performance.md): `peritherm bench --nodes 1e7` (the 2D m = 3
# plate's model build and explicit step, and the process's peak resident set) and the
# 10⁷-node case cases/large/plate_1e7.toml end to end through `peritherm run` (20 explicit
# steps, one output of CSV + VTU, ~2 GB on disk). Writes validation/bench_*_1e7.json and
# validation/ten_million.json and the docs' tables; the run goes to out/ten-million/.
# Needs about 8 GB of memory; about 5 minutes on 2 cores. The run passes --max-memory 48G so
# that a machine with less free memory than the set-up's estimate (9.3 GiB for this case,
# 1.4 times what it holds) still runs it.
# Usage: bash scripts/ten-million.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" bench --nodes 1e7 --json validation --command "bash scripts/ten-million.sh"
python3 scripts/timed-commands.py ten_million --by "bash scripts/ten-million.sh" \
  --label "\`peritherm --max-memory 48G run cases/large/plate_1e7.toml\`" -- \
  "rm -rf out/ten-million && $bin --max-memory 48G run cases/large/plate_1e7.toml --out out/ten-million --quiet"
bash scripts/update-docs.sh
