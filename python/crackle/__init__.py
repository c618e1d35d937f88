"""crackle from Python: nonlinear vibration of elastic bodies with a breathing crack.

    import crackle
    scene = crackle.Scene("data/beam.yaml").set("mesh.box.order", 2)
    modes = crackle.modal(scene)          # modes.frequencies_hz["uncracked"], modes.shapes["open"]
    curve = crackle.sweep(scene)          # curve.frequency_hz, curve.curves["tip"]["A1"]
    curve.write("out")                    # the files `crackle sweep data/beam.yaml -o out` writes

Every command runs the library functions of the command line (``crackle modal|run|sweep|study|
identify|plan``) with the GIL released; progress lines go to ``progress`` (a callable taking one line)
or, by default, to the logger ``crackle`` at INFO level. Ctrl-C (KeyboardInterrupt) stops a run
within a fraction of a second and leaves no file behind. See docs/python.md.
"""
import atexit
import logging
import os
import shutil

from . import _crackle
from ._paths import CRACKLE_EXECUTABLE
from .errors import CrackleError, IoError, SceneError, SolverError
from .results import (IdentifyResult, Mesh, ModalResult, PlanResult, Result, RunResult, StudyResult, SweepResult,
                      private_folder, private_scene)
from .scene import Scene

__all__ = [
    "Scene", "Mesh", "Result", "ModalResult", "RunResult", "SweepResult", "StudyResult", "IdentifyResult", "PlanResult",
    "CrackleError", "SceneError", "SolverError", "IoError",
    "modal", "run", "sweep", "study", "identify", "plan", "parameters", "set_threads", "threads",
    "set_petsc_options", "executable",
]

logger = logging.getLogger("crackle")

# crackle ends the SLEPc session it started (never one petsc4py or slepc4py started).
atexit.register(_crackle.shutdown)


def executable():
    """The ``crackle`` command that study and identify run per case (CRACKLE_EXECUTABLE overrides)."""
    return os.environ.get("CRACKLE_EXECUTABLE", CRACKLE_EXECUTABLE)


def parameters():
    """The parameter table (see Scene.keys)."""
    return _crackle.parameters()


def set_threads(threads):
    """OpenMP threads of crackle's element loops and Eigen (as OMP_NUM_THREADS)."""
    if int(threads) < 1:
        raise ValueError(f"set_threads: expected a positive integer, got {threads}")
    _crackle.set_threads(int(threads))


def threads():
    return _crackle.threads()


def set_petsc_options(options):
    """PETSc/SLEPc options from a dict, e.g. ``{"eps_tol": 1e-10, "eps_view": None}`` (None or ""
    for a flag). Before crackle starts SLEPc they join its start-up options; after (or when
    petsc4py started PETSc) they go into PETSc's options database. ``sys.argv`` is never read."""
    pairs = []
    for name, value in dict(options).items():
        text = "" if value is None or value is True else str(value)
        pairs.append((str(name), text))
    _crackle.set_petsc_options(pairs)


def _scene(scene):
    return scene if isinstance(scene, Scene) else Scene(scene)


def _sink(progress, lines):
    """A line sink: keeps every line (the result's log) and passes it on."""
    def sink(line):
        lines.append(line)
        if progress is not None:
            progress(line)
        else:
            logger.info("%s", line)
    return sink


def _command(body, progress, make_result):
    """Runs body(output_folder, sink) into a new private folder; the result keeps the folder, a
    failure (an error, a KeyboardInterrupt) removes it."""
    folder = private_folder()
    lines = []
    try:
        value = body(os.path.join(folder, "out"), _sink(progress, lines))
        output = os.path.join(folder, "out")
        if not os.path.isdir(output):
            os.makedirs(output)
        # The result owns only the command's folder.
        for name in os.listdir(folder):
            if name != "out":
                shutil.rmtree(os.path.join(folder, name), ignore_errors=True)
        return make_result(output, lines, value)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    finally:
        if os.path.isdir(folder) and not os.listdir(folder):
            os.rmdir(folder)


