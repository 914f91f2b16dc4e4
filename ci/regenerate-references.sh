#!/usr/bin/env bash
# Regenerate the reference CSVs in references/ from the shipped scenes:
#   <scene>.csv       regularized reference (the scene as written, Gaussian walls)
#   <scene>.hard.csv  hard-wall reference (ideal elastic walls), for scenes with fixed
#                     walls (the hard-wall reference refuses moving walls)
# each sampled on the scene's own grid, DOP853 at rtol = atol = 1e-12, with a
# provenance header. references.rs regenerates one of them and checks that it
# matches the checked-in file. Run from anywhere: bash ci/regenerate-references.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --quiet -p skg-cli
bin=./target/debug/skg-solve
out=references
mkdir -p "$out"
for scene in free_fall rolling_disk tumbler incline_friction incline_frictionless knife_edge driven_oscillator pendulum vibrating_plate; do
    "$bin" reference "scenarios/$scene.toml" -o "$out/$scene.csv" --rtol 1e-12 --quiet
    if grep -q '^\[\[walls\]\]' "scenarios/$scene.toml" && [[ $scene != vibrating_plate ]]; then
        "$bin" reference "scenarios/$scene.toml" -o "$out/$scene.hard.csv" --rtol 1e-12 --hard-walls --quiet
    fi
done
ls -l "$out"
