#!/usr/bin/env bash
# Runs the benchmarks and prints Markdown tables for docs/benchmarks.md.
# Usage: scripts/bench.sh [assembly|modal|modal-scale|modal-calculix|transient|spectrum|study|reduced|reduced-scale|reduced-composite|reduced-snapshots|sweep|all]   (default all)
# (sweep: data/beam.yaml by harmonic balance (cold cache), without stability and by stepped sine; cost and peaks vs H)
# (reduced: data/beam.yaml full vs transient.model=reduced; FULL_DIR=dir reuses a full run's outputs)
# (reduced-scale: bench_reduced, cost per step vs crack pairs (REDUCED_PAIRS, default 100..5000) and modes)
# (reduced-composite: data/composite-plate.yaml full vs reduced, both cut to COMPOSITE_PERIODS periods (default 12))
# (reduced-snapshots: data/beam.yaml reduced, cached reduction, with 0, 10 and 60 snapshots: the field recovery's cost)
# (modal = work-precision + scale; modal-scale = the scale part alone)
# (modal-calculix: bench/calculix_modal.py, crackle against CalculiX 2.20 on the open-crack beam, a = 0.3 h and
#  0.5 h, 10 modes; installs calculix-ccx when ccx is missing; not part of all: ~15 min and ~3 GB, quiet machine)
#
# Environment:
#   BUILD=dir        use an existing build folder (e.g. build-bench) and only rebuild it; without it
#                    scripts/build.sh builds build/ first. BENCH_NO_BUILD=1: do not even rebuild it.
#   BENCH_OUT=dir    where the runs write their outputs (default /tmp/crackle-bench).
#   BENCH_LARGE=1    also run the ~600k-DOF modal case (ARPACK + CHOLMOD, about 6 min and 16 GB).
#   CALCULIX_REUSE=1 modal-calculix keeps the runs already in $BENCH_OUT/calculix-modal.
#   STUDY_DIR=dir    output folder of `crackle study data/depth-study.yaml` for the study section
#                    (default /tmp/depth-study; STUDY_TIME=file with its /usr/bin/time output).
# Every table is preceded by the load average at its start: the figures are best-of-N wall times
# on whatever machine runs this, so compare them only with that load in mind.
# Compute (2 loaded cores, 2026-11-22): assembly ~0.5 min, modal ~5 min (+3 with BENCH_LARGE, quiet),
# transient ~7 min, spectrum ~6 min.
set -euo pipefail
cd "$(dirname "$0")/.."
what="${1:-all}"
case "$what" in assembly|modal|modal-scale|modal-calculix|transient|spectrum|study|reduced|reduced-scale|reduced-composite|reduced-snapshots|sweep|all) ;; *)
  echo "usage: scripts/bench.sh [assembly|modal|modal-scale|modal-calculix|transient|spectrum|study|reduced|reduced-scale|reduced-composite|reduced-snapshots|sweep|all]" >&2; exit 2 ;;
esac
if [[ -n "${BUILD:-}" ]]; then
  [[ "${BENCH_NO_BUILD:-0}" == 1 ]] || cmake --build "$BUILD" -j"$(nproc)" >/dev/null
else
  scripts/build.sh >/dev/null
  BUILD=build
fi
out="${BENCH_OUT:-/tmp/crackle-bench}"
mkdir -p "$out"
crackle="$BUILD/apps/crackle"
load() { echo; echo "_load average at start: $(cut -d' ' -f1-3 /proc/loadavg), $(date -u '+%F %H:%M') UTC_"; echo; }
want() { [[ "$what" == "$1" || "$what" == all ]]; }

echo "machine: $(lscpu | sed -n 's/Model name: *//p'), $(nproc) cores, $(free -g | awk '/Mem/{print $2}') GiB; date: $(date -u +%F)"

if want assembly; then
  echo
  echo "### Assembly of K and lumped M (bench_assembly CELLS ORDER 2: best of 2)"
  load
  echo "| p | cells | DOFs | threads | K nonzeros | K MiB | K s | lumped M s | peak RSS MiB |"
  echo "|---|---|---|---|---|---|---|---|---|"
  for config in "32 1" "69 1" "16 2" "35 2"; do
    for threads in 1 2; do
      OMP_NUM_THREADS=$threads "$BUILD"/bench/bench_assembly $config 2
    done
  done
