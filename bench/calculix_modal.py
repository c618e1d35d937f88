#!/usr/bin/env python3
"""Modal work-precision against CalculiX: the open-crack cantilever of data/beam.yaml (crack depths
a = 0.3 h and 0.5 h), crackle and CalculiX 2.20 (`ccx`, Debian package calculix-ccx) on the same
machine in the same run.

Usage: bench/calculix_modal.py CRACKLE OUTDIR [--reuse] [--quick] [--element C3D20R|C3D20]
                               [--reference stored|run] [--ccx-clamp-layers N] [--ccx-threads OMP,SPOOLES]
                               [--validate]
  CRACKLE     the crackle binary (e.g. build/apps/crackle)
  --reuse     keep the runs already in OUTDIR
  --quick     only the two smallest meshes per code (for testing the script)
  --element   CalculiX element type (default C3D20R: 20-node bricks, reduced integration)
  --reference stored (default): the reference frequencies below (STORED_REFERENCE); run: compute
              them again (crackle p = 4, 413k DOFs: 4-5 min and 17 GB per depth)
  --ccx-clamp-layers  also grade the CalculiX meshes towards the clamped face's edges (default 0)
  --ccx-threads   OMP_NUM_THREADS,CCX_NPROC_EQUATION_SOLVER for ccx (default 2,1: on 2 cores SPOOLES's
              threaded factor and solves were 1.6-3x slower than its serial ones)
  --validate  only CalculiX on two coarse meshes: uncracked f1..f6 against docs/benchmarks.md's
              converged values, a = 0.3 h open against the reference below, and the crack-face
              duplication check

Both codes solve the OPEN crack (faces free, no contact) for the 10 lowest modes, one command per
point, timed whole by /usr/bin/time -v (wall time, peak RSS). crackle runs `crackle modal
data/beam.yaml -q --set modal.modes=10 --set modal.variants=[open]` (one eigenproblem, as CalculiX)
with accuracy.estimate=off, except the accuracy.tolerance rows, whose time includes the estimate's
other element orders (crackle modal does not refine to meet the tolerance: it reports met / not met).
CalculiX gets a structured mesh of 20-node bricks (standard C3D20 node order) on the same box,
graded towards the crack front (x = 0.05 m, z = 0.01 m - a) in x and z as bench/modal_graded.py
grades crackle's (lines at front -/+ h ratio^k, k = 1..L, h the uniform cell); the crack-face nodes
(x = 0.05, z > front) are duplicated, one copy for the elements on each side (checked), the front
line and the ligament below stay shared; *FREQUENCY with the default solver (SPOOLES + ARPACK).

Reference per depth: crackle p = 4 graded towards the crack front and towards the clamped face and
its edges (STORED_REFERENCE below says how it was made and checked). Without the clamp grading every
frequency is 2-3e-4 high, which is most of the error of the finer meshes of both codes. Modes are paired by
sorted frequency; each mode is labelled from the tip corners' displacement (z: bending in z, y:
bending in y, t: torsion, a: axial), and a mode whose symmetry about y = 0.01 m (z, a symmetric; y, t
antisymmetric) differs from the reference's at the same sorted position is reported as a swap
(within a class the crack mixes z-bending with axial motion and y-bending with torsion, so z/a and
y/t labels may trade places without a swap).

Prints a Markdown table per depth (code, setting, DOFs, wall s, peak RSS MiB, max relative error of
f1..f6 and of f1..f10, the time inside: matrices / factor / eigen-solve) and, for each crackle row,
the cheapest CalculiX row at least as accurate on f1..f6 with the time ratio, and CalculiX's time at
exactly that error (log-log between the two meshes of its error-time front that bracket it); then the reference
against the finest CalculiX mesh. Writes OUTDIR/calculix_modal.csv and the plot
OUTDIR/calculix_modal.png (error against time; gnuplot script calculix_modal.gp).
"""
import argparse
import array
import csv
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from modal_graded import graded_lines  # noqa: E402  (lines at center -/+ h ratio^k)
SCENE = os.path.join(HERE, "..", "data", "beam.yaml")
LENGTH, WIDTH, DEPTH = 0.2, 0.02, 0.01  # m, along x, y, z
CRACK_X = 0.05
E, NU, RHO = 210.0e9, 0.3, 7850.0
MODES = 10
CRACKS = {"0.3h": 0.003, "0.5h": 0.005}  # crack depth a [m] from the top face z = DEPTH
# Converged values (docs/benchmarks.md section 2 and "Open crack on graded meshes").
UNCRACKED_CONVERGED = [209.366, 415.665, 1297.042, 2493.189, 3001.838, 3568.616]
OPEN_03H_CONVERGED = [201.629, 409.978, 1295.487, 2490.708, 2970.250, 3473.077]
# The reference (the full model on a finer mesh): crackle p = 4 on cells [20,2,1], graded towards the
# crack front (mesh.box.grading: always, 3 layers of ratio 0.2) and towards the clamped face and its
# edges by mesh.box.lines (CLAMP_LINES: 2 layers of ratio 0.2 at x = 0, y = 0 and 0.02, z = 0 and
# 0.01), both variants, 10 modes: 413,400 free DOFs, 4-5 min and 17 GB per depth (`--reference run`
# recomputes it). Its uncracked f1..f6 agree with the Richardson-extrapolated uniform p = 4 values of
# docs/benchmarks.md section 2 to 4e-5 (f1 to 1e-6); the same mesh at p = 3 (221,787 DOFs) differs
# from it by at most 8e-5 (a = 0.3 h) and 2.2e-4 (a = 0.5 h, f1; 1.4e-4 for the others), so its
# own error is about a quarter of that. Without the clamp lines (bench/modal_graded.py's REFERENCE)
# every frequency is 2-3e-4 high: docs/benchmarks.md's converged open f1..f6 of section 2 carry it.
CLAMP_LINES = {"x": [0.0004, 0.002], "y": [0.0004, 0.002, 0.018, 0.0196], "z": [0.0004, 0.002, 0.008, 0.0096]}
REFERENCE_SETS = ["mesh.box.order=4", "mesh.box.cells=[20,2,1]", "mesh.box.grading.mode=always",
                  "mesh.box.grading.layers=3", "mesh.box.grading.ratio=0.2", "accuracy.estimate=off"] + [
                      "mesh.box.lines.%s=%s" % (axis, json.dumps(lines)) for axis, lines in CLAMP_LINES.items()]
