#!/usr/bin/env python3
"""Modal work-precision (issue 3): error of the first MODES frequencies of data/beam.yaml (variants
uncracked and open) against a reference, versus wall time, over the mesh size h and the order p.

Usage: bench/modal_wp.py CRACKLE OUTDIR [--scene data/beam.yaml] [--quick]
Runs `crackle modal SCENE --set mesh.box.order=P --set mesh.box.cells=[NX,NY,NZ]` per point, reads
OUTDIR/<point>/modal.json, and prints Markdown tables; writes OUTDIR/modal_wp.csv and the gnuplot
data/script OUTDIR/modal_wp.{dat,gp} (run gnuplot on it to get the PNG).

Wall time of a variant = its assembly + eigen-solve + post-processing (timings_s of the variant in
modal.json); the whole command (mesh, both variants, VTU output) is reported too. Points that ran
in under 5 s are repeated and the fastest run is kept (the machine is shared).
The reference is the finest point at the highest order (p = 4, [40,4,2] by default); its own error
is estimated from the p = 4 sequence, assuming the eigenvalue rate h^(2p).
"""
import json
import math
import os
import subprocess
import sys
import time

MODES = 6
# (p, [NX, NY, NZ]): h = 0.2 m / NX along the beam, the same aspect in y and z (0.02, 0.01 m).
# NX = 10 is not possible: the crack plane x = 0.05 m must be a grid plane.
POINTS = [
    (1, [20, 2, 1]), (1, [40, 4, 2]), (1, [80, 8, 4]), (1, [160, 16, 8]),
    (2, [20, 2, 1]), (2, [40, 4, 2]), (2, [80, 8, 4]),
    (3, [20, 2, 1]), (3, [40, 4, 2]),
    (4, [20, 2, 1]),
]
REFERENCE = (4, [40, 4, 2])
VARIANTS = ["uncracked", "open"]
REUSE = "--reuse" in sys.argv