fi

if want modal; then
  echo
  echo "### Modal work-precision: data/beam.yaml, 6 modes, uncracked and open"
  load
  python3 bench/modal_wp.py "$crackle" "$out/modal-wp"
  mkdir -p docs/img
  sed "s#set output .*#set output 'docs/img/modal-work-precision.png'#" "$out/modal-wp/modal_wp.gp" | gnuplot
  echo
  echo "Plot: docs/img/modal-work-precision.png"
  echo
  echo "### Modal work-precision, open crack on graded meshes (bench/modal_graded.py)"
  load
  python3 bench/modal_graded.py "$crackle" "$out/modal-graded" --uniform "$out/modal-wp/modal_wp.csv"
  gnuplot "$out/modal-graded/modal_graded.gp" && cp "$out/modal-graded/modal_graded.png" docs/img/modal-graded.png
  echo
  echo "Plot: docs/img/modal-graded.png"
fi

if want modal || want modal-scale; then
  echo
  echo "### Modal scale: unit cube clamped on x-, p = 2, 10 modes (bench_modal)"
  load
  echo "| route | p | cells | free DOFs | ranks | BLAS threads | assembly s | factorisation s | iterations s | backend s | post s | total s | RSS rank 0 MiB | f1 Hz | wall s | peak RSS MiB (time -v) |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  modal_case() {  # cells route ranks blas
    local cells=$1 route=$2 ranks=$3 blas=$4 pre=() row
    if ((ranks > 1)); then
      pre=(mpirun --allow-run-as-root --oversubscribe -np "$ranks" -x OMP_NUM_THREADS=1 -x OPENBLAS_NUM_THREADS=1)
    fi
    row=$(OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=$blas /usr/bin/time -v -o "$out/modal-time.txt" \
          "${pre[@]}" "$BUILD"/bench/bench_modal "$cells" 2 "$route" 10 2>/dev/null | grep '^|' || true)
    local wall rss
    wall=$(awk -F': ' '/Elapsed/{n=split($2,a,":"); s=0; for(i=1;i<=n;i++) s=s*60+a[i]; print s}' "$out/modal-time.txt")
    rss=$(awk -F': ' '/Maximum resident/{printf "%.0f", $2/1024}' "$out/modal-time.txt")
    if [[ -z "$row" ]]; then row="| $route | 2 | $cells^3 | failed | $ranks | | | | | | | | | |"; fi
    # insert the BLAS thread count after the ranks column, append wall and peak RSS
    echo "$row" | awk -F'|' -v b="$blas" -v w="$wall" -v r="$rss" 'BEGIN{OFS="|"}{
      line=""; for(i=2;i<NF;i++){ line=line "|" $i; if(i==6) line=line "| " b " " } print line "| " w " | " r " |" }'
  }
  for c in "slepc-cholmod 1 1" "slepc-cholmod 1 2" "arpack 1 1" "arpack 1 2" "slepc-mumps 1 1" "slepc-mumps 2 1"; do
    modal_case 15 $c
  done
  modal_case 20 arpack 1 1
  modal_case 20 arpack 1 2
  if [[ "${BENCH_LARGE:-0}" == 1 ]]; then
    modal_case 29 arpack 1 2
  fi
fi

if [[ "$what" == modal-calculix ]]; then  # not in all
  if ! command -v ccx > /dev/null; then
    # As scripts/build.sh installs its packages; apt's output kept off the tables.
    echo "scripts/bench.sh: installing calculix-ccx" >&2
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
    $sudo apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends calculix-ccx >&2
  fi
  echo
  echo "### Modal work-precision against CalculiX $(dpkg-query -W -f='${Version}' calculix-ccx 2>/dev/null): open-crack beam, 10 modes (bench/calculix_modal.py)"
  # The script prints the load average before each of its tables (one per crack depth).
  reuse=()
  if [[ "${CALCULIX_REUSE:-0}" == 1 ]]; then reuse=(--reuse); fi
  python3 bench/calculix_modal.py "$crackle" "$out/calculix-modal" "${reuse[@]}"
