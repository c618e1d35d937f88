#!/usr/bin/env python3
"""Spectrum and transient accuracy against cost (issues 4 and 5): data/beam.yaml driven at half its
first bilinear frequency; tip amplitude A1, A2/A1 and A3/A1 at steady state against wall time, over
the mesh (cells), the order p, the time-step factor and the steady-state tolerance.

Usage: bench/spectrum_wp.py CRACKLE OUTDIR [--scene data/beam.yaml] [--budget SECONDS] [--reuse] [--graded]

--graded runs the second set (issue 15): the reduced transient (transient.model=reduced, equal to the
full explicit model on the same mesh to ~1e-4 in A2/A1, docs/benchmarks.md section 8) on meshes graded
towards the crack front (mesh.box.grading=always) against the same meshes uniform, so that the
signature's discretisation error can be followed to meshes the full explicit model cannot afford.

Each point is one `crackle run SCENE -q --set ...`; its wall time is run.json wall_s (modal + transient
+ spectrum). The reference is the most expensive point that ran (REFERENCE below); differences are
relative to it. Points are run cheapest first; once --budget seconds (default 1200) are spent the
rest are skipped and listed. Writes OUTDIR/spectrum_wp.{csv,dat,gp}.
"""
import json
import os
import subprocess
import sys
import time

# (label, overrides); the default scene is p = 2, cells [40,4,2], tolerance 1e-3, safety factor 0.9.
POINTS = [
    ("p1 20x2x1", ["mesh.box.order=1", "mesh.box.cells=[20,2,1]"]),
    ("p1 20x2x1 dt 0.5", ["mesh.box.order=1", "mesh.box.cells=[20,2,1]", "transient.safety_factor=0.5"]),
    ("p1 40x4x2 tol 1e-2", ["mesh.box.order=1", "spectrum.steady_state.tolerance=1.0e-2"]),
    ("p1 40x4x2", ["mesh.box.order=1"]),
    ("p2 20x2x1", ["mesh.box.cells=[20,2,1]"]),
    ("p1 40x4x2 tol 1e-4", ["mesh.box.order=1", "spectrum.steady_state.tolerance=1.0e-4"]),
    ("p3 20x2x1", ["mesh.box.order=3", "mesh.box.cells=[20,2,1]"]),
    ("p2 40x4x2 (default)", []),
]
# Not included: p = 1 at [80,8,4] (the crack edge z = 0.007 m adds a 0.5 mm layer next to the grid
# line z = 0.0075 m, so dt drops ~4x), p = 3 at [40,4,2] and p = 2 at [80,8,4] (over 10 min each).
REFERENCE = "p2 40x4x2 (default)"
COMMON = ["spectrum.plots=false", "transient.progress=false"]

# --graded: the same signature by the reduced model, uniform (grading none) against graded (always).
REDUCED = ["transient.model=reduced"]
# Graded p = 4 at [40,4,2] (441 k DOFs) is left out: its modal stage holds K, M and their copies
# (~18 GB) before the factor (crackle refuses it with a clear error once the factor is analysed).
MESHES = ((2, (20, 2, 1)), (2, (40, 4, 2)), (3, (20, 2, 1)), (3, (40, 4, 2)), (4, (20, 2, 1)), (2, (80, 8, 4)))
GRADED_POINTS = [
    (f"{'graded' if graded else 'uniform'} p{p} {'x'.join(map(str, cells))}",
     REDUCED + [f"mesh.box.grading={'always' if graded else 'none'}", f"mesh.box.order={p}",
                f"mesh.box.cells=[{','.join(map(str, cells))}]"])
    for graded in (False, True) for p, cells in MESHES
] + [("uniform p4 40x4x2", REDUCED + ["mesh.box.grading=none", "mesh.box.order=4", "mesh.box.cells=[40,4,2]"])]
GRADED_REFERENCE = "graded p4 20x2x1"


