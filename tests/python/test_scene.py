"""crackle.Scene: sources, --set overrides, the parameter table, and the errors with exit codes."""
import pytest

import crackle
from conftest import crackle_cli, data

BEAM = data("beam.yaml")


def test_scene_from_file_text_and_dict_agree():
    from_file = crackle.Scene(BEAM)
    from_text = crackle.Scene(open(BEAM).read(), name="beam")
    assert from_file.path == BEAM and from_text.path is None
    assert from_file.has("sweep") and from_text.has("transient") and from_file.has("crack")
    document = {"mesh": {"box": {"size": [0.2, 0.02, 0.01], "cells": [10, 1, 2], "order": 1}},
                "material": {"E": 210e9, "nu": 0.3, "rho": 7850.0},
                "boundary": [{"face": "x-", "fix": ["x", "y", "z"]}]}
    scene = crackle.Scene(document)
    assert not scene.has("crack") and not scene.has("transient")
    assert scene.mesh().n_nodes == 11 * 2 * 3


def test_set_validates_like_the_command_line():
    scene = crackle.Scene(BEAM).set("mesh.box.order", 3).set("mesh.box.cells", [20, 2, 2])
    assert scene.overrides == [("mesh.box.order", "3"), ("mesh.box.cells", "[20, 2, 2]")]
    with pytest.raises(crackle.SceneError) as caught:
        scene.set("mesh.box.order", 7)
    error = caught.value
    assert isinstance(error, ValueError) and error.exit_code == 2
    assert error.key == "mesh.box.order" and error.file == BEAM
    assert scene.overrides[-1] == ("mesh.box.cells", "[20, 2, 2]")  # unchanged by the failed set
    # The same message as `crackle check --set`.
    cli = crackle_cli(["check", BEAM, "--no-assembly", "--set", "mesh.box.order=7"], check=False)
    assert cli.returncode == error.exit_code
    assert cli.stderr.strip() == f"crackle: error: {error}"


def test_unknown_key_names_the_key_path_and_line():
    text = open(BEAM).read().replace("    order: 2", "    ordr: 2")
    with pytest.raises(crackle.SceneError) as caught:
        crackle.Scene(text, name="beam-typo.yaml")
    error = caught.value
    assert error.file == "beam-typo.yaml" and error.line == 6  # the first line is a comment
    assert error.key == "mesh.box.ordr"
    with pytest.raises(crackle.SceneError) as caught:
        crackle.Scene(BEAM).set("mesh.box.ordr", 2)
    assert caught.value.key == "mesh.box.ordr" and caught.value.line is None


def test_missing_file_raises_io_error():
    with pytest.raises(crackle.IoError) as caught:
        crackle.Scene("/nonexistent/scene.yaml")
    assert isinstance(caught.value, OSError)
    cli = crackle_cli(["check", "/nonexistent/scene.yaml"], check=False)
    assert caught.value.exit_code == cli.returncode == 2
    assert crackle.SolverError.exit_code == 3 and crackle.IoError.exit_code == 4


def test_keys_is_the_parameter_table():
    rows = {row["key"]: row for row in crackle.Scene.keys()}
    order = rows["mesh.box.order"]
    assert order["kind"] == "integer" and order["required"] and order["default"] == ""
    assert rows["material.E"]["unit"] == "Pa"
    assert "boundary[].face" in rows and "sweep.harmonics" in rows
    assert "study.vary" in rows and "identify.unknowns" in rows
    markdown = open(data("../docs/scene-format.md")).read()
    for key in ("mesh.box.order", "crack.contact.penalty", "transient.excitation.amplitude"):
        assert f"`{key}`" in markdown