fi

if want transient; then
  echo
  echo "### Transient cost per DOF and step (bench_transient, unit cube with a crack in contact)"
  load
  echo "| p | elements | DOFs | threads | kernel | steps | ns/DOF-step | setup s | contact % | crack pairs |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  "$BUILD"/bench/bench_transient --orders 1,2,3,4 --elements 1e4,1e5,1e6 --threads 1,2 --seconds 1.5 \
      --max-dofs 3.5e6 --crack 2>/dev/null | awk 'NR>1{printf "|"; for(i=1;i<=NF;i++) printf " %s |", $i; print ""}'
  echo
  echo "Roofline of the step (bench_transient --roofline: the update alone on vectors of the case's size):"
  "$BUILD"/bench/bench_transient --orders 1,2 --elements 1e5,1e6 --threads 1,2 --seconds 1.5 --max-dofs 3.5e6 \
      --crack --roofline 2>/dev/null | awk '/update alone/{sub(/^ +/, ""); print "- p = " p ", " d " DOFs, " t " thread(s): " $0; next} NR>1{p=$1; d=$3; t=$4}'
  echo
  echo "### Transient stability map: data/beam.yaml, cells [10,1,2], p = 1"
  load
  python3 bench/stability_map.py "$crackle" "$out/stability"
fi

if want spectrum; then
  echo
  echo "### Spectrum and transient accuracy against cost: data/beam.yaml at f1/2"
  load
  python3 bench/spectrum_wp.py "$crackle" "$out/spectrum" --budget 900
  mkdir -p docs/img
  sed "s#set output .*#set output 'docs/img/spectrum-work-precision.png'#" "$out/spectrum/spectrum_wp.gp" | gnuplot
  echo
  echo "Plot: docs/img/spectrum-work-precision.png"
  echo
  echo "### The same signature by the reduced model, uniform against graded meshes (issue 15)"
  load
  python3 bench/spectrum_wp.py "$crackle" "$out/spectrum-graded" --graded --budget 1800
fi

if want study; then
  echo
  echo "### Depth study: crackle study data/depth-study.yaml"
  echo
  dir="${STUDY_DIR:-/tmp/depth-study}"
  if [[ -f "$dir/study.csv" ]]; then
    [[ -f "${STUDY_TIME:-/tmp/depth.time}" ]] && echo "time: $(tr '\n' ' ' < "${STUDY_TIME:-/tmp/depth.time}")" && echo
    python3 - "$dir/study.csv" <<'EOF'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
print("| " + " | ".join(rows[0]) + " |")
print("|" + "---|" * len(rows[0]))
for row in rows[1:]:
    print("| " + " | ".join(row) + " |")
EOF
  else
    echo "(no $dir/study.csv: run \`/usr/bin/time -v -o /tmp/depth.time crackle study data/depth-study.yaml -o $dir\` first)"
  fi
fi

if want reduced; then
  echo
  echo "### Reduced vs full transient: data/beam.yaml (wall time end to end, spectrum indices)"
  load
  full="${FULL_DIR:-$out/reduced-full}"
  [[ -f "$full/run.json" ]] || "$crackle" run data/beam.yaml -o "$full" -q >/dev/null
  cache="$out/reduced-cache"
  rm -rf "$cache"
  runs=()
  red() { local name=$1; shift; "$crackle" run data/beam.yaml -o "$out/$name" -q --set transient.model=reduced "$@" >/dev/null; runs+=("$out/$name"); }
  red reduced-cold --modal-cache "$cache"
  red reduced-cached --modal-cache "$cache" --set transient.excitation.amplitude=40
  for m in 10 20 40 80; do red "reduced-m$m" --modal-cache "$cache" --set transient.reduced.modes=$m; done
  for n in 20 80; do red "reduced-s$n" --modal-cache "$cache" --set transient.reduced.steps_per_period=$n; done
  python3 - "$full" "${runs[@]}" <<'PY'