def run_point(crackle, scene, outdir, label, overrides, reuse):
    out = os.path.join(outdir, label.replace(" ", "_").replace("(", "").replace(")", ""))
    if not (reuse and os.path.exists(os.path.join(out, "spectrum.json"))):
        cmd = [crackle, "run", scene, "-q", "-o", out]
        for item in overrides + COMMON:
            cmd += ["--set", item]
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if proc.returncode != 0:
            sys.stderr.write(f"spectrum_wp: {label} failed ({proc.returncode}): {proc.stderr[-300:]}\n")
            return None
    load = lambda name: json.load(open(os.path.join(out, name)))
    run, tr, sp = load("run.json"), load("transient.json"), load("spectrum.json")
    tip = sp["probes"]["tip"]
    a1 = next(h["amplitude"] for h in tip["harmonics"] if h["order"] == 1)
    point = {"label": label, "wall": run["wall_s"], "dofs": tr["dofs"], "steps": tr["steps"], "dt": tr["dt"],
             "dt_crit": tr["dt_critical"], "ns": tr["ns_per_dof_step"], "contact": tr["contact_time_fraction"],
             "f": sp["excitation_hz"], "A1": a1, "A2": tip["indices"]["A2/A1"], "A3": tip["indices"]["A3/A1"],
             "periods": sp["steady_state"].get("periods_used"), "settled": sp["steady_state"].get("settled"),
             "pairs": tr.get("pairs", 0),
             "energy": tr["energy_error"]}
    sys.stderr.write(f"spectrum_wp: {label}: {point['wall']:.1f} s\n")
    return point


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    crackle, outdir = sys.argv[1], sys.argv[2]
    scene = sys.argv[sys.argv.index("--scene") + 1] if "--scene" in sys.argv else "data/beam.yaml"
    budget = float(sys.argv[sys.argv.index("--budget") + 1]) if "--budget" in sys.argv else 1200.0
    reuse = "--reuse" in sys.argv
    os.makedirs(outdir, exist_ok=True)
    points, skipped, spent = [], [], 0.0
    point_set, reference = (GRADED_POINTS, GRADED_REFERENCE) if "--graded" in sys.argv else (POINTS, REFERENCE)
    for label, overrides in point_set:
        if spent > budget:
            skipped.append(label)
            continue
        start = time.monotonic()
        point = run_point(crackle, scene, outdir, label, overrides, reuse)
        spent += time.monotonic() - start
        if point:
            points.append(point)
    ref = next((p for p in points if p["label"] == reference), None) or max(points, key=lambda p: p["wall"])
    others = sorted((p for p in points if p is not ref), key=lambda p: p["wall"])
    runner = others[-1] if others else ref
    rel0 = lambda a, b: abs(a - b) / abs(b) if b else float("nan")
    print(f"Reference: {ref['label']} (the most expensive point run). No finer discretisation fit the time "
          f"budget; the next most expensive point, {runner['label']} (other h and p), differs from it by "
          f"{rel0(runner['A1'], ref['A1']):.1e} in A1, {rel0(runner['A2'], ref['A2']):.1e} in A2/A1 and "
          f"{rel0(runner['A3'], ref['A3']):.1e} in A3/A1: the best estimate of the reference's own error.")
    print()
    print("| point | DOFs (reduced: modes) | pairs | excitation Hz | dt / dt_crit | steps | periods to settle | wall s | "
          "ns/DOF-step | A1 tip [m] | A2/A1 | A3/A1 | dA1 | dA2/A1 | dA3/A1 |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    ratio = lambda a, b: "%.2f" % (a / b) if b else "-"
    rel = lambda a, b: abs(a - b) / abs(b) if b else float("nan")
    with open(os.path.join(outdir, "spectrum_wp.csv"), "w") as csv, open(os.path.join(outdir, "spectrum_wp.dat"), "w") as dat:
        csv.write("label,dofs,excitation_hz,dt_over_dtcrit,steps,periods,settled,wall_s,ns_per_dof_step,A1_m,A2_A1,A3_A1\n")
        for p in points:
            print("| %s | %d | %d | %.2f | %s | %d | %s%s | %.1f | %.1f | %.4e | %.4e | %.3e | %.1e | %.1e | %.1e |" % (
                p["label"], p["dofs"], p["pairs"], p["f"], ratio(p["dt"], p["dt_crit"]), p["steps"], p["periods"],
                "" if p["settled"] else " (not settled)", p["wall"], p["ns"], p["A1"], p["A2"], p["A3"],
                rel(p["A1"], ref["A1"]), rel(p["A2"], ref["A2"]), rel(p["A3"], ref["A3"])))
            csv.write("%s,%d,%.6g,%s,%d,%s,%s,%.3f,%.2f,%.6e,%.6e,%.6e\n" % (
                p["label"], p["dofs"], p["f"], ratio(p["dt"], p["dt_crit"]), p["steps"], p["periods"], p["settled"], p["wall"],
                p["ns"], p["A1"], p["A2"], p["A3"]))
            dat.write('%.4g %.6e %.6e "%s"\n' % (p["wall"], p["A2"], p["A3"], p["label"]))
    if skipped:
        print()
        print(f"Skipped (budget of {budget:.0f} s spent): {', '.join(skipped)}.")
    with open(os.path.join(outdir, "spectrum_wp.gp"), "w") as handle:
        handle.write(f"""set terminal pngcairo size 900,450 font ',10'
set output '{outdir}/spectrum_wp.png'
set logscale x
set grid
set xlabel 'wall time of crackle run [s]'
set ylabel 'A2/A1 at the tip'
set y2label 'A3/A1 at the tip'
set ytics nomirror
set y2tics
set key bottom right
set xrange [1:1000]
plot '{outdir}/spectrum_wp.dat' using 1:2 with points pt 7 ps 1.5 title 'A2/A1', \\
     '' using 1:2:4 with labels left offset 1,-0.3 rotate by 25 font ',7' notitle, \\
     '' using 1:3 axes x1y2 with points pt 6 ps 1.5 title 'A3/A1 (right axis)'
""")


if __name__ == "__main__":
    main()
