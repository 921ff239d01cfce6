#!/usr/bin/env bash
# The Wang, Oterkus & Oterkus §4.3 study of docs/validation.md: runs the four dual-horizon crack
# plates to 0.5 s and compares each with the uniform (k, m) = (1, 1) run at every output time, leaving out the
# nodes within 2δ of a crack tip (`peritherm compare --exclude-tips`).
# Outputs go to out/dh-crack/<case>/. Usage: scripts/dh-crack-study.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
for k in k1_m1 k1_m0.5 k2_m1 k2_m2; do
    ./target/release/peritherm run "cases/dh_crack_plate_$k.toml" --out "out/dh-crack/$k" --quiet
done
for k in k1_m0.5 k2_m1 k2_m2; do
    # 2δ: δ = 3Δ = 0.3 mm in the crack region, doubled for m = 0.5
    radius=6e-4
    [ "$k" = k1_m0.5 ] && radius=1.2e-3
    echo "## dh_crack_plate_$k against dh_crack_plate_k1_m1 (tips: $radius m left out)"
    ./target/release/peritherm compare "out/dh-crack/$k" out/dh-crack/k1_m1 --exclude-tips "$radius"
done
