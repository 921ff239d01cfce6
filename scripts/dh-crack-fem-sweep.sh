#!/usr/bin/env bash
# The four Wang, Oterkus & Oterkus §4.3 dual-horizon crack plates, each against its own FEM
# reference, in one `peritherm sweep` (docs/validation.md), written into
# validation/dh_crack_fem.json (table, commit, machine and the checks of
# scripts/check-figures.sh), then the docs' blocks. Outputs go to out/dh-crack-sweep/.
# Usage: bash scripts/dh-crack-fem-sweep.sh   (about 80 s on 2 cores once built)
# PERITHERM=target/release/peritherm skips the build and uses that binary.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
"$bin" sweep cases/dh_crack_plate_k1_m1.toml cases/dh_crack_plate_k1_m0.5.toml \
  cases/dh_crack_plate_k2_m1.toml cases/dh_crack_plate_k2_m2.toml --out out/dh-crack-sweep \
  --json validation/dh_crack_fem.json --command scripts/dh-crack-fem-sweep.sh
bash scripts/update-docs.sh