STORED_REFERENCE = {  # computed 2026-12-07 by `--reference run` (crackle at a124143)
    "0.3h": {"dofs": 413400, "wall_s": 273,
             "open": [201.568320, 409.853199, 1295.039794, 2489.915188, 2969.728310, 3471.837420, 6302.233889, 6503.373223, 6708.474613, 8995.214663],
             "uncracked": [209.365890, 415.656459, 1297.008901, 2493.082650, 3001.779112, 3568.443892, 6478.558089, 6565.306751, 6825.645380, 9015.866598],
             "labels": {"open": "zyzytzayzt", "uncracked": "zyzytzayzt"}},
    "0.5h": {"dofs": 413400, "wall_s": 235,
             "open": [184.691381, 399.154812, 1290.773647, 2482.760085, 2921.991932, 3275.307029, 5795.778566, 6392.676707, 6681.285746, 8964.682854],
             "uncracked": [209.366030, 415.656467, 1297.008919, 2493.082647, 3001.779074, 3568.443886, 6478.558082, 6565.306742, 6825.645352, 9015.866478],
             "labels": {"open": "zyzytzzyzt", "uncracked": "zyzytzayzt"}},
}

# crackle rows: (name, --set overrides); the a = 0.5 h variant adds crack.region.z.
CRACKLE_ROWS = [
    ("beam.yaml (p=2, [40,4,2], auto grading)", []),
    ("p=3, [20,2,1], auto grading", ["mesh.box.order=3", "mesh.box.cells=[20,2,1]"]),
    ("p=4, [20,2,1], auto grading", ["mesh.box.order=4", "mesh.box.cells=[20,2,1]"]),
    ("p=3, [20,2,1], auto grading + clamp lines (x, y: 1 layer)",
     ["mesh.box.order=3", "mesh.box.cells=[20,2,1]", "mesh.box.lines.x=[0.002]", "mesh.box.lines.y=[0.002,0.018]"]),
    ("p=2, [88,8,4], auto grading", ["mesh.box.cells=[88,8,4]"]),
    # The tolerance on p = 3: order 2 is the estimate's other level. On data/beam.yaml (p = 2) the levels
    # would be orders 3 and 4 on [40,4,2] (~440k DOFs at order 4, more than this benchmark's budget).
    ("p=3, [20,2,1] + accuracy.tolerance=1e-3", ["mesh.box.order=3", "mesh.box.cells=[20,2,1]",
                                                 "accuracy.tolerance=0.001"]),
]
# CalculiX meshes: (base cells, graded layers, ratio).
# Twenty-node bricks need the beam's depth resolved more than crackle's p >= 2 cells do (at 0.5 h,
# [40,4,2] stays at 2e-3 in f1 whatever the layers; [40,4,4] is at 9e-4), hence nz = nx / 10.
CALCULIX_ROWS = [
    ([20, 2, 1], 1, 0.2), ([20, 2, 1], 2, 0.2), ([40, 4, 2], 2, 0.2), ([40, 4, 4], 3, 0.2),
    ([60, 6, 6], 3, 0.2), ([80, 4, 8], 3, 0.2), ([100, 6, 10], 3, 0.2), ([120, 6, 12], 3, 0.2),
]  # [120,8,12] (262k equations) took 216 s on 2 cores, over this benchmark's ~3 min per run
QUICK_CRACKLE = 2
QUICK_CALCULIX = 2


# ---------------------------------------------------------------------------------------------
# Timing
# ---------------------------------------------------------------------------------------------

def time_file_values(time_file):
    """(wall s, peak RSS MiB) from a /usr/bin/time -v output file."""
    wall, rss = float("nan"), float("nan")
    with open(time_file) as handle:
        for line in handle:
            if "Elapsed (wall clock)" in line:
                seconds = 0.0
                for part in line.rsplit(": ", 1)[1].strip().split(":"):
                    seconds = seconds * 60 + float(part)
                wall = seconds
            elif "Maximum resident set size" in line:
                rss = int(line.rsplit(":", 1)[1]) / 1024.0
    return wall, rss


def timed(cmd, time_file, cwd=None, env=None, log=None):
    """Runs cmd under /usr/bin/time -v; returns (exit code, wall s, peak RSS MiB)."""
    with open(log or os.devnull, "w") as out:
        proc = subprocess.run(["/usr/bin/time", "-v", "-o", time_file] + cmd, cwd=cwd, env=env,
                              stdout=out, stderr=subprocess.STDOUT)
    return (proc.returncode, *time_file_values(time_file))


