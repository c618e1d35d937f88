"""How soon Ctrl-C stops a command of the Python module (docs/benchmarks.md, section 14).

    PYTHONPATH=build/python /usr/bin/python3 bench/interrupt_latency.py [data/beam.yaml] [--step 2]

Runs `crackle.run(scene)` once to time it, then again, interrupted from a timer thread at every
`--step` seconds of its length (_thread.interrupt_main, as Ctrl-C), and prints the seconds from each
interruption to the KeyboardInterrupt, the factorisations left running on their workers
(crackle._crackle.background_work()), and whether a private folder was left. Between two runs the
script waits for the workers of the last one, so that each run starts on an idle machine.
"""
import _thread
import argparse
import glob
import os
import signal
import tempfile
import threading
import time

import crackle


def interrupted_at(scene, after_s):
    fired = []

    def interrupt():
        fired.append(time.monotonic())
        _thread.interrupt_main()

    timer = threading.Timer(after_s, interrupt)
    timer.start()
    try:
        crackle.run(scene, quiet=True)
        return None, 0  # finished first (or the interruption was not seen)
    except KeyboardInterrupt:
        return time.monotonic() - fired[0], crackle._crackle.background_work()
    finally:
        timer.cancel()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="data/beam.yaml")
    parser.add_argument("--step", type=float, default=2.0, help="seconds between interruption times")
    arguments = parser.parse_args()
    # Python's handler even where SIGINT is ignored (a job started in the background by a shell):
    # interrupt_main() acts only through it.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    scene = crackle.Scene(arguments.scene)
    start = time.monotonic()
    crackle.run(scene, quiet=True)
    length = time.monotonic() - start
    print(f"crackle.run({arguments.scene}): {length:.1f} s uninterrupted")
    print("interrupted at [s] | stopped after [s] | factorisations left running | private folder left")
    worst = 0.0
    before = set(glob.glob(os.path.join(tempfile.gettempdir(), "crackle-result-*")))
    after_s = arguments.step / 2
    while after_s < length:
        latency, running = interrupted_at(scene, after_s)
        left = set(glob.glob(os.path.join(tempfile.gettempdir(), "crackle-result-*"))) - before
        if latency is None:
            print(f"{after_s:.1f} | not interrupted: finished | | ")
        else:
            worst = max(worst, latency)
            print(f"{after_s:.1f} | {latency:.3f} | {running} | {'yes' if left else 'no'}")
        while crackle._crackle.background_work():
            time.sleep(0.1)
        after_s += arguments.step
    print(f"worst: {worst:.3f} s")


if __name__ == "__main__":
    main()
