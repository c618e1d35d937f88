#!/usr/bin/env python3
"""Transient stability map (issue 4): time step factor x dt_critical against the contact penalty,
without and with friction and stiffness-proportional (beta) damping, on a small mesh of
data/beam.yaml. For each case: stable or not (exit status and transient.json status) and the
largest relative energy-balance error.

Usage: bench/stability_map.py CRACKLE OUTDIR [--scene data/beam.yaml]

dt_critical is taken from a short probe run of the same configuration (same penalty, friction and
damping; time_step auto), so the factor measures the solver's own stability estimate: a factor
<= 1 should be stable, > 1 may diverge. The excitation is set in Hz and the damping by alpha/beta,
so no modal solve runs.
"""
import json
import os
import subprocess
import sys
import time

REUSE = "--reuse" in sys.argv

BASE = [
    "--set", "transient.model=full", "--set", "mesh.box.cells=[20,1,2]", "--set", "mesh.box.order=1",
    "--set", "transient.excitation.frequency=100", "--set", "transient.excitation.ramp_periods=0.5",
    "--set", "transient.excitation.amplitude=200",
    "--set", "transient.periods=2", "--set", "transient.progress=false",
    "--set", "spectrum.plots=false", "--set", "spectrum.steady_state.tolerance=0", "--set", "modal.modes=1",
]
MULTIPLIERS = [0.01, 0.1, 1.0, 10.0, 100.0]
FACTORS = [0.5, 0.8, 1.0, 1.05, 1.1, 1.2]
TAGS = {"frictionless, alpha damping": "frictionlessdamping", "friction mu = 0.3, alpha damping": "frictiondamping",
        "frictionless, beta = 1e-6 s": "frictionless=1e-6s",
        "frictionless, explicit contact, alpha damping": "explicit"}
CONFIGS = [
    ("frictionless, alpha damping", ["--set", "crack.contact.friction=0", "--set", "transient.damping={alpha: 60, beta: 0}"]),
    ("friction mu = 0.3, alpha damping", ["--set", "crack.contact.friction=0.3", "--set", "transient.damping={alpha: 60, beta: 0}"]),
    ("frictionless, beta = 1e-6 s", ["--set", "crack.contact.friction=0", "--set", "transient.damping={alpha: 0, beta: 1.0e-6}"]),
    # MODEL.md eq. (27) as written: contact force at U(i), so the penalty springs enter omega_max.
    ("frictionless, explicit contact, alpha damping", ["--set", "crack.contact.friction=0", "--set", "crack.contact.integration=explicit",
                                                       "--set", "transient.damping={alpha: 60, beta: 0}"]),
]


def run(crackle, scene, out, extra):
    cmd = [crackle, "run", scene, "-q", "-o", out] + BASE + extra
    data, path = None, os.path.join(out, "transient.json")
    if REUSE and os.path.exists(path):
        with open(path) as handle:
            data = json.load(handle)
        rc = open(os.path.join(out, "rc.txt")).read().strip() if os.path.exists(os.path.join(out, "rc.txt")) else "?"
        return rc, data, data["wall_s"], []
    start = time.monotonic()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.monotonic() - start
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "rc.txt"), "w") as handle:
        handle.write(str(proc.returncode))
    if os.path.exists(path):
        with open(path) as handle:
            data = json.load(handle)
    return proc.returncode, data, wall, proc.stderr.strip().splitlines()[-1:] if proc.stderr else []


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    crackle, outdir = sys.argv[1], sys.argv[2]
    scene = sys.argv[sys.argv.index("--scene") + 1] if "--scene" in sys.argv else "data/beam.yaml"
    os.makedirs(outdir, exist_ok=True)
    rc, auto, _, err = run(crackle, scene, os.path.join(outdir, "auto"), ["--set", "transient.periods=0.01"])
    if auto is None:  # the spectrum stage refuses so short a run (exit 3); transient.json is there
        sys.exit(f"stability_map: probe run failed ({rc}): {err}")
    penalty_auto = auto["penalty"]  # the implicit default's auto value (1000 E/h); explicit rows use the same scale
    print(f"Mesh [20,1,2], p = 1, {auto['dofs']} DOFs; excitation 200 N at 100 Hz (about f1/2) for 2 periods (0.02 s); "
          f"auto penalty {penalty_auto:.3g} Pa/m. Each cell: largest relative energy-balance error of a stable run "
          f"(transient.json status completed), or UNSTABLE and the step at which the health check stopped it; dt_crit is the solver's estimate for that row.")
    print()
    print("| configuration | penalty x auto | dt_crit [s] | " + " | ".join(f"{f} dt_crit" for f in FACTORS) + " |")
    print("|---|---|---|" + "---|" * len(FACTORS))
    total = 0.0
    anomalies, codes = [], set()
    for name, extra in CONFIGS:
        for m in MULTIPLIERS:
            pen = ["--set", f"crack.contact.penalty={m * penalty_auto:.6g}"]
            tag = f"{TAGS[name]}_{m:g}"
            rc, probe, _, err = run(crackle, scene, os.path.join(outdir, "probe_" + tag),
                                    extra + pen + ["--set", "transient.periods=0.01"])
            if probe is None:
                print(f"| {name} | {m:g} | probe failed: {err} |")
                continue
            dt_crit = probe["dt_critical"]
            cells = []
            for f in FACTORS:
                rc, data, wall, err = run(crackle, scene, os.path.join(outdir, f"{tag}_{f}"),
                                          extra + pen + ["--set", f"transient.time_step={f * dt_crit:.6g}",
                                                         "--set", "transient.force_time_step=true"])
                total += wall
                status = data["status"] if data else "no transient.json"
                codes.add(str(rc))
                if data and status == "completed":
                    cells.append("%.1e" % data["energy_error"])
                    if f > 1.0:
                        anomalies.append(f"{name}, penalty x{m:g}, {f} dt_crit: stable ({data['steps']} steps)")
                else:
                    step = f" @ step {data['steps']}" if data else ""
                    cells.append(f"UNSTABLE{step}" if status in ("unstable", "no transient.json") else status)
                    if f <= 1.0:
                        anomalies.append(f"{name}, penalty x{m:g}, {f} dt_crit: {status}, rc {rc}: {' '.join(err)}")
            print(f"| {name} | {m:g} | {dt_crit:.3g} | " + " | ".join(cells) + " |")
    print()
    print(f"Runs above dt_crit that stayed stable over 0.02 s, or runs at or below it that failed: "
          f"{'; '.join(anomalies) if anomalies else 'none'}. Exit statuses seen: {', '.join(sorted(codes))}. "
          f"Transient time of the map: {total:.0f} s.")


if __name__ == "__main__":
    main()
