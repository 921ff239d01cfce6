#!/usr/bin/env bash
# Regenerates every bundled mesh: for each meshes/<name>.geo writes meshes/<name>.msh
# (MSH 4.1 ASCII, first-order, physical groups only) with the gmsh Python API, via
# meshes/mesh.py, and prints the element count of each mesh. Deterministic (one thread,
# fixed algorithms) and idempotent: rerunning rewrites the same files.
# Usage (from the repository root): bash scripts/regenerate-meshes.sh
set -euo pipefail
cd "$(dirname "$0")/.."
PIP_ROOT_USER_ACTION=ignore python3 -m pip install --quiet 'gmsh>=4.11'
shopt -s nullglob
geos=(meshes/*.geo)
if [ ${#geos[@]} -eq 0 ]; then
  echo "no meshes/*.geo found" >&2
  exit 1
fi
for geo in "${geos[@]}"; do
  python3 meshes/mesh.py "$geo" "${geo%.geo}.msh"
done
