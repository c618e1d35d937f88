#!/usr/bin/env bash
# Runs `crackle modal`, `crackle run` and `crackle study` on every data/*.yaml scene (shortened to a
# few excitation periods so that the whole set takes minutes) with one crackle binary into a folder,
# so that two builds can be compared with scripts/compare_outputs.py. Used to show that a refactoring
# leaves every output the same.
# Usage: scripts/same_outputs.sh CRACKLE_BINARY OUTPUT_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
crackle="$1"
out="$2"
rm -rf "$out"
mkdir -p "$out"
short=(--set transient.periods=5 --set spectrum.steady_state.window_periods=2 --set transient.snapshots.count=2)
for scene in data/beam.yaml data/composite-plate.yaml data/gmsh-cracked-box.yaml; do
  name=$(basename "$scene" .yaml)
  "$crackle" modal "$scene" -o "$out/$name-modal" > "$out/$name-modal.log"
  "$crackle" run "$scene" -q "${short[@]}" -o "$out/$name-run" > "$out/$name-run.log"
done
# The depth study, shortened in a copy of its scene (a study takes no --set).
sed -e 's/^\(  *\)periods: 60/\1periods: 4/' -e 's/window_periods: 4/window_periods: 2/' \
  data/depth-study.yaml > "$out/depth-study.yaml"
"$crackle" study "$out/depth-study.yaml" -o "$out/depth-study" --jobs 2 > "$out/depth-study.log" 2>&1
echo "scripts/same_outputs.sh: outputs of $crackle in $out"
