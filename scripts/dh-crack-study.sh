#!/usr/bin/env bash
# The Wang, Oterkus & Oterkus §4.3 study of docs/validation.md: runs the four dual-horizon crack
# plates to 0.5 s and compares each with the uniform (k, m) = (1, 1) run, named first, at every
# output time (`peritherm sweep --against-first`), leaving out the nodes within 1.2 mm of a
# crack tip (2δ of the (1, 0.5) plate, whose crack region has the doubled horizon; 4δ of the
# others). Writes validation/dh_crack_vs_k1_m1.json and the docs' table from it; runs go to
# out/dh-crack/. About 5 minutes on 2 cores. Usage: bash scripts/dh-crack-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/dh_crack_plate_k1_m1.toml cases/dh_crack_plate_k1_m0.5.toml \
  cases/dh_crack_plate_k2_m1.toml cases/dh_crack_plate_k2_m2.toml --against-first \
  --exclude-tips 1.2e-3 --out out/dh-crack --json validation/dh_crack_vs_k1_m1.json \
  --command scripts/dh-crack-study.sh
bash scripts/update-docs.sh