def modal(scene, modes=0, solver="", modal_cache="", progress=None):
    """``crackle modal``: eigenmodes of the uncracked and open-crack body (crackle.ModalResult)."""
    scene = _scene(scene)
    with private_scene(scene) as (path, overrides):
        return _command(
            lambda out, sink: _crackle.modal(path, overrides, out, int(modes), solver, os.fspath(modal_cache), sink),
            progress, lambda out, log, arrays: ModalResult(out, log, arrays))


def _start_file(accuracy_start):
    """``--accuracy-start``'s file: a path, or an earlier RunResult's run.json / SweepResult's sweep.json."""
    if isinstance(accuracy_start, RunResult):
        return os.path.join(accuracy_start.folder, "run.json")
    if isinstance(accuracy_start, SweepResult):
        return os.path.join(accuracy_start.folder, "sweep.json")
    return os.fspath(accuracy_start)


def _stage_command(call, make_result, scene, modal_cache, progress, quiet, accuracy_start):
    scene = _scene(scene)
    start = _start_file(accuracy_start)
    with private_scene(scene) as (path, overrides):
        return _command(lambda out, sink: call(path, overrides, out, os.fspath(modal_cache), not quiet, sink, start),
                        progress, lambda out, log, _: make_result(out, log))


def run(scene, modal_cache="", progress=None, quiet=False, accuracy_start=""):
    """``crackle run``: modal (if needed) -> transient -> spectrum (crackle.RunResult).
    ``accuracy_start``: an earlier RunResult or SweepResult of the same mesh (or its run.json /
    sweep.json): the accuracy tolerance's refinement starts at the setting it reached."""
    return _stage_command(_crackle.run, RunResult, scene, modal_cache, progress, quiet, accuracy_start)


def sweep(scene, modal_cache="", progress=None, quiet=False, accuracy_start=""):
    """``crackle sweep``: response curves of the reduced model (crackle.SweepResult).
    ``accuracy_start``: as for run()."""
    return _stage_command(_crackle.sweep, SweepResult, scene, modal_cache, progress, quiet, accuracy_start)


def study(scene, jobs=0, modal_cache=True, retry_failed=False, case_timeout=0.0, progress=None):
    """``crackle study``: every case of the study: section (crackle.StudyResult). The cases run as
    ``crackle`` processes (crackle.executable()), as on the command line. Raises KeyboardInterrupt
    when interrupted; a study with failed cases returns normally with ``exit_code`` 3."""
    scene = _scene(scene)
    with private_scene(scene, with_overrides=True) as (path, _):
        def body(out, sink):
            code = _crackle.study(path, out, executable(), int(jobs), bool(modal_cache), bool(retry_failed),
                                  float(case_timeout), sink)
            if code == _crackle.exit_code("interrupted"):
                raise KeyboardInterrupt("crackle study: interrupted")
            return code
        return _command(body, progress, lambda out, log, code: StudyResult(out, log, code))


def plan(scene, jobs=0, progress=None):
    """``crackle plan``: sensors, drive points and frequencies ranked for the prior (crackle.PlanResult)."""
    scene = _scene(scene)
    with private_scene(scene, with_overrides=True) as (path, _):
        return _command(lambda out, sink: _crackle.plan(path, out, executable(), int(jobs), sink),
                        progress, lambda out, log, document: PlanResult(out, log, document))


def identify(scene, jobs=0, map_cache="", progress=None):
    """``crackle identify``: the crack's unknowns from the measured signatures (crackle.IdentifyResult)."""
    scene = _scene(scene)
    with private_scene(scene, with_overrides=True) as (path, _):
        return _command(
            lambda out, sink: _crackle.identify(path, out, executable(), int(jobs), os.fspath(map_cache), sink),
            progress, lambda out, log, document: IdentifyResult(out, log, document))
