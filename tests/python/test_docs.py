"""docs/python.md: its worked example runs, block by block, in one namespace."""
import os
import re
import shutil

from conftest import SOURCE_DIR


def test_worked_example(tmp_path):
    text = open(os.path.join(SOURCE_DIR, "docs", "python.md")).read()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 3
    # The example names data/beam.yaml relative to the source tree.
    shutil.copytree(os.path.join(SOURCE_DIR, "data"), tmp_path / "data")
    previous = os.getcwd()
    os.chdir(tmp_path)
    try:
        namespace = {}
        for block in blocks:
            exec(compile(block, "docs/python.md", "exec"), namespace)
    finally:
        os.chdir(previous)
    assert (tmp_path / "beam-sweep.png").stat().st_size > 0
    assert (tmp_path / "beam-sweep" / "sweep.csv").exists()
