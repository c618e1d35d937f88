#!/usr/bin/env python3
"""Effectivity of crackle modal's frequency estimate (modal.json accuracy, issue 23).

The scene (data/beam.yaml by default) is solved on a coarse grid (--cells, default 20 x 2 x 1) at
orders 2 (accuracy.estimate: on: levels 2, 3, 4), 3 (levels 2, 3) and 4 (levels 2, 3, 4), and
on the scene's own grid at order 4 as the reference: its value extrapolated by its own levels
(value x (1 + delta / Fs)); the two grids are the same body. Prints, per mode and frequency,
the estimate, the true error against the reference and their ratio (the effectivity).

    python3 bench/modal_effectivity.py [--crackle build/apps/crackle] [--scene data/beam.yaml]
        [--cells 20,2,1] [--work /tmp/modal-effectivity] [--reuse]
"""
import argparse
import json
import os
import subprocess
import sys
import time


def solve(crackle, scene, folder, sets, reuse):
    if not (reuse and os.path.exists(os.path.join(folder, "modal.json"))):
        command = [crackle, "modal", scene, "-o", folder, "-q", "--overwrite"]
        for item in sets:
            command += ["--set", item]
        start = time.time()
        subprocess.run(command, check=True)
        print(f"# {' '.join(sets) or 'as written'}: {time.time() - start:.1f} s", file=sys.stderr)
    with open(os.path.join(folder, "modal.json")) as handle:
        return json.load(handle)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--crackle", default="build/apps/crackle")
    parser.add_argument("--scene", default="data/beam.yaml")
    parser.add_argument("--cells", default="20,2,1")
    parser.add_argument("--work", default="/tmp/modal-effectivity")
    parser.add_argument("--reuse", action="store_true", help="keep folders that hold a modal.json")
    args = parser.parse_args()
    cells = f"mesh.box.cells=[{args.cells}]"
    reference = solve(args.crackle, args.scene, os.path.join(args.work, "reference"), ["mesh.box.order=4"], args.reuse)
    runs = {
        "p2 (levels 2,3,4)": ["mesh.box.order=2", cells, "accuracy.estimate=on"],
        "p3 (levels 2,3)": ["mesh.box.order=3", cells],
        "p4 (levels 2,3,4)": ["mesh.box.order=4", cells],
    }
    fields = [("f_uncracked_hz", "f_u"), ("f_open_hz", "f_o"), ("f_bilinear_hz", "f_b")]
    truth = []
    for pair in reference["accuracy"]["pairs"]:
        mesh = {f: pair[f]["components"]["mesh"] for f, _ in fields}
        # The levels' own extrapolation (before the check level widened the estimate, if it did).
        delta = {f: mesh[f]["check"]["levels_delta"] if "check" in mesh[f] else mesh[f]["delta"] for f, _ in fields}
        truth.append({f: pair[f]["value"] * (1.0 + delta[f] / mesh[f]["safety_factor"]) for f, _ in fields})
    print("| run | mode | quantity | value [Hz] | estimate [%] | levels' [%] | check level [%] | verified | true error [%] "
          "| effectivity |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    summary = {}
    for name, sets in runs.items():
        document = solve(args.crackle, args.scene, os.path.join(args.work, name.split()[0]), sets, args.reuse)
        accuracy = document["accuracy"]
        for mode, pair in enumerate(accuracy["pairs"]):
            for field, label in fields:
                estimate = pair[field]
                true_error = abs(truth[mode][field] - estimate["value"]) / abs(estimate["value"])
                effectivity = estimate["error"] / true_error if true_error > 0 else float("inf")
                summary.setdefault(name, []).append((effectivity, estimate["verified"]))
                mesh = estimate["components"]["mesh"]
                levels = abs(mesh["check"]["levels_delta"]) if "check" in mesh else abs(mesh["delta"])
                check = f"{100 * mesh['check']['delta']:+.4f}" if "check" in mesh else "-"
                print(f"| {name} | {mode + 1} | {label} | {estimate['value']:.4f} | {100 * estimate['error']:.4f} | "
                      f"{100 * levels:.4f} | {check} | {str(estimate['verified']).lower()} | {100 * true_error:.4f} | "
                      f"{effectivity:.2f} |")
        print(f"# {name}: estimate {accuracy['estimate_s']:.1f} s of {accuracy['estimate_s'] + accuracy['run_s']:.1f} s",
              file=sys.stderr)
    for name, values in summary.items():
        verified = [e for e, v in values if v]
        every = [e for e, _ in values]
        print(f"\n{name}: effectivity {min(every):.2f}-{max(every):.2f} over {len(every)} frequencies; "
              f"verified {len(verified)}" + (f", {min(verified):.2f}-{max(verified):.2f}" if verified else ""))


if __name__ == "__main__":
    main()
