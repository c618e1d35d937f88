"""For every scene of data/: result.write(d) gives the files `crackle` writes, to 1e-12.

Each case is shortened with the same overrides on both sides (--set for the command line,
Scene.set here), as the example tests of tests/apps shorten them; study, identify and plan, which
take no --set, read one shortened scene file on both sides."""
import glob
import json
import os
import shutil

import numpy as np

import pytest

import crackle
from conftest import DATA, compare_folders, crackle_cli, data, set_arguments

SHORT_RUN = [("transient.periods", "2"), ("spectrum.steady_state.tolerance", "0"), ("accuracy.estimate", "off")]
# The beam's reduced model on a coarser mesh (the default route would refine it for the accuracy).
SMALL_BEAM = [("mesh.box.cells", "[20, 2, 2]"), ("modal.modes", "4"), ("transient.model", "reduced")]

CASES = [
    ("beam.yaml", "modal", SMALL_BEAM),
    ("beam.yaml", "run", SMALL_BEAM + SHORT_RUN),
    ("beam.yaml", "sweep", SMALL_BEAM + [("sweep.points", "20"), ("sweep.harmonics", "6")]),
    ("composite-plate.yaml", "run", [("mesh.box.grading.mode", "none"), ("mesh.box.cells", "[6, 4, 4]"),
                                     ("transient.model", "reduced"), ("spectrum.plots", "false")] + SHORT_RUN),
    ("gmsh-cracked-box.yaml", "run", [("transient.model", "reduced")] + SHORT_RUN),
    ("pluck.yaml", "run", [("transient.duration", "0.05")]),
    # The scene's own mesh (the default route would refine it to order 4: a minute on each side).
    ("plan-beam.yaml", "run", [("transient.model", "reduced")] + SHORT_RUN),
    # A plan of one drive and frequency, 2 samples per key, 5 sensors on a p = 1 mesh: 30 forward runs.
    ("plan-beam.yaml", "plan", [("cells: [20, 2, 2]", "cells: [10, 1, 2]"), ("order: 2", "order: 1"),
                                ("samples: 3", "samples: 2"), ("spacing: 0.01}", "spacing: 0.05}"),
                                ("[[0.2, 0.01, 0.01], [0.1, 0.01, 0.01]]", "[[0.2, 0.01, 0.01]]"),
                                (", {mode: 1, ratio: 0.333}, {mode: 1, ratio: 2.0}, {mode: 3, ratio: 0.5}", "")]),
    ("subharmonic.yaml", "run", SHORT_RUN),
    ("subharmonic.yaml", "sweep", [("sweep.points", "20"), ("sweep.harmonics", "8")]),
    ("depth-study.yaml", "study", [("steps: 5", "steps: 2"), ("periods: 60", "periods: 2"),
                                   ("cells: [40, 4, 2]", "cells: [20, 2, 2]"),
                                   ("transient:\n", "transient:\n  model: reduced\n"),
                                   ("spectrum:\n", "accuracy: {estimate: off}\nspectrum:\n")]),
    # Two unknowns at 3 map points each on a p = 1 mesh.
    ("identify-beam.yaml", "identify",
     [("points: 7", "points: 3"), ("cells: [20, 2, 2]", "cells: [10, 1, 2]"), ("order: 2", "order: 1")]),
]


def test_every_example_has_a_case():
    covered = {case[0] for case in CASES}
    assert covered == {os.path.basename(path) for path in glob.glob(os.path.join(DATA, "*.yaml"))}


def shortened_copy(name, replacements, folder):
    """The scene with text replacements, next to copies of the files it refers to."""
    text = open(data(name)).read()
    for old, new in replacements:
        assert old in text, (name, old)
        text = text.replace(old, new)
    for other in glob.glob(os.path.join(DATA, "*.csv")):
        shutil.copy(other, folder)
    path = os.path.join(folder, name)
    with open(path, "w") as file:
        file.write(text)
    return path


def case_id(case):
    name, command, _ = case
    return f"{command}-{name}"


@pytest.mark.parametrize("name,command,overrides", CASES, ids=[case_id(case) for case in CASES])
def test_write_gives_the_command_line_files(name, command, overrides, tmp_path):
    cli_out, python_out = str(tmp_path / "cli"), str(tmp_path / "python")
    if command in ("study", "identify", "plan"):
        path = shortened_copy(name, overrides, str(tmp_path))
        crackle_cli([command, path, "-o", cli_out, "-j", "2"])
        scene = crackle.Scene(path)
        result = getattr(crackle, command)(scene, jobs=2)
    else:
        path = data(name)
        quiet = ["-q"] if command in ("run", "sweep") else []
        crackle_cli([command, path, "-o", cli_out, *quiet, *set_arguments(overrides)])
        scene = crackle.Scene(path)
        for key, value in overrides:
            scene.set(key, value)
        result = getattr(crackle, command)(scene) if command == "modal" else getattr(crackle, command)(scene, quiet=True)
    result.write(python_out)
    files = compare_folders(cli_out, python_out)
    assert result.main_document in files
    # result.json is the document, naming the private folder where the file names the target.
    with open(os.path.join(python_out, result.main_document)) as file:
        written = json.load(file)
    assert json.loads(json.dumps(result.json).replace(result.folder, python_out)) == written
    if command == "identify":
        # the NumPy view of identify.json's profiles: with two unknowns, the map itself
        (keys, (x, y, chi2)), = result.profiles.items()
        assert keys == ("crack.plane.at", "crack.region.z[0]")
        assert chi2.shape == (len(x), len(y)) == (3, 3)
        assert list(x) == written["profiles"][0]["axes"][0]
        assert chi2[1, 2] == written["profiles"][0]["chi2"][1][2]
    if command == "plan":
        # the NumPy view of plan.json: one row per ranked candidate, sensors by their index
        ranked = written["candidates"]
        assert list(result.candidates["rank"]) == [c["rank"] for c in ranked]
        assert result.sensors.shape == (len({c["sensor"]["name"] for c in ranked}), 3)
        for row, candidate in enumerate(ranked):
            assert list(result.sensors[result.candidates["sensor"][row]]) == candidate["sensor"]["point"]
            assert result.candidates["responds"][row] == candidate["responds"]
            for figure in ("mean", "worst"):
                for key, width in candidate["widths_95"][figure].items():
                    got, expected = result.candidates["widths_95_" + figure][key][row], np.nan if width is None else width
                    assert got == expected or (np.isnan(got) and np.isnan(expected))
