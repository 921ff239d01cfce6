#!/usr/bin/env bash
# One process against two MPI ranks on this machine (docs/distributed.md): the 10⁶-node plate
# (cases/large/plate_1e7.toml at 1000 × 1000 cells, 23 explicit steps, one output) with the
# default build on 2 threads against the MPI build on 2 ranks of 1 thread (median of three
# runs each), and the fixed-step Crank–Nicolson crack plate (one run each). Fails unless the
# explicit fields are the same bytes and the implicit ones agree within 1e-12 of their largest
# magnitude (scripts/fields-differ.py). Also times planning 4096 ranks of the 10⁷-node plate
# (`peritherm partition`). Writes validation/mpi_explicit.json, validation/mpi_implicit.json
# and validation/partition_plan.json and the docs' tables; runs go to out/mpi-runs/. Needs MPI (see
# docs/distributed.md); about 3 minutes on 2 cores plus the two builds.
# Usage: bash scripts/mpi-runs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cargo build --release --features mpi --quiet
cp target/release/peritherm "$tmp/peritherm-mpi"
cargo build --release --quiet
serial=./target/release/peritherm
mpi="mpiexec -n 2 $tmp/peritherm-mpi --threads 1"
out=out/mpi-runs
rm -rf "$out"
plate="cases/large/plate_1e7.toml --set 'region.*.cells=[1000,1000]' --set time.end=2e-5"
plate+=" --set 'time.outputs=[2e-5]' --set time.dt=9e-7 --quiet"
python3 scripts/timed-commands.py mpi_explicit --repeat 3 --by "bash scripts/mpi-runs.sh" \
  --label "10⁶-node plate, 1 process, 2 threads" --label "10⁶-node plate, 2 ranks, 1 thread each" -- \
  "$serial --threads 2 run $plate --out $out/plate/serial" \
  "$mpi run $plate --out $out/plate/ranks2"
for f in "$out"/plate/serial/field_*.csv; do
  cmp "$f" "$out/plate/ranks2/$(basename "$f")"
done
crack="cases/dh_crack_plate_k1_m1_implicit.toml --quiet"
python3 scripts/timed-commands.py mpi_implicit --by "bash scripts/mpi-runs.sh" \
  --label "Crank–Nicolson crack plate, 1 process, 2 threads (direct solves)" \
  --label "Crank–Nicolson crack plate, 2 ranks, 1 thread each (block-Jacobi CG)" -- \
  "$serial --threads 2 run $crack --out $out/crack/serial" \
  "$mpi run $crack --out $out/crack/ranks2"
python3 scripts/fields-differ.py "$out/crack/serial" "$out/crack/ranks2" 1e-12
python3 scripts/timed-commands.py partition_plan --by "bash scripts/mpi-runs.sh" \
  --label "\`peritherm partition cases/large/plate_1e7.toml --ranks 4096\`" -- \
  "$serial partition cases/large/plate_1e7.toml --ranks 4096 > /dev/null"
bash scripts/update-docs.sh
