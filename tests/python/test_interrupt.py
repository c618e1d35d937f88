"""KeyboardInterrupt: a run stops within a second and leaves no file behind."""
import _thread
import glob
import os
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
        scene.set("mesh.box.cells", [20, 2, 2]).set("sweep.method", "stepped_sine").set("sweep.points", 400).set("sweep.tolerance", 1e-12)
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


def test_interrupted_text_scene_leaves_no_scene_file(tmp_path):
    text = open(data("beam.yaml")).read()
    scene = crackle.Scene(text, base=str(tmp_path)).set("sweep.method", "stepped_sine").set("sweep.points", 400)
    scene.set("sweep.tolerance", 1e-12)
    interrupted(lambda s: crackle.sweep(s, quiet=True), scene, after_s=2.0)
    assert sorted(os.listdir(tmp_path)) == ["temporary"] and private_folders() == set()
