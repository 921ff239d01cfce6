#!/usr/bin/env bash
# Every bundled case, shortened to a hundredth of its first output (as scripts/fields-table.sh
# does), run serially on one thread and under `mpiexec -n 2` and `-n 3` with the MPI build;
# fails at the first CSV field file that differs from the serial run's: by a byte, or for the
# fixed-step implicit runs that step by rows (distributed CG against the serial direct
# solve) by more than 1e-12 of a quantity's largest magnitude (scripts/fields-differ.py).
# The VTK data of a distributed run is in one piece per rank, field_<k>.pvtu:
# tests/mpi/read_pvd.py reads it.
# About 20 minutes on 2 cores (the cases with a FEM reference solve it on rank 0).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --features mpi --quiet
bin=./target/release/peritherm
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for f in cases/*.toml; do
  n=$(basename "$f" .toml)
  settings=$(python3 scripts/short-settings.py "$f")
  args=()
  for s in $settings; do args+=(--set "$s"); done
  "$bin" --threads 1 run "$f" "${args[@]}" --out "$out/$n/serial" --quiet > /dev/null
  for ranks in 2 3; do
    mpiexec -n "$ranks" "$bin" --threads 1 run "$f" "${args[@]}" --out "$out/$n/$ranks" --quiet > /dev/null
    size=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["ranks"]["size"])' \
      "$out/$n/$ranks/run.json")
    [ "$size" = "$ranks" ] || { echo "$n: ran on $size ranks, not $ranks" >&2; exit 1; }
    rows_implicit=$(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print(int(r["ranks"]["mode"] == "rows" and "implicit" in r))' \
      "$out/$n/$ranks/run.json")
    if [ "$rows_implicit" = 1 ]; then
      python3 scripts/fields-differ.py "$out/$n/serial" "$out/$n/$ranks" 1e-12 \
        || { echo "$n on $ranks ranks: the fields differ by more than 1e-12" >&2; exit 1; }
    fi
    for csv in "$out/$n/serial"/field_*.csv; do
      [ "$rows_implicit" = 1 ] || cmp -s "$csv" "$out/$n/$ranks/$(basename "$csv")" \
        || { echo "$n on $ranks ranks: $(basename "$csv") differs" >&2; exit 1; }
      pvtu="$out/$n/$ranks/$(basename "$csv" .csv).pvtu"
      [ -f "$pvtu" ] || { echo "$n on $ranks ranks: no $(basename "$pvtu")" >&2; exit 1; }
    done
    how=$(python3 -c 'import json,sys; r=json.load(open(sys.argv[1]))["ranks"]; print(r["mode"] + ", set-up " + r["setup"])' \
      "$out/$n/$ranks/run.json")
    echo "$n: $ranks ranks ($how), the same CSV files$([ "$rows_implicit" = 1 ] && echo ' within 1e-12')"
  done
done