def timed_lines(cmd, time_file, cwd, env, log):
    """As timed(), with each output line stamped with the seconds since the start (the command's
    stdout line-buffered by stdbuf) in the log; returns (exit code, wall s, peak RSS MiB, stamped
    lines [(s, text)])."""
    start = time.monotonic()
    stamped = []
    with open(log, "w") as out:
        proc = subprocess.Popen(["/usr/bin/time", "-v", "-o", time_file, "stdbuf", "-oL"] + cmd, cwd=cwd, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        for line in proc.stdout:
            t = time.monotonic() - start
            stamped.append((t, line.rstrip()))
            out.write("%8.3f %s\n" % (t, line.rstrip()))
        proc.wait()
    return (proc.returncode, *time_file_values(time_file), stamped)


# ---------------------------------------------------------------------------------------------
# Mode labels from the tip corners (x = LENGTH, y in {0, WIDTH}, z in {0, DEPTH})
# ---------------------------------------------------------------------------------------------

TIP_CORNERS = [(LENGTH, y, z) for y in (0.0, WIDTH) for z in (0.0, DEPTH)]


def mode_label(corners):
    """corners: [(y, z, ux, uy, uz)] at the four tip corners -> 'z', 'y', 't' or 'a'."""
    n = len(corners)
    yc = sum(c[0] for c in corners) / n
    zc = sum(c[1] for c in corners) / n
    ux = sum(c[2] for c in corners) / n
    uy = sum(c[3] for c in corners) / n
    uz = sum(c[4] for c in corners) / n
    r2 = sum((c[0] - yc) ** 2 + (c[1] - zc) ** 2 for c in corners) / n
    twist = sum(((c[0] - yc) * c[4] - (c[1] - zc) * c[3]) for c in corners) / n / r2
    scores = {"a": abs(ux), "y": abs(uy), "z": abs(uz), "t": abs(twist) * r2 ** 0.5}
    return max(scores, key=scores.get)


def vtu_labels(path):
    """Labels of the modes in crackle's modes_<variant>.vtu (raw appended data, UInt64 headers)."""
    with open(path, "rb") as handle:
        data = handle.read()
    start = data.index(b"<AppendedData")
    base = data.index(b"_", start) + 1
    header = data[:start].decode("ascii", "replace")

    def read_array(name):
        m = re.search(r'<DataArray type="Float64" Name="%s" NumberOfComponents="3" format="appended" '
                      r'offset="(\d+)"' % name, header)
        offset = base + int(m.group(1))
        (nbytes,) = struct.unpack_from("<Q", data, offset)
        values = array.array("d")
        values.frombytes(data[offset + 8: offset + 8 + nbytes])
        if sys.byteorder != "little":
            values.byteswap()
        return values

    points = read_array("Points")
    corners = []
    for target in TIP_CORNERS:
        best = min(range(len(points) // 3),
                   key=lambda i: sum((points[3 * i + d] - target[d]) ** 2 for d in range(3)))
        corners.append(best)
    labels = []
    for name in sorted(set(re.findall(r'Name="(mode_\d+)"', header)), key=lambda n: int(n[5:])):
        u = read_array(name)
        labels.append(mode_label([(points[3 * i + 1], points[3 * i + 2], u[3 * i], u[3 * i + 1], u[3 * i + 2])
                                  for i in corners]))
    return labels


# ---------------------------------------------------------------------------------------------
# crackle
# ---------------------------------------------------------------------------------------------

def crackle_run(crackle, out, sets, reuse, variants="[open]"):
    """Runs `crackle modal` (timed whole) unless reused; returns the row's data."""
    record = out + ".json"
    if reuse and os.path.exists(record) and os.path.exists(os.path.join(out, "modal.json")):
        with open(record) as handle:
            return json.load(handle)
    if os.path.exists(out):
        shutil.rmtree(out)
    cmd = [crackle, "modal", SCENE, "-o", out, "-q", "--set", f"modal.modes={MODES}",
           "--set", f"modal.variants={variants}"]
    for s in sets:
        cmd += ["--set", s]
    code, wall, rss = timed(cmd, out + ".time", log=out + ".log")
    if code != 0:
        with open(out + ".log") as handle:
            tail = handle.read()[-600:]
        sys.exit(f"calculix_modal: {' '.join(cmd)} failed ({code}): {tail}")
    with open(os.path.join(out, "modal.json")) as handle:
        data = json.load(handle)
    result = {"wall_s": wall, "rss_mib": rss, "variants": {}, "accuracy": data.get("accuracy", {}),
              "command": cmd}
    for name, v in data["variants"].items():
        t = v["timings_s"]
        result["variants"][name] = {
            "f": v["frequencies_hz"], "dofs": v["free_dofs"],
            "solve_s": t["assembly"] + t["solve"] + t["postprocess"],
            "phases_s": {"matrices": t["assembly"], "factor": t.get("factorization", float("nan")),
                         "eigen": t.get("iterations", float("nan"))},
            "labels": vtu_labels(os.path.join(out, f"modes_{name}.vtu"))}
    with open(record, "w") as handle:
        json.dump(result, handle, indent=1)
    sys.stderr.write(f"calculix_modal: {os.path.basename(out)}: {wall:.1f} s, {rss:.0f} MiB\n")
    return result


def crack_sets(depth):
    return [f"crack.region.z=[{DEPTH - depth:.6g},{DEPTH:.6g}]"]


def reference(crackle, outdir, key, depth, reuse, run):
    """The reference of this crack depth: STORED_REFERENCE, or (run) computed again by crackle."""
    if not run:
        stored = STORED_REFERENCE[key]
        return {"wall_s": stored["wall_s"], "stored": True,
                "variants": {v: {"f": stored[v], "dofs": stored["dofs"], "labels": list(stored["labels"][v])}
                             for v in ("open", "uncracked")}}
    out = os.path.join(outdir, f"reference_{key}")
    return crackle_run(crackle, out, crack_sets(depth) + REFERENCE_SETS, reuse, variants="[uncracked,open]")


# ---------------------------------------------------------------------------------------------
# CalculiX
# ---------------------------------------------------------------------------------------------

def axis_lines(size, cells, fronts, layers, ratio):
    """Uniform lines, the fronts, and lines at front -/+ h ratio^k, k = 1..layers, h = size / cells
    the uniform cell (graded_lines, as bench/modal_graded.py); lines closer than 1e-9 size merge."""
    tol = 1e-9 * size
    h = size / cells
    candidates = [size * i / cells for i in range(cells + 1)] + list(fronts)
    for front in fronts:
        candidates += graded_lines(front, h, ratio, layers, 0.0, size)
    lines = []
    for x in sorted(candidates):
        if not lines or x - lines[-1] > tol:
            lines.append(x)
    return lines


# Standard C3D20 node order (CalculiX manual / shape20h.f): corners 1-4 at zeta = -1 counter-
# clockwise from (-1,-1), 5-8 at zeta = +1, then mid-edges 1-2, 2-3, 3-4, 4-1, 5-6, 6-7, 7-8, 8-5,
# 1-5, 2-6, 3-7, 4-8. With (xi, eta, zeta) along (x, y, z) the Jacobian is positive. Offsets are
# on the quadratic lattice (0, 1, 2 per cell).
C3D20_OFFSETS = [
    (0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2),
    (1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2),
    (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1),
]


def calculix_mesh(cells, layers, ratio, depth, open_crack=True, clamp_layers=0):
    """Nodes {id: (x, y, z)}, elements [[20 ids]], clamp ids, tip-corner ids, crack twins {original:
    copy}, mesh facts. clamp_layers > 0 also grades towards the clamped face's edges (x = 0 in x;
    y = 0, WIDTH and z = 0, DEPTH over the whole length): a check of what the clamp costs."""
    front_z = DEPTH - depth
    xs = axis_lines(LENGTH, cells[0], [CRACK_X], layers, ratio)
    ys = axis_lines(WIDTH, cells[1], [], 0, ratio)
    zs = axis_lines(DEPTH, cells[2], [front_z] if 0 < front_z < DEPTH else [], layers, ratio)
    if clamp_layers:
        xs = sorted(set(xs) | set(graded_lines(0.0, LENGTH / cells[0], ratio, clamp_layers, 0.0, LENGTH)))
        for lines, size, n in ((ys, WIDTH, cells[1]), (zs, DEPTH, cells[2])):
            for edge in (0.0, size):
                for x in graded_lines(edge, size / n, ratio, clamp_layers, 0.0, size):
                    if all(abs(x - y) > 1e-9 * size for y in lines):
                        lines.append(x)
            lines.sort()

    def lattice(lines):
        q = []
        for i in range(len(lines) - 1):
            q += [lines[i], 0.5 * (lines[i] + lines[i + 1])]
        return q + [lines[-1]]

    qx, qy, qz = lattice(xs), lattice(ys), lattice(zs)
    nqx, nqy, nqz = len(qx), len(qy), len(qz)
    ic = 2 * min(range(len(xs)), key=lambda i: abs(xs[i] - CRACK_X))
    kf = 2 * min(range(len(zs)), key=lambda k: abs(zs[k] - front_z))
    assert abs(qx[ic] - CRACK_X) < 1e-12 and abs(qz[kf] - front_z) < 1e-12, "crack plane/front not grid lines"
    ids = {}
    coords = {}
    next_id = 1
    for k in range(nqz):
        for j in range(nqy):
            for i in range(nqx):
                if (i % 2) + (j % 2) + (k % 2) <= 1:
                    ids[(i, j, k)] = next_id
                    coords[next_id] = (qx[i], qy[j], qz[k])
                    next_id += 1
    # The crack face: x = CRACK_X, z above the front; one more copy for the elements on x > CRACK_X.
    twin = {}
    if open_crack:
        for k in range(kf + 1, nqz):
            for j in range(nqy):
                if (ic, j, k) in ids:
                    twin[ids[(ic, j, k)]] = next_id
                    coords[next_id] = coords[ids[(ic, j, k)]]
                    next_id += 1
    elements = []
    for ez in range(len(zs) - 1):
        for ey in range(len(ys) - 1):
            for ex in range(len(xs) - 1):
                right = 2 * ex >= ic  # the element lies on x >= CRACK_X
                nodes = []
                for (a, b, c) in C3D20_OFFSETS:
                    key = (2 * ex + a, 2 * ey + b, 2 * ez + c)
                    n = ids[key]
                    if right and n in twin:
                        n = twin[n]
                    nodes.append(n)
                elements.append(nodes)
    clamp = [ids[(0, j, k)] for k in range(nqz) for j in range(nqy) if (0, j, k) in ids]
    tip = [ids[(nqx - 1, j, k)] for k in (0, nqz - 1) for j in (0, nqy - 1)]
    facts = {"nodes": len(coords), "elements": len(elements), "crack_twins": len(twin),
             "free_dofs": 3 * (len(coords) - len(clamp)), "lines": (len(xs), len(ys), len(zs)),
             "min_cell": min(min(b - a for a, b in zip(l, l[1:])) for l in (xs, zs))}
    return coords, elements, clamp, tip, twin, facts


def check_duplication(coords, elements, twin, depth):
    """Elements on each side of the crack use their own copy of the crack-face nodes; the front and
    the ligament are shared. Returns a line of text; raises on a violation."""
    front_z = DEPTH - depth
    original = set(twin)
    copies = set(twin.values())
    left_uses, right_uses, shared = set(), set(), set()
    for nodes in elements:
        xmin = min(coords[n][0] for n in nodes)
        for n in nodes:
            x, _, z = coords[n]
            if abs(x - CRACK_X) > 1e-12:
                continue
            if xmin < CRACK_X - 1e-12:
                left_uses.add(n)
            else:
                right_uses.add(n)
            if z <= front_z + 1e-12:
                shared.add(n)
    assert not (left_uses & copies), "an element on x < crack uses a copy"
    assert not (right_uses & original), "an element on x > crack uses an original crack-face node"
    assert all(coords[n][2] > front_z + 1e-12 for n in original), "a twin at or below the front"
    assert shared <= (left_uses & right_uses), "a front/ligament node not shared"
    return (f"{len(twin)} crack-face nodes duplicated (z > {front_z * 1e3:g} mm), "
            f"{len(shared)} front/ligament nodes on x = {CRACK_X} shared by both sides")


def write_deck(path, coords, elements, clamp, tip, element_type):
    def id_lines(ids):
        return "\n".join(", ".join(str(n) for n in ids[i:i + 16]) for i in range(0, len(ids), 16))

    with open(path, "w") as f:
        f.write("*HEADING\ncrackle benchmark: open-crack cantilever (bench/calculix_modal.py)\n")
        f.write("*NODE, NSET=NALL\n")
        for n in sorted(coords):
            x, y, z = coords[n]
            f.write(f"{n}, {x:.15g}, {y:.15g}, {z:.15g}\n")
        f.write(f"*ELEMENT, TYPE={element_type}, ELSET=EALL\n")
        for e, nodes in enumerate(elements, start=1):
            f.write(f"{e}, " + ", ".join(map(str, nodes[:15])) + ",\n" + ", ".join(map(str, nodes[15:])) + "\n")
        f.write("*NSET, NSET=CLAMP\n" + id_lines(clamp) + "\n")
        f.write("*NSET, NSET=TIP\n" + id_lines(tip) + "\n")
        f.write("*BOUNDARY\nCLAMP, 1, 3\n")
        f.write(f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{E:.6g}, {NU}\n*DENSITY\n{RHO}\n")
        f.write("*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n")
        f.write(f"*STEP\n*FREQUENCY\n{MODES}\n*NODE PRINT, NSET=TIP\nU\n*END STEP\n")


def parse_dat(path, coords, tip):
    """Frequencies [Hz] (cycles/time) and the tip corners' mode labels from the .dat file."""
    with open(path) as handle:
        text = handle.read()
    freqs = []
    at = text.index("E I G E N V A L U E   O U T P U T")
    for line in text[at:].splitlines()[1:]:
        parts = line.split()
        if len(parts) == 5 and parts[0].isdigit():
            freqs.append(float(parts[3]))
        elif freqs and not parts:
            break
    labels = []
    # Blocks " displacements (vx,vy,vz) for set TIP and time ..." follow, one per mode.
    for block in re.split(r"displacements \(vx,vy,vz\) for set TIP", text)[1:]:
        u = {}
        for line in block.splitlines()[1:]:
            parts = line.split()
            if len(parts) == 4 and parts[0].isdigit():
                u[int(parts[0])] = tuple(float(v) for v in parts[1:])
            elif u and not parts:
                break
        labels.append(mode_label([(coords[n][1], coords[n][2], *u[n]) for n in tip]))
    return freqs, labels


def calculix_run(outdir, cells, layers, ratio, depth, key, element_type, threads, reuse, open_crack=True,
                 clamp_layers=0):
    name = "ccx_%s_%s_%dx%dx%d_L%d_r%g%s%s" % (key, element_type, *cells, layers, ratio,
                                              "_clamp%d" % clamp_layers if clamp_layers else "",
                                              "" if open_crack else "_uncracked")
    out = os.path.join(outdir, name)
    record = out + ".json"
    if reuse and os.path.exists(record):
        with open(record) as handle:
            return json.load(handle)
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(out)
    start = time.monotonic()
    coords, elements, clamp, tip, twin, facts = calculix_mesh(cells, layers, ratio, depth, open_crack,
                                                                clamp_layers)
    check = check_duplication(coords, elements, twin, depth) if open_crack else "no crack"
    write_deck(os.path.join(out, "beam.inp"), coords, elements, clamp, tip, element_type)
    deck_s = time.monotonic() - start
    env = dict(os.environ, OMP_NUM_THREADS=str(threads[0]), CCX_NPROC_EQUATION_SOLVER=str(threads[1]))
    code, wall, rss, stamped = timed_lines(["ccx", "-i", "beam"], os.path.join(out, "time.txt"), out, env,
                                           os.path.join(out, "ccx.log"))
    log = "\n".join(text for _, text in stamped)
    if code != 0 or "Job finished" not in log:
        sys.exit(f"calculix_modal: ccx failed in {out} ({code}): {log[-800:]}")
    m = re.search(r"number of equations\s+(\d+)", log)

    def stamp(pattern):
        return next((t for t, text in stamped if pattern in text), float("nan"))

    # Phases from the stamped log: setup (input, structure, K and M), factor (SPOOLES), Lanczos
    # (ARPACK with SPOOLES solves), output (modes: results, .dat/.frd).
    factor, eigen, job = stamp("Factoring the system"), stamp("Calculating the eigenvalues"), stamp("Job finished")
    after = next((t for t, text in stamped if t > eigen and ("U^T*M*U" in text or "stress calculation" in text)),
                 float("nan"))
    phases = {"setup": factor, "factor": eigen - factor, "lanczos": after - eigen, "output": job - after}
    freqs, labels = parse_dat(os.path.join(out, "beam.dat"), coords, tip)
    result = {"wall_s": wall, "rss_mib": rss, "deck_s": deck_s, "equations": int(m.group(1)) if m else None,
              "f": freqs, "labels": labels, "facts": facts, "check": check, "phases_s": phases,
              "threads": list(threads)}
    with open(record, "w") as handle:
        json.dump(result, handle, indent=1)
    # The .frd/.dat of large meshes are kept (small: no field output is requested).
    sys.stderr.write(f"calculix_modal: {name}: {wall:.1f} s, {rss:.0f} MiB, {result['equations']} equations "
                     f"(deck {deck_s:.1f} s; " + ", ".join("%s %.1f s" % kv for kv in phases.items()) + ")\n")
    return result


# ---------------------------------------------------------------------------------------------
# Tables
# ---------------------------------------------------------------------------------------------

def max_error(f, ref, n):
    if len(f) < n:
        return float("nan")
    return max(abs(a - b) / b for a, b in zip(f[:n], ref[:n]))


def write_plot(outdir, tables):
    """OUTDIR/calculix_modal.{dat,gp,png}: error of f1..f6 against wall time, one panel per crack
    depth, CalculiX's meshes as a line and each crackle setting as a labelled point."""
    dat = os.path.join(outdir, "calculix_modal.dat")
    with open(dat, "w") as handle:
        for key, rows in tables:
            for code in ("CalculiX", "crackle"):
                handle.write(f"# {key} {code}: wall [s], max rel err f1..f6 [-], setting\n")
                for r in sorted((r for r in rows if r["code"] == code), key=lambda r: r["wall_s"]):
                    # A tolerance row is its run order's point again: unlabelled (the labels would overlap).
                    label = "" if "accuracy.tolerance" in r["setting"] else r["setting"].split(" (")[0]
                    handle.write('%.5g %.5g "%s"\n' % (r["wall_s"], r["err6"], label))
                handle.write("\n\n")
    png = os.path.join(outdir, "calculix_modal.png")
    script = os.path.join(outdir, "calculix_modal.gp")
    with open(script, "w") as handle:
        handle.write(f"""set terminal pngcairo size 1100,480 font ',9'
set output '{png}'
set multiplot layout 1,{len(tables)}
set logscale xy
set format y '10^{{%L}}'
set grid
set xlabel 'wall time, whole command [s]'
set ylabel 'max relative error of f1..f6 (open crack)'
set key top right
""")
        for index, (key, _) in enumerate(tables):
            handle.write(f"""set title 'beam, open crack a = {key}: crackle and CalculiX 2.20 (C3D20R), same machine'
plot '{dat}' index {2 * index} using 1:2 with linespoints lw 2 pt 6 lc rgb '#1f77b4' title 'CalculiX, graded meshes', \\
     '{dat}' index {2 * index + 1} using 1:2 with points pt 7 ps 1.3 lc rgb '#d62728' title 'crackle', \\
     '{dat}' index {2 * index + 1} using 1:2:3 with labels offset 0.8,0.6 left font ',7' notitle, \\
     1e-3 with lines dt 2 lc rgb 'black' title '0.1 %'
""")
        handle.write("unset multiplot\n")
    if shutil.which("gnuplot"):
        subprocess.run(["gnuplot", script], check=False)
    return png


def calculix_time_at(ccx_rows, error):
    """CalculiX's time at exactly `error`, log-log interpolated between the two meshes of its Pareto
    front (no faster mesh is more accurate) that bracket it; None when none is less accurate."""
    front = []
    for r in sorted(ccx_rows, key=lambda r: r["wall_s"]):
        if not front or r["err6"] < front[-1]["err6"]:
            front.append(r)
    for coarse, fine in zip(front, front[1:]):
        if fine["err6"] <= error <= coarse["err6"]:
            share = math.log(coarse["err6"] / error) / math.log(coarse["err6"] / fine["err6"])
            return coarse["wall_s"] * (fine["wall_s"] / coarse["wall_s"]) ** share
    return None


def symmetry(label):
    """The beam and its full-width crack are symmetric about y = WIDTH / 2: modes are symmetric
    (z-bending, axial: 'S') or antisymmetric (y-bending, torsion: 'A'). The crack couples z-bending
    with axial motion (and y-bending with torsion), so z/a (y/t) can trade places within a class as
    the mesh changes; a different class at the same sorted position is a real swap."""
    return "S" if label in ("z", "a") else "A"


def swaps(labels, ref_labels, n=MODES):
    return [i + 1 for i in range(min(n, len(labels), len(ref_labels)))
            if symmetry(labels[i]) != symmetry(ref_labels[i])]


def validate(outdir, element_type, threads, reuse):
    print("### CalculiX validation on coarse meshes (a = 0.3 h)")
    print()
    print("| mesh | variant | equations | wall s | f1..f6 [Hz] | max err f1..f6 vs reference | labels |")
    print("|---|---|---|---|---|---|---|")
    for cells, layers, ratio in (([20, 2, 1], 2, 0.2), ([40, 4, 4], 3, 0.2)):
        for open_crack, ref in ((False, UNCRACKED_CONVERGED), (True, STORED_REFERENCE["0.3h"]["open"])):
            r = calculix_run(outdir, cells, layers, ratio, CRACKS["0.3h"], "0.3h", element_type, threads, reuse,
                             open_crack)
            print("| [%s] L%d | %s | %s | %.1f | %s | %.2e | %s |" % (
                ",".join(map(str, cells)), layers, "open" if open_crack else "uncracked", r["equations"], r["wall_s"],
                ", ".join("%.2f" % f for f in r["f"][:6]), max_error(r["f"], ref, 6), "".join(r["labels"])))
            if open_crack:
                print(f"|  | ({r['check']}) | | | | | |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("crackle")
    parser.add_argument("outdir")
    parser.add_argument("--reuse", action="store_true")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--validate", action="store_true")
    parser.add_argument("--element", default="C3D20R", choices=["C3D20R", "C3D20"])
    parser.add_argument("--reference", default="stored", choices=["stored", "run"],
                        help="stored: STORED_REFERENCE; run: compute it again (4-5 min and 17 GB per depth)")
    parser.add_argument("--ccx-clamp-layers", type=int, default=0,
                        help="also grade the CalculiX meshes towards the clamped face's edges (default 0)")
    parser.add_argument("--ccx-threads", default="2,1",
                        help="OMP_NUM_THREADS,CCX_NPROC_EQUATION_SOLVER for ccx (default 2,1: SPOOLES's threaded "
                             "factor/solve was slower on 2 cores)")
    args = parser.parse_args()
    sys.stdout.reconfigure(line_buffering=True)  # the tables and the progress lines on stderr in order
    threads = tuple(int(t) for t in args.ccx_threads.split(","))
    crackle = os.path.abspath(args.crackle)
    outdir = os.path.abspath(args.outdir)
    os.makedirs(outdir, exist_ok=True)
    if shutil.which("ccx") is None:
        sys.exit("calculix_modal: no ccx on PATH (apt-get install calculix-ccx)")
    if args.validate:
        validate(outdir, args.element, threads, args.reuse)
        return
    crackle_rows = CRACKLE_ROWS[:QUICK_CRACKLE] if args.quick else CRACKLE_ROWS
    calculix_rows = CALCULIX_ROWS[:QUICK_CALCULIX] if args.quick else CALCULIX_ROWS
    csv_rows = []
    tables = []
    for key, depth in CRACKS.items():
        ref = reference(crackle, outdir, key, depth, args.reuse, args.reference == "run")
        f_ref, ref_labels = ref["variants"]["open"]["f"], ref["variants"]["open"]["labels"]
        twin = max_error(ref["variants"]["uncracked"]["f"], UNCRACKED_CONVERGED, 6)
        print()
        print(f"### Open crack a = {key} ({depth * 1e3:g} mm, front z = {(DEPTH - depth) * 1e3:g} mm), "
              f"{MODES} modes: crackle vs CalculiX ({args.element})")
        print()
        print("_load average at start: %s_" % " ".join(open("/proc/loadavg").read().split()[:3]))
        print()
        print("Reference (%s): crackle p = 4, cells [20,2,1] graded towards the crack front (3 layers) and the "
              "clamped face and its edges (2 layers), %d free DOFs, %.0f s (both variants); f1..f10 = %s Hz (modes "
              "%s); its uncracked f1..f6 are %.1e off the Richardson-extrapolated ones (per mode %s)." % (
                  "stored" if ref.get("stored") else "computed", ref["variants"]["open"]["dofs"], ref["wall_s"],
                  ", ".join("%.3f" % f for f in f_ref), "".join(ref_labels), twin,
                  ", ".join("%+.1e" % (a / b - 1) for a, b in zip(ref["variants"]["uncracked"]["f"], UNCRACKED_CONVERGED))))
        if key == "0.3h":
            print("docs/benchmarks.md's converged open f1..f6 are off this reference by %s." % ", ".join(
                "%+.1e" % (a / b - 1) for a, b in zip(OPEN_03H_CONVERGED, f_ref)))
        print()
        rows = []
        for name, sets in crackle_rows:
            out = os.path.join(outdir, "crackle_%s_%s" % (key, re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_")))
            extra = [] if any(s.startswith("accuracy.tolerance") for s in sets) else ["accuracy.estimate=off"]
            r = crackle_run(crackle, out, crack_sets(depth) + sets + extra, args.reuse)
            v = r["variants"]["open"]
            setting = name
            acc = r.get("accuracy", {})
            if acc.get("estimated"):
                setting += " (estimate %.1e: %s)" % (acc.get("error", float("nan")), "met" if acc.get("met") else "not met")
            rows.append({"code": "crackle", "setting": setting, "dofs": v["dofs"], "wall_s": r["wall_s"],
                         "rss_mib": r["rss_mib"], "f": v["f"], "labels": v["labels"], "phases": v["phases_s"]})
        for cells, layers, ratio in calculix_rows:
            r = calculix_run(outdir, cells, layers, ratio, depth, key, args.element, threads, args.reuse,
                             clamp_layers=args.ccx_clamp_layers)
            rows.append({"code": "CalculiX", "setting": "%s [%s], L=%d, r=%g%s" % (
                args.element, ",".join(map(str, cells)), layers, ratio,
                ", clamp L=%d" % args.ccx_clamp_layers if args.ccx_clamp_layers else ""), "dofs": r["equations"],
                "wall_s": r["wall_s"], "rss_mib": r["rss_mib"], "f": r["f"], "labels": r["labels"],
                "phases": {"matrices": r["phases_s"]["setup"], "factor": r["phases_s"]["factor"],
                           "eigen": r["phases_s"]["lanczos"]}})
        print("| code | setting | DOFs | wall s | peak RSS MiB | max err f1..f6 | max err f1..f10 | "
              "K,M / factor / eigen s | modes (swaps) |")
        print("|---|---|---|---|---|---|---|---|---|")
        for row in rows:
            row["err6"] = max_error(row["f"], f_ref, 6)
            row["err10"] = max_error(row["f"], f_ref, 10)
            row["swaps"] = swaps(row["labels"], ref_labels)
            ph = row["phases"]
            print("| %s | %s | %d | %.2f | %.0f | %.2e | %.2e | %.2f / %.2f / %.2f | %s%s |" % (
                row["code"], row["setting"], row["dofs"], row["wall_s"], row["rss_mib"], row["err6"], row["err10"],
                ph["matrices"], ph["factor"], ph["eigen"], "".join(row["labels"]),
                " (swap at %s)" % ",".join(map(str, row["swaps"])) if row["swaps"] else ""))
            csv_rows.append([key, depth, row["code"], row["setting"], row["dofs"], "%.3f" % row["wall_s"],
                             "%.1f" % row["rss_mib"], "%.4e" % row["err6"], "%.4e" % row["err10"],
                             "%.3f" % ph["matrices"], "%.3f" % ph["factor"], "%.3f" % ph["eigen"],
                             "".join(row["labels"]), " ".join(map(str, row["swaps"]))]
                            + ["%.6f" % f for f in row["f"][:MODES]])
        print()
        print("DOFs: crackle's free DOFs of the open variant; CalculiX's number of equations (its free DOFs). "
              "Wall time and peak RSS: the whole command under /usr/bin/time -v (crackle: mesh, one variant, "
              "VTU output; CalculiX: ccx -i on the deck, OMP_NUM_THREADS=%d, CCX_NPROC_EQUATION_SOLVER=%d; the "
              "deck's writing is not counted). K,M / factor / eigen: crackle's modal.json timings (assembly, "
              "factorization, iterations); CalculiX's stamped log (start to 'Factoring', SPOOLES factor, ARPACK "
              "with its solves). crackle's rows run the open variant alone with accuracy.estimate=off, except the "
              "accuracy.tolerance rows (their time includes the estimate's other orders, their frequencies are "
              "the run order's, K,M / factor / eigen are the run order's). Modes: tip-corner labels (z, y: "
              "bending; t: torsion; a: axial)." % threads)
        print()
        ccx_rows = [r for r in rows if r["code"] == "CalculiX"]
        tables.append((key, rows))
        for row in rows:
            if row["code"] != "crackle":
                continue
            match = [r for r in ccx_rows if r["err6"] <= row["err6"]]
            if match:
                best = min(match, key=lambda r: r["wall_s"])
                between = calculix_time_at(ccx_rows, row["err6"])
                print("- at equal accuracy: crackle %s (%.2e, %.1f s) vs CalculiX %s (%.2e, %.1f s): "
                      "CalculiX / crackle time %.2f; %s" % (
                          row["setting"], row["err6"], row["wall_s"], best["setting"], best["err6"], best["wall_s"],
                          best["wall_s"] / row["wall_s"],
                          "CalculiX at the same error %.1f s (between its meshes), %.2fx" % (between, between / row["wall_s"])
                          if between else "no CalculiX mesh above this error to interpolate from"))
            else:
                best = min(ccx_rows, key=lambda r: r["err6"])
                print("- at equal accuracy: crackle %s (%.2e, %.1f s): no CalculiX row reaches it (best %s: %.2e "
                      "in %.1f s)" % (row["setting"], row["err6"], row["wall_s"], best["setting"], best["err6"],
                                      best["wall_s"]))
        finest = max(ccx_rows, key=lambda r: r["dofs"])
        print()
        print("Reference vs the finest CalculiX mesh (%s, %d equations): max relative difference %.1e over f1..f6, "
              "%.1e over f1..f10; per mode %s." % (
                  finest["setting"], finest["dofs"], finest["err6"], finest["err10"],
                  ", ".join("%+.1e" % (a / b - 1) for a, b in zip(finest["f"], f_ref))))
    with open(os.path.join(outdir, "calculix_modal.csv"), "w", newline="") as handle:
        w = csv.writer(handle)
        w.writerow(["crack", "a [m]", "code", "setting", "DOFs [-]", "wall [s]", "peak RSS [MiB]",
                    "max rel err f1..f6 [-]", "max rel err f1..f10 [-]", "K and M [s]", "factor [s]", "eigen [s]",
                    "mode labels [-]", "symmetry swaps (modes) [-]"] + [f"f{i} [Hz]" for i in range(1, MODES + 1)])
        w.writerows(csv_rows)
    print()
    print(f"CSV: {os.path.join(outdir, 'calculix_modal.csv')}; plot: {write_plot(outdir, tables)}")


if __name__ == "__main__":
    main()
