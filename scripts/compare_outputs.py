#!/usr/bin/env python3
"""Compares two output folders of scripts/same_outputs.sh: every JSON and CSV file of one must be in
the other with the same keys, columns and strings, and every number equal to a relative tolerance
(default 1e-12 of the largest magnitude of its CSV column, or of the number itself in JSON).
Timings, paths and thread counts are skipped. Exit 0 when they agree, 1 with the differences listed.
Usage: scripts/compare_outputs.py DIR_A DIR_B [--tolerance 1e-12]"""
import csv, json, math, os, sys

SKIP = {"wall_s", "setup_s", "seconds", "ns_per_dof_step", "contact_time_fraction", "assembly_s",
        "solve_s", "total_s", "output", "scene", "threads", "started", "finished", "elapsed_s", "pid",
        "command", "cache", "cached", "time_s", "rss_mib", "peak_rss_mib", "solve_time_s"}


def close(a, b, scale, tolerance):
    return a == b or abs(a - b) <= tolerance * max(scale, abs(a), abs(b), 1e-300)


def compare_json(a, b, path, tolerance, problems):
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key in SKIP or key.endswith("_s"):
                continue
            if key not in a or key not in b:
                problems.append(f"{path}.{key}: only in {'B' if key not in a else 'A'}")
                continue
            compare_json(a[key], b[key], f"{path}.{key}", tolerance, problems)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            problems.append(f"{path}: {len(a)} against {len(b)} entries")
            return
        scale = max((abs(x) for x in a if isinstance(x, (int, float)) and not isinstance(x, bool)), default=0.0)
        for i, (x, y) in enumerate(zip(a, b)):
            if isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
                if not close(x, y, scale, tolerance):
                    problems.append(f"{path}[{i}]: {x!r} against {y!r}")
            else:
                compare_json(x, y, f"{path}[{i}]", tolerance, problems)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if not close(a, b, 0.0, tolerance):
            problems.append(f"{path}: {a!r} against {b!r}")
    elif isinstance(a, str) and isinstance(b, str) and ("/" in a or "/" in b):
        return  # paths differ between folders
    elif a != b:
        problems.append(f"{path}: {a!r} against {b!r}")


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def compare_csv(file_a, file_b, name, tolerance, problems):
    rows_a = list(csv.reader(open(file_a)))
    rows_b = list(csv.reader(open(file_b)))
    if not rows_a or not rows_b or rows_a[0] != rows_b[0] or len(rows_a) != len(rows_b):
        problems.append(f"{name}: header or row count differs ({len(rows_a)} against {len(rows_b)} rows)")
        return
    header = rows_a[0]
    skip = {i for i, h in enumerate(header) if h.split(" [")[0] in SKIP or h.endswith("_s") or "[s wall]" in h}
    scales = [0.0] * len(header)
    for row in rows_a[1:]:
        for i, cell in enumerate(row):
            value = number(cell)
            if value is not None and math.isfinite(value):
                scales[i] = max(scales[i], abs(value))
    for r, (row_a, row_b) in enumerate(zip(rows_a[1:], rows_b[1:]), start=2):
        for i, (x, y) in enumerate(zip(row_a, row_b)):
            if i in skip:
                continue
            vx, vy = number(x), number(y)
            if vx is None or vy is None:
                if x != y and "/" not in x:
                    problems.append(f"{name}:{r}: column '{header[i]}': {x!r} against {y!r}")
            elif not (math.isnan(vx) and math.isnan(vy)) and not close(vx, vy, scales[i], tolerance):
                problems.append(f"{name}:{r}: column '{header[i]}': {x} against {y}")


def main():
    args = sys.argv[1:]
    tolerance = 1e-12
    if "--tolerance" in args:
        k = args.index("--tolerance")
        tolerance = float(args[k + 1])
        del args[k:k + 2]
    a_dir, b_dir = args
    problems, compared = [], 0
    for root, _, files in os.walk(a_dir):
        for file in sorted(files):
            if not file.endswith((".json", ".csv")):
                continue
            rel = os.path.relpath(os.path.join(root, file), a_dir)
            other = os.path.join(b_dir, rel)
            if not os.path.exists(other):
                problems.append(f"{rel}: missing in {b_dir}")
                continue
            compared += 1
            if file.endswith(".json"):
                compare_json(json.load(open(os.path.join(root, file))), json.load(open(other)), rel, tolerance, problems)
            else:
                compare_csv(os.path.join(root, file), other, rel, tolerance, problems)
    for line in problems[:200]:
        print(line)
    print(f"compare_outputs: {compared} files compared, {len(problems)} differences (tolerance {tolerance:g})")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