import sys
sys.path.insert(0, "bench")
from run_outputs import read as read_run
def read(d):
    return read_run(d, "tip")
fw, fst, ft, fa1, fi = read(sys.argv[1])
print("| run | modes | steps/period | steps | wall s | transient stage s | cached | A1 err | A2/A1 err | A3/A1 err |")
print("|---|---|---|---|---|---|---|---|---|---|")
print(f"| full | - | - | {ft['steps']} | {fw:.1f} | {fst['transient']:.1f} | - | 0 | 0 | 0 |")
for d in sys.argv[2:]:
    w, st, t, a1, i = read(d)
    scale = 2.0 if "cached" in d else 1.0  # the cached case doubles the amplitude
    print(f"| {d.split('/')[-1]} | {t['modes']} | {t['steps_per_period']} | {t['steps']} | {w:.2f} | {st['transient']:.2f} | "
          f"{t['reduction_cached']} | {a1 / scale / fa1 - 1:.1e} | {i['A2/A1'] / fi['A2/A1'] - 1:.1e} | {i['A3/A1'] / fi['A3/A1'] - 1:.1e} |")
PY
fi

if want reduced-scale; then
  echo
  echo "### Reduced transient: cost per step against crack pairs and modes (bench_reduced, one process)"
  load
  # One thread: the CPU us/step column is then the solve's own cost.
  OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 /usr/bin/time -v -o "$out/reduced-scale-time.txt" "$BUILD"/bench/bench_reduced \
    --pairs "${REDUCED_PAIRS:-100,300,1000,3000,5000}" --modes 10,40
  echo
  echo "peak RSS of the whole sweep over sizes: $(awk '/Maximum resident/{print int($6/1024)}' "$out/reduced-scale-time.txt") MiB"
fi

if want reduced-snapshots; then
  echo
  echo "### Reduced transient: the cost of snapshots (data/beam.yaml, all 60 periods, cached reduction, 3 alternated runs each)"
  load
  cache="$out/snapshots-cache"
  rm -rf "$cache"
  "$crackle" run data/beam.yaml -o "$out/snapshots-warm" -q --set transient.model=reduced --modal-cache "$cache" >/dev/null
  dirs=()
  for k in 1 2 3; do
    for n in 0 10 60; do
      "$crackle" run data/beam.yaml -o "$out/snapshots-$n-$k" -q --set transient.model=reduced --modal-cache "$cache" \
        --set spectrum.plots=false --set spectrum.steady_state.tolerance=0 --set transient.snapshots.count=$n >/dev/null
      dirs+=("$out/snapshots-$n-$k")
    done
  done
  python3 - "${dirs[@]}" <<'PY'
import json, os, statistics, sys
rows = {}
for d in sys.argv[1:]:
    n = int(d.split("-")[-2])
    r = json.load(open(d + "/run.json")); st = {x["name"]: x["seconds"] for x in r["stages"]}
    size = sum(os.path.getsize(os.path.join(d, f)) for f in os.listdir(d) if f.startswith("snapshot_"))
    rows.setdefault(n, []).append((st["transient"], r["wall_s"], size))
base = statistics.median(t for t, _, _ in rows[0])
print("| snapshots | transient stage s (median of 3) | run.json wall s (median) | transient s over 0 snapshots | snapshot MiB |")
print("|---|---|---|---|---|")
median = {n: statistics.median(x[0] for x in rows[n]) for n in rows}
for n in sorted(rows):
    w = statistics.median(x[1] for x in rows[n])
    print(f"| {n} | {median[n]:.3f} | {w:.3f} | {median[n] - base:.3f} | {rows[n][0][2] / 2**20:.1f} |")
each = (median[60] - median[10]) / 50
print(f"\neach further snapshot (10 -> 60): {each:.4f} s; the first (the factor of K, then one solve): "
      f"{median[10] - base - 9 * each:.3f} s")
PY
fi

