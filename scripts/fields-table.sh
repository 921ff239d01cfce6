#!/usr/bin/env bash
# Runs every bundled case briefly (to a hundredth of its first output time, with a time step of
# at most a third of that) and writes validation/fields.json: per case its thermal energy and,
# for the explicit integrators, the hash of its field file, with the checks a rerun must pass
# (scripts/check-figures.sh), then the docs' blocks (scripts/update-docs.sh). A change that
# should not touch the numerics must leave every figure of this file as it is.
# Outputs go to out/fields/<case>/. Usage: bash scripts/fields-table.sh   (a few minutes on 2 cores)
#   PERITHERM=target/release/peritherm   (skip the build, use this binary)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/peritherm-bin.sh
dirs=()
for f in cases/*.toml; do
  n=$(basename "$f" .toml)
  settings=$(python3 scripts/short-settings.py "$f")
  args=()
  for s in $settings; do args+=(--set "$s"); done
  "$bin" run "$f" "${args[@]}" --out "out/fields/$n" --quiet >&2
  dirs+=("out/fields/$n")
done
"$bin" table "${dirs[@]}" --fields --json validation/fields.json \
  --command "scripts/fields-table.sh"
bash scripts/update-docs.sh
