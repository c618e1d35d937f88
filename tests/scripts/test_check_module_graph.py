"""scripts/check_module_graph.py: the include graph of src/ against docs/architecture.md's module table."""
import importlib.util
import os
import pathlib

SOURCE = pathlib.Path(os.environ.get("CRACKLE_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
spec = importlib.util.spec_from_file_location("check_module_graph", SOURCE / "scripts" / "check_module_graph.py")
graph = importlib.util.module_from_spec(spec)
spec.loader.exec_module(graph)

TABLE = """| target | folder | what it owns | depends on |
|---|---|---|---|
| `crackle_core` | `src/core` | types | Eigen |
| `crackle_mesh` | `src/mesh` | meshes | core |
| `crackle_fem` | `src/fem` | elements | mesh, OpenMP |
| `crackle_spectral` | `src/spectral` | spectra | core, FFTW |
"""


def tree(tmp_path, table, files):
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "architecture.md").write_text("# Architecture\n\n" + table)
    for name, text in files.items():
        path = tmp_path / "src" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path


def test_the_repository_keeps_the_documented_direction():
    assert graph.violations(SOURCE) == []


def test_an_include_against_the_direction_is_named_with_its_file_and_line(tmp_path):
    root = tree(tmp_path, TABLE, {
        "core/types.hpp": "#pragma once\n#include <vector>\n",
        "mesh/mesh.hpp": '#pragma once\n#include "core/types.hpp"\n',
        "fem/system.cpp": '#include "fem/system.hpp"\n#include "mesh/mesh.hpp"\n#include "core/types.hpp"\n',
        "spectral/window.cpp": '#include <cmath>\n\n#include "fem/system.hpp"\n',
    })
    found = graph.violations(root)
    assert len(found) == 1, found  # fem -> mesh -> core is allowed, also the transitive core
    assert found[0].startswith("src/spectral/window.cpp:3: includes fem/system.hpp")
    assert "spectral depends on core" in found[0]


def test_a_cycle_in_the_table_and_an_undocumented_module_are_reported(tmp_path):
    cyclic = TABLE.replace("| meshes | core |", "| meshes | core, fem |")
    root = tree(tmp_path, cyclic, {"mesh/mesh.hpp": "#pragma once\n"})
    found = graph.violations(root)
    assert len(found) == 1 and "cycle" in found[0] and "mesh" in found[0] and "fem" in found[0], found
    (tmp_path / "docs" / "architecture.md").write_text(TABLE)
    (tmp_path / "src" / "sweep").mkdir()
    (tmp_path / "src" / "sweep" / "hb.cpp").write_text('#include "core/types.hpp"\n')
    found = graph.violations(root)
    assert found == ["src/sweep/hb.cpp: module 'sweep' is not in the table of docs/architecture.md"]