if want reduced-composite; then
  echo
  echo "### Reduced vs full transient: data/composite-plate.yaml cut to ${COMPOSITE_PERIODS:-12} periods (no steady-state stop)"
  load
  periods="${COMPOSITE_PERIODS:-12}"
  # Both models on the same (ungraded) mesh.
  cut=(--set transient.periods="$periods" --set spectrum.steady_state.tolerance=0 --set spectrum.steady_state.min_periods=4
       --set spectrum.steady_state.window_periods=4 --set mesh.box.grading.mode=none)
  cache="$out/composite-cache"
  rm -rf "$cache"
  [[ -f "${COMPOSITE_FULL_DIR:-$out/composite-full}/run.json" ]] || \
    "$crackle" run data/composite-plate.yaml -o "$out/composite-full" -q "${cut[@]}" >/dev/null
  "$crackle" run data/composite-plate.yaml -o "$out/composite-reduced-cold" -q "${cut[@]}" --set transient.model=reduced \
    --modal-cache "$cache" >/dev/null
  "$crackle" run data/composite-plate.yaml -o "$out/composite-reduced-cached" -q "${cut[@]}" --set transient.model=reduced \
    --modal-cache "$cache" >/dev/null
  python3 - "${COMPOSITE_FULL_DIR:-$out/composite-full}" "$out/composite-reduced-cold" "$out/composite-reduced-cached" <<'PY'
import sys
sys.path.insert(0, "bench")
from run_outputs import read as read_run
def read(d):
    return read_run(d, "top")
fw, fst, ft, fa1, fi = read(sys.argv[1])
print("| run | modes | pairs | steps | us/step | wall s | modal s | transient s | A1 | A2/A1 | A3/A1 | A1/2/A1 |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
def row(name, w, st, t, a1, i):
    print(f"| {name} | {t.get('modes', '-')} | {t.get('pairs', '-')} | {t['steps']} | {1e6 * t['wall_s'] / t['steps']:.1f} | {w:.1f} | "
          f"{st['modal']:.1f} | {st['transient']:.1f} | {a1:.4e} | {i['A2/A1']:.4e} | {i['A3/A1']:.4e} | {i.get('A1/2/A1', float('nan')):.3e} |")
row("full", fw, fst, ft, fa1, fi)
for d in sys.argv[2:]:
    row(d.split('/')[-1], *read(d))
PY
fi

if want sweep; then
  load
  echo "### Sweep of data/beam.yaml (crackle sweep; stage times from sweep.json)"
  cache="$out/sweep-cache"
  rm -rf "$cache"
  sw() { local name=$1; shift; /usr/bin/time -f "%e s wall, %U s user" "$crackle" sweep data/beam.yaml -o "$out/$name" -q --modal-cache "$cache" "$@" >/dev/null; echo "$out/$name"; }
  dirs=("$(sw sweep-hb)" "$(sw sweep-stepped --set sweep.method=stepped_sine --set sweep.points=50)")
  dirs+=("$(sw sweep-nostab --set sweep.stability=false)")
  for h in 5 10 20 30 40; do dirs+=("$(sw "sweep-h$h" --set sweep.harmonics=$h --set sweep.points=50)"); done
  python3 - "${dirs[@]}" <<'PY'
import json, sys
print("| run | method | H | pairs | unknowns | points | modal s | reduction s | sweep s | s/point | wall s | A2/A1 peak [Hz] | vs f_b/2 | A2/A1 | A3/A1 peak |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for d in sys.argv[1:]:
    j = json.load(open(d + "/sweep.json")); st = {x["name"]: x["seconds"] for x in j["stages"]}
    p = next(iter(j["probes"].values()))["peak_a2_over_a1"]; fb = j["bilinear_hz"]
    print(f"| {d.split('/')[-1]} | {j['settings']['method']} | {j['settings']['harmonics']} | {j['model']['pairs']} | "
          f"{j['model']['unknowns']} | {j['points']} | {st['modal']:.1f} | {st['reduction']:.1f} | {st['sweep']:.1f} | "
          f"{j['seconds_per_point']:.3f} | {j['wall_s']:.1f} | {p['frequency_hz']:.2f} | {p['frequency_hz'] / (fb / 2) - 1:+.2%} | "
          f"{p['value']:.5f} | {next(iter(j['probes'].values()))['peak_a3_over_a1']['value']:.6f} |")
PY
fi
