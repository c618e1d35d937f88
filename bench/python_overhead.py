"""The Python module against the command line (docs/benchmarks.md, section 14).

    PYTHONPATH=build/python OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
        /usr/bin/python3 bench/python_overhead.py [data/beam.yaml] [--repeats 5]

1. Calling overhead: crackle.sweep(scene) in one process against `crackle sweep` as a new process
   each time, on the same scene (median wall time of --repeats calls after one warm-up each). The
   two do the same work; the module saves the process start and MPI's, pays the result's reading
   of sweep.csv.
2. Memory of a result against its arrays: resident memory gained by holding --keep results of
   crackle.sweep and of crackle.modal, per result, against result.nbytes() (bytes in its arrays).
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import crackle


def resident_bytes():
    with open("/proc/self/statm") as file:
        return int(file.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def timed(call, repeats):
    call()  # warm-up: SLEPc start, page cache
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), max(times)


def held_memory(make, keep):
    make()
    before = resident_bytes()
    results = [make() for _ in range(keep)]
    after = resident_bytes()
    return (after - before) / keep, results[0].nbytes()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scene", nargs="?", default="data/beam.yaml")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--keep", type=int, default=10)
    args = parser.parse_args()

    scene = crackle.Scene(args.scene)
    out = tempfile.mkdtemp(prefix="bench-python-")
    command = [crackle.executable(), "sweep", args.scene, "-o", out, "-q"]
    cli = timed(lambda: subprocess.run(command, check=True, capture_output=True), args.repeats)
    module = timed(lambda: crackle.sweep(scene, quiet=True), args.repeats)
    points = len(crackle.sweep(scene, quiet=True).frequency_hz)
    print(f"sweep of {args.scene} ({points} points), median (min-max) of {args.repeats}:")
    print(f"  crackle sweep (new process)  {cli[0]:.3f} s ({cli[1]:.3f}-{cli[2]:.3f})")
    print(f"  crackle.sweep (in process)   {module[0]:.3f} s ({module[1]:.3f}-{module[2]:.3f})")
    print(f"  module / command line        {module[0] / cli[0]:.3f}")

    for name, make in (("sweep", lambda: crackle.sweep(scene, quiet=True)), ("modal", lambda: crackle.modal(scene))):
        per_result, arrays = held_memory(make, args.keep)
        print(f"{name} result: {per_result / 2**20:.2f} MiB resident per result held, "
              f"{arrays / 2**20:.2f} MiB in its arrays (ratio {per_result / max(arrays, 1):.2f})")
    subprocess.run(["rm", "-rf", out], check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
