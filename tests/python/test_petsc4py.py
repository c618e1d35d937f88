"""petsc4py started PETSc first: crackle uses it and does not finalise it."""
import glob
import os
import subprocess
import sys

import pytest

from conftest import data

# Debian installs petsc4py below PETSc's own folder; the python3-petsc4py package links it into
# dist-packages through an alternative.
CANDIDATES = glob.glob("/usr/lib/petscdir/petsc*/x86_64-linux-gnu-real/lib/python3/dist-packages")

SCRIPT = f"""
import sys
sys.path[:0] = {CANDIDATES!r}
import petsc4py
petsc4py.init(["-crackle_marker", "1"])
from petsc4py import PETSc
import crackle
modes = crackle.modal(crackle.Scene({data("beam.yaml")!r}).set("mesh.box.cells", [20, 2, 2]).set("modal.modes", 2))
assert modes.frequencies_hz["uncracked"].shape == (2,)
assert PETSc.Options().getInt("crackle_marker") == 1  # PETSc's own options database, untouched
crackle._crackle.shutdown()                        # crackle's atexit: ends SLEPc only
assert PETSc.Sys.isInitialized() and not PETSc.Sys.isFinalized()
v = PETSc.Vec().createSeq(3); v.set(2.0); assert v.sum() == 6.0
print("ok")
"""


def test_petsc4py_first():
    probe = subprocess.run([sys.executable, "-c", f"import sys; sys.path[:0] = {CANDIDATES!r}; import petsc4py"],
                           capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.skip("petsc4py is not installed (Debian: python3-petsc4py-real)")
    result = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=os.environ)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip().endswith("ok")


def test_petsc_options_from_a_dict():
    script = f"""
import crackle
crackle.set_petsc_options({{"eps_tol": 1e-12}})
crackle.modal(crackle.Scene({data("beam.yaml")!r}).set("mesh.box.cells", [20, 2, 2]).set("modal.modes", 2))
assert crackle._crackle.slepc_initialized()
print("ok")
"""
    # sys.argv of the interpreter never reaches PETSc: an option there would be an error.
    result = subprocess.run([sys.executable, "-c", script, "-not_a_petsc_option"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "not_a_petsc_option" not in result.stderr
