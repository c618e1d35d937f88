#!/usr/bin/env bash
# Runs the benchmarks and prints Markdown tables for docs/benchmarks.md.
# Usage: scripts/bench.sh [assembly|modal|all]   (default all). Builds first.
set -euo pipefail
cd "$(dirname "$0")/.."
what="${1:-all}"
scripts/build.sh >/dev/null
echo "machine: $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB, $(lscpu | sed -n 's/Model name: *//p'); date: $(date -u +%F)"
if [[ "$what" == assembly || "$what" == all ]]; then
  echo
  echo "| p | cells | DOFs | threads | K nonzeros | K MiB | K s | lumped M s | peak RSS MiB |"
  echo "|---|---|---|---|---|---|---|---|---|"
  for config in "32 1" "69 1" "16 2" "35 2"; do
    for threads in 1 2; do
      OMP_NUM_THREADS=$threads build/bench/bench_assembly $config 2
    done
  done
fi