def run_point(crackle, scene, outdir, p, cells, repeats):
    name = f"p{p}_{cells[0]}x{cells[1]}x{cells[2]}"
    best = None
    out = os.path.join(outdir, name)
    if REUSE and os.path.exists(os.path.join(out, "wall.json")):
        repeats = 0
        with open(os.path.join(out, "wall.json")) as handle:
            best = json.load(handle)
    for attempt in range(repeats):
        cmd = [crackle, "modal", scene, "--set", f"mesh.box.order={p}",
               "--set", "mesh.box.cells=[%d,%d,%d]" % tuple(cells), "--set", f"modal.modes={MODES}", "-o", out]
        start = time.monotonic()
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        wall = time.monotonic() - start
        if proc.returncode != 0:
            sys.stderr.write(f"modal_wp: {' '.join(cmd)} failed ({proc.returncode}): {proc.stderr[-400:]}\n")
            return None
        with open(os.path.join(out, "modal.json")) as handle:
            data = json.load(handle)
        result = {"name": name, "p": p, "cells": cells, "command_s": wall, "variants": {}}
        for variant in VARIANTS:
            v = data["variants"][variant]
            t = v["timings_s"]
            result["variants"][variant] = {
                "dofs": v["free_dofs"], "f": v["frequencies_hz"][:MODES],
                "time": t["assembly"] + t["solve"] + t["postprocess"],
                "factorization": t["factorization"], "iterations": t["iterations"]}
        if best is None or wall < best["command_s"]:
            best = result
            with open(os.path.join(out, "wall.json"), "w") as handle:
                json.dump(best, handle)
        if wall > 5.0:
            break
        repeats = max(repeats, 2)
    sys.stderr.write(f"modal_wp: {name}: {best['command_s']:.2f} s\n")
    return best


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    crackle, outdir = sys.argv[1], sys.argv[2]
    scene = "data/beam.yaml"
    if "--scene" in sys.argv:
        scene = sys.argv[sys.argv.index("--scene") + 1]
    points = POINTS
    if "--quick" in sys.argv:
        points = [pt for pt in POINTS if pt[1][0] <= 40]
    os.makedirs(outdir, exist_ok=True)
    results = []
    for p, cells in points:
        r = run_point(crackle, scene, outdir, p, cells, 1)
        if r:
            results.append(r)
    ref = run_point(crackle, scene, outdir, REFERENCE[0], REFERENCE[1], 1)
    # The clamped face (3D edge singularities) and, in the open variant, the crack front make the
    # convergence algebraic at a rate well below 2p, so the finest p = 4 mesh is not converged to
    # 0.1 % by itself. Reference = Richardson extrapolation of the p = 4 pair (h, h/2), per mode,
    # with the rate q observed on the three-level p = 2 sequence; the spread between that and the
    # rate of the p = 1 sequence is reported as the reference's uncertainty.
    def find(p, nx):
        if (p, nx) == (ref["p"], ref["cells"][0]):
            return ref
        return next((r for r in results if r["p"] == p and r["cells"][0] == nx), None)

    def rates(p, nxs, variant):
        seq = [find(p, nx) for nx in nxs]
        if None in seq:
            return None
        a, b, c = (s["variants"][variant]["f"] for s in seq)
        out = []
        for i in range(MODES):
            num, den = a[i] - b[i], b[i] - c[i]
            q = math.log2(num / den) if den != 0 and num / den > 1 else 1.0
            out.append(min(max(q, 0.5), 8.0))
        return out

    coarse = find(REFERENCE[0], REFERENCE[1][0] // 2)
    reference, ref_err, ref_spread, ref_rates = {}, {}, {}, {}
    for variant in VARIANTS:
        fine = ref["variants"][variant]["f"]
        q2 = rates(2, [20, 40, 80], variant)
        q1 = rates(1, [40, 80, 160], variant)
        if coarse is None or q2 is None:
            reference[variant], ref_err[variant], ref_spread[variant], ref_rates[variant] = fine, 0.0, 0.0, None
            continue
        fc = coarse["variants"][variant]["f"]
        extrap = [f + (f - c) / (2 ** q - 1) for f, c, q in zip(fine, fc, q2)]
        other = [f + (f - c) / (2 ** q - 1) for f, c, q in zip(fine, fc, q1 or q2)]
        reference[variant] = extrap
        ref_rates[variant] = q2
        ref_err[variant] = max(abs(f - e) / e for f, e in zip(fine, extrap))
        ref_spread[variant] = max(abs(a - b) / b for a, b in zip(other, extrap))
    rows = []
    for r in results + [ref]:
        for variant in VARIANTS:
            v = r["variants"][variant]
            fr = reference[variant]
            errors = [abs(a - b) / b for a, b in zip(v["f"], fr)]
            rows.append((r, variant, v, max(errors), errors[0]))
    with open(os.path.join(outdir, "modal_wp.csv"), "w") as handle:
        handle.write("p,nx,ny,nz,variant,free_dofs,time_s,factorization_s,iterations_s,command_s,max_rel_err,f1_rel_err\n")
        for r, variant, v, err, err1 in rows:
            handle.write("%d,%d,%d,%d,%s,%d,%.4f,%.4f,%.4f,%.3f,%.4e,%.4e\n" % (
                r["p"], *r["cells"], variant, v["dofs"], v["time"], v["factorization"], v["iterations"], r["command_s"],
                err, err1))
    # gnuplot data: one block per (variant, p).
    with open(os.path.join(outdir, "modal_wp.dat"), "w") as handle:
        for variant in VARIANTS:
            for p in (1, 2, 3, 4):
                handle.write(f"# {variant} p={p}\n")
                for r, var, v, err, _ in rows:
                    if var == variant and r["p"] == p:
                        handle.write("%.5g %.5g %d\n" % (v["time"], max(err, 1e-12), r["cells"][0]))
                handle.write("\n\n")
    for variant in VARIANTS:
        print("Reference (%s): Richardson extrapolation of p = 4 at %s and its half, rates q per mode %s "
              "(from the p = 2 sequence); f1..f6 = %s Hz. The p = 4 %s mesh alone is off by %.1e; "
              "the extrapolation is uncertain to about %.1e (p = 1 rates instead)." % (
                  variant, "x".join(map(str, REFERENCE[1])),
                  "[" + ", ".join("%.2f" % q for q in ref_rates[variant]) + "]" if ref_rates[variant] else "n/a",
                  ", ".join("%.3f" % f for f in reference[variant]), "x".join(map(str, REFERENCE[1])),
                  ref_err[variant], ref_spread[variant]))
    print()
    print("| p | cells | free DOFs | uncracked: s | uncracked: max err (6 modes) | open: s | open: max err (6 modes) | whole command s |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        u, o = r["variants"]["uncracked"], r["variants"]["open"]
        eu = next(e for rr, var, v, e, _ in rows if rr is r and var == "uncracked")
        eo = next(e for rr, var, v, e, _ in rows if rr is r and var == "open")
        print("| %d | %s | %d | %.2f | %.2e | %.2f | %.2e | %.1f |" % (
            r["p"], "x".join(map(str, r["cells"])), o["dofs"], u["time"], eu, o["time"], eo, r["command_s"]))
    print("| %d | %s | %d | %.2f | %.2e | %.2f | %.2e | %.1f |" % (
        ref["p"], "x".join(map(str, ref["cells"])), ref["variants"]["open"]["dofs"], ref["variants"]["uncracked"]["time"],
        ref_err["uncracked"], ref["variants"]["open"]["time"], ref_err["open"], ref["command_s"]))
    print()
    for variant in VARIANTS:
        hits = [(v["time"], r) for r, var, v, e, _ in rows if var == variant and e <= 1e-3]
        if hits:
            t, r = min(hits, key=lambda x: x[0])
            print("Fastest to 0.1%% (%s): p = %d, cells %s, %.2f s." % (variant, r["p"], r["cells"], t))
        else:
            print(f"Fastest to 0.1% ({variant}): no point reached it.")
    with open(os.path.join(outdir, "modal_wp.gp"), "w") as handle:
        handle.write(f"""set terminal pngcairo size 1100,450 font ',10'
set output '{outdir}/modal_wp.png'
set multiplot layout 1,2
set logscale xy
set format y '10^{{%L}}'
set grid
set yrange [5e-5:1]
set xlabel 'wall time per variant [s] (assembly + eigen-solve)'
set ylabel 'max relative error, first 6 frequencies'
set key bottom left
do for [v=0:1] {{
  set title (v == 0 ? 'beam, uncracked' : 'beam, open crack')
  plot for [p=0:3] '{outdir}/modal_wp.dat' index (4*v+p) using 1:2 with linespoints lw 2 pt 7 title sprintf('p = %d', p+1), \\
       1e-3 with lines dt 2 lc rgb 'gray' title '0.1 %'
}}
unset multiplot
""")


if __name__ == "__main__":
    main()
