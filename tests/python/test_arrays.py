"""Result arrays: the documented shapes and units, the mesh, and two runs in one process."""
import numpy as np
import pytest

import crackle
from conftest import data

# A small beam: seconds per command.
SMALL = [("mesh.box.cells", "[20, 2, 2]"), ("transient.model", "reduced"), ("modal.modes", "4"), ("transient.periods", "3"),
         ("spectrum.steady_state.tolerance", "0"), ("accuracy.estimate", "off"), ("sweep.points", "20"),
         ("sweep.harmonics", "5")]


def small_beam():
    scene = crackle.Scene(data("beam.yaml"))
    for key, value in SMALL:
        scene.set(key, value)
    return scene


def test_mesh_arrays():
    mesh = small_beam().mesh()
    assert mesh.nodes.shape == (mesh.n_nodes, 3) and mesh.nodes.dtype == np.float64
    assert mesh.connectivity.shape == (mesh.n_elements, 27)  # order 2 hexahedra
    assert mesh.connectivity.max() < mesh.n_nodes
    assert np.allclose(mesh.nodes.min(axis=0), 0) and np.allclose(mesh.nodes.max(axis=0), [0.2, 0.02, 0.01])
    pairs = mesh.crack_pairs
    assert mesh.n_pairs > 0 and pairs["normal"].shape == (mesh.n_pairs, 3)
    assert np.allclose(mesh.nodes[pairs["minus"], 0], 0.05) and np.allclose(mesh.nodes[pairs["plus"], 0], 0.05)
    assert np.allclose(pairs["normal"], [1, 0, 0])
    assert np.isclose(pairs["area"].sum(), mesh.crack_area)  # 20 mm x 3 mm
    # Off the crack front a pair joins a node to its duplicate (numbered from n_original_nodes).
    split = pairs["minus"] != pairs["plus"]
    assert split.any() and (np.maximum(pairs["minus"], pairs["plus"])[split] >= mesh.n_original_nodes).all()


def test_modal_arrays():
    modes = crackle.modal(small_beam())
    for variant in ("uncracked", "open"):
        f = modes.frequencies_hz[variant]
        assert f.shape == (4,) and (np.diff(f) > 0).all()
        assert modes.shapes[variant].shape == (4, modes.mesh.n_nodes, 3)
        assert np.allclose(modes.json["variants"][variant]["frequencies_hz"], f, rtol=1e-14)
    # Clamped end: no displacement at x = 0.
    clamped = modes.mesh.nodes[:, 0] == 0.0
    assert np.abs(modes.shapes["uncracked"][:, clamped, :]).max() == 0.0
    assert modes.pairs["f_bilinear_hz"].shape == (4,) and modes.mac.shape == (4, 4)
    # First bending mode of a 0.2 m x 10 mm steel cantilever: ~204 Hz (Euler-Bernoulli).
    assert 190 < modes.frequencies_hz["uncracked"][0] < 220
    assert modes.frequencies_hz["open"][0] < modes.frequencies_hz["uncracked"][0]


def test_run_and_sweep_arrays():
    scene = small_beam()
    run = crackle.run(scene, quiet=True)
    tip = run.probes["tip"]
    n = tip["time"].shape[0]
    assert n > 10 and tip["u"].shape == (n, 3) and tip["a"].shape == (n, 3)
    assert tip["units"] == {"time": "s", "u": "m", "v": "m/s", "a": "m/s^2"}
    assert (np.diff(tip["time"]) > 0).all()
    assert run.json["stages"] and run.spectrum is not None
    harmonics = run.harmonics["tip"]
    orders = harmonics["order"].shape[0]
    assert orders > 3 and harmonics["amplitude"].shape == (orders,) and harmonics["order"][0] == 0
    assert np.allclose(harmonics["frequency_hz"], harmonics["order"] * run.json["excitation_hz"])
    curve = crackle.sweep(scene, quiet=True)
    points = curve.frequency_hz.shape[0]
    assert points >= 20 and (curve.frequency_hz > 0).all()
    assert curve.curves["tip"]["A1"].shape == (points,) and curve.curves["tip"]["units"]["A1"] == "m"
    assert curve.nbytes() > 0


def test_a_bad_solver_is_named_as_python_spells_it():
    """modal(solver=...) takes the words of modal.solver; another is refused before any solve, with
    the message naming the argument `solver` (the command line's `--solver`) and the words."""
    with pytest.raises(crackle.SceneError, match=r"^solver: expected one of auto, slepc, arpack, got 'lapack'"):
        crackle.modal(small_beam(), solver="lapack")


def test_a_run_starts_its_tolerance_where_an_earlier_result_ended():
    """accuracy_start takes an earlier RunResult (its run.json): one whose estimate reached no setting
    is refused before the run starts, naming the file and the key."""
    unestimated = crackle.run(small_beam(), quiet=True)  # accuracy.estimate off: no accuracy.reached
    toleranced = small_beam()
    toleranced.set("accuracy.estimate", "auto")
    toleranced.set("accuracy.tolerance", "0.01")
    with pytest.raises(crackle.SceneError, match=r"run\.json: accuracy\.reached: expected the setting"):
        crackle.run(toleranced, quiet=True, accuracy_start=unestimated)
    with pytest.raises(crackle.SceneError, match=r"sweep\.json: accuracy\.reached"):
        crackle.sweep(toleranced, quiet=True, accuracy_start=crackle.sweep(small_beam(), quiet=True))


def test_the_estimates_load_as_one_table():
    """RunResult.estimates: one row per estimated signature and frequency of spectrum.json's accuracy
    block, with the estimate, its bound and each component; here at order 2, where the mesh part is
    not estimated, so every row says verified False."""
    scene = small_beam()
    scene.set("accuracy.estimate", "on")
    run = crackle.run(scene, quiet=True)
    rows = {row["at"]: row for row in run.estimates}
    assert "probes/tip/A2/A1" in rows and "probes/tip/A1" in rows, sorted(rows)
    block = run.spectrum["accuracy"]["probes"]["tip"]["A2/A1"]
    row = rows["probes/tip/A2/A1"]
    assert row["value"] == block["value"] and row["error"] == block["error"]
    assert row["delta window"] == block["components"]["window"]["delta"]
    for row in rows.values():
        assert row["error"] <= row["sum"] * (1 + 1e-12) and row["verified"] is False
    assert crackle.run(small_beam(), quiet=True).estimates == []  # accuracy.estimate off


def test_two_runs_in_one_process_are_identical():
    scene = small_beam()
    first, second = crackle.sweep(scene, quiet=True), crackle.sweep(scene, quiet=True)
    for name in first.table:
        assert np.array_equal(first.table[name], second.table[name], equal_nan=True), name
    a, b = crackle.modal(scene), crackle.modal(scene)
    assert np.array_equal(a.frequencies_hz["open"], b.frequencies_hz["open"])
    assert np.array_equal(a.shapes["open"], b.shapes["open"])


def test_progress_goes_to_the_callback():
    lines = []
    crackle.sweep(small_beam(), progress=lines.append)
    assert any(line.startswith("sweep:") for line in lines)


def test_set_threads():
    crackle.set_threads(1)
    assert crackle.threads() == 1


def test_solves_release_the_gil():
    import threading
    import time

    ticks, done = [], threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)
            time.sleep(0.001)

    thread = threading.Thread(target=count)
    thread.start()
    start = time.monotonic()
    crackle.modal(small_beam())
    elapsed = time.monotonic() - start
    done.set()
    thread.join()
    # Python ran the other thread all along (about one tick a millisecond, far fewer if it waited).
    assert len(ticks) > 0.1 * elapsed / 0.001
