"""KeyboardInterrupt: a run stops within a second and leaves no file behind."""
import _thread
import glob
import os
import signal
import tempfile
import threading
import time

import pytest

import crackle
from conftest import data


def private_folders():
    return set(glob.glob(os.path.join(tempfile.gettempdir(), "crackle-result-*")))


@pytest.fixture(autouse=True)
def own_temporary_folder(tmp_path, monkeypatch):
    """The private folders of this test's commands in a folder of its own (other tests run beside)."""
    folder = tmp_path / "temporary"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))


def interrupted(command, scene, after_s):
    """Runs command(scene) and interrupts it from a timer thread after `after_s`; returns the
    seconds from the interruption to the KeyboardInterrupt."""
    fired = []
    # Python's handler even where SIGINT is ignored (a test started in the background by a shell):
    # interrupt_main() acts only through it.
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def interrupt():
        fired.append(time.monotonic())
        _thread.interrupt_main()

    timer = threading.Timer(after_s, interrupt)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            command(scene)
            time.sleep(5)  # finished before the timer: fail below
    finally:
        timer.cancel()
    assert fired, "the command finished before the interruption"
    return time.monotonic() - fired[0]


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_interrupt_stops_within_a_second_and_leaves_no_file(command):
    scene = crackle.Scene(data("beam.yaml")).set("accuracy.estimate", "off")
    if command == "run":  # the full explicit transient: minutes when not interrupted
        scene.set("transient.model", "full").set("spectrum.steady_state.tolerance", 0).set("modal.solver", "arpack")
        run = lambda s: crackle.run(s, quiet=True)
    else:  # a stepped sine of many points (after a quick modal stage and reduction)
        scene.set("mesh.box.cells", [20, 2, 2]).set("transient.model", "reduced").set("sweep.method", "stepped_sine").set("sweep.points", 400).set("sweep.tolerance", 1e-12)
        run = lambda s: crackle.sweep(s, quiet=True)
    assert private_folders() == set()
    scene_folder = set(os.listdir(os.path.dirname(scene.path)))
    latency = interrupted(run, scene, after_s=2.0)
    assert latency < 1.0, f"stopped {latency:.2f} s after the interruption"
    assert private_folders() == set(), "a private folder was left"
    assert set(os.listdir(os.path.dirname(scene.path))) == scene_folder
    # The next command in the same process runs normally.
    small = crackle.Scene(data("beam.yaml")).set("mesh.box.cells", [20, 2, 2]).set("modal.modes", 2)
    assert crackle.modal(small).frequencies_hz["uncracked"].shape == (2,)


def test_an_interrupted_factorisation_returns_within_a_second():
    """The modal stage of the default route's mesh (order 4, 93k DOFs): assembly, K - sigma M, the
    ordering and two sparse factorisations of seconds each, which have no place to poll. Interrupted at
    several times, each returns within a second; a factorisation in progress is left to finish on its
    worker (crackle._crackle.background_work()), and the process goes on."""
    scene = crackle.Scene(data("beam.yaml")).set("mesh.box.order", 4).set("mesh.box.cells", [20, 2, 1])
    scene.set("modal.solver", "arpack")
    left_running = []
    for after_s in (1.0, 2.0, 3.0, 4.0, 5.0):
        latency = interrupted(crackle.modal, scene, after_s=after_s)
        assert latency < 1.0, f"interrupted at {after_s} s: stopped {latency:.2f} s after the interruption"
        left_running.append(crackle._crackle.background_work())
        print(f"interrupted at {after_s} s: {latency:.3f} s, {left_running[-1]} left running")
        assert private_folders() == set(), "a private folder was left"
    assert max(left_running) > 0, f"no interruption landed in a factorisation ({left_running})"
    small = crackle.Scene(data("beam.yaml")).set("mesh.box.cells", [20, 2, 2]).set("modal.modes", 2)
    assert crackle.modal(small).frequencies_hz["uncracked"].shape == (2,)


def test_interrupted_text_scene_leaves_no_scene_file(tmp_path):
    text = open(data("beam.yaml")).read()
    scene = crackle.Scene(text, base=str(tmp_path)).set("sweep.method", "stepped_sine").set("sweep.points", 400)
    scene.set("sweep.tolerance", 1e-12)
    interrupted(lambda s: crackle.sweep(s, quiet=True), scene, after_s=2.0)
    assert sorted(os.listdir(tmp_path)) == ["temporary"] and private_folders() == set()
