"""Result objects of crackle's commands: NumPy arrays, the JSON documents as dicts, and write(dir).

Each command runs into a private folder; a result keeps that folder (removed with the result) so
that ``write`` can give exactly the files the command line writes. Arrays the pipeline hands back
in memory (modal results, meshes) come straight from C++; the tables the pipeline only writes
(probe histories, sweep curves, the study table) are read back from the private folder once.
"""
import contextlib
import csv
import io
import json
import os
import re
import shutil
import tempfile
import weakref

import numpy as np

from . import _crackle


def private_folder():
    """A new private folder (removed by the result that keeps it, or on failure)."""
    return tempfile.mkdtemp(prefix="crackle-result-")


@contextlib.contextmanager
def private_scene(scene, with_overrides=False):
    """Yields (scene path, overrides) for a library call. A file scene is used where it lies; a
    text or dict scene is written to a hidden file in its base folder (so that its relative file
    references resolve there), removed afterwards. ``with_overrides``: the commands that take no
    ``--set`` (study, identify) get a file with the overrides applied, next to the scene."""
    overrides = scene.overrides
    if scene.path is not None and not (with_overrides and overrides):
        yield scene.path, overrides
        return
    text = scene.text
    folder = os.path.dirname(os.path.abspath(scene.path)) if scene.path else scene._base
    if with_overrides and overrides:
        text = _crackle.effective_text(text, scene.name, overrides)
        overrides = []
    handle, path = tempfile.mkstemp(prefix=".crackle-scene-", suffix=".yaml", dir=folder)
    try:
        with os.fdopen(handle, "w") as file:
            file.write(text)
        yield path, overrides
    finally:
        os.unlink(path)


def read_table(path):
    """A CSV file of crackle as {header: column}; numeric columns as float arrays, others as str."""
    with open(path, newline="") as file:
        rows = list(csv.reader(file))
    if not rows:
        return {}
    headers, body = rows[0], rows[1:]
    table = {}
    for c, header in enumerate(headers):
        column = [row[c] if c < len(row) else "" for row in body]
        try:
            table[header] = np.array([float(value) if value != "" else np.nan for value in column])
        except ValueError:
            table[header] = np.array(column, dtype=str)
    return table


_UNIT = re.compile(r"^(?P<name>.*?) \[(?P<unit>[^\]]*)\]$")


def split_header(header):
    """('tip u_z', 'm') from 'tip u_z [m]'; (header, '') without a unit."""
    match = _UNIT.match(header)
    return (match.group("name"), match.group("unit")) if match else (header, "")


class Mesh:
    """The mesh of a scene: ``nodes`` (n_nodes, 3) [m], ``connectivity`` (n_elements,
    nodes_per_element) node indices (GLL/VTK-free lexicographic order of crackle's elements),
    ``element_region`` (n_elements,) material index, and the crack pairs ``crack_pairs`` as a dict
    of ``minus``, ``plus`` (n_pairs,) node indices, ``normal`` (n_pairs, 3) and ``area`` (n_pairs,)
    [m^2]. Nodes from ``n_original_nodes`` on are the duplicated crack nodes."""

    def __init__(self, arrays):
        self.nodes = arrays["nodes"]
        self.connectivity = arrays["connectivity"]
        self.element_region = arrays["element_region"]
        self.crack_pairs = dict(arrays["crack_pairs"])
        self.n_original_nodes = arrays["n_original_nodes"]
        self.order = arrays["order"]
        self.shape = arrays["shape"]
        self.crack_area = arrays["crack_area"]

    @property
    def n_nodes(self):
        return self.nodes.shape[0]

    @property
    def n_elements(self):
        return self.connectivity.shape[0]

    @property
    def n_pairs(self):
        return self.crack_pairs["minus"].shape[0]

    def nbytes(self):
        return sum(a.nbytes for a in [self.nodes, self.connectivity, self.element_region, *self.crack_pairs.values()])

    def __repr__(self):
        return (f"crackle.Mesh({self.n_nodes} nodes, {self.n_elements} {self.shape}s of order {self.order}, "
                f"{self.n_pairs} crack pairs)")


class Result:
    """What a command computed. ``json`` is its main JSON document (the same content as the file),
    ``documents`` every JSON file it wrote by name, ``files`` the names of every file (relative
    paths), and ``write(dir)`` writes them into ``dir`` as the command line would."""

    main_document = None

    def __init__(self, folder, log):
        self._folder = folder
        self._cleanup = weakref.finalize(self, shutil.rmtree, folder, True)
        self.log = log
        self.files = sorted(
            os.path.relpath(os.path.join(root, name), folder)
            for root, _, names in os.walk(folder)
            for name in names
        )
        self.documents = {}
        for name in self.files:
            if name.endswith(".json"):
                with open(os.path.join(folder, name)) as file:
                    self.documents[name] = json.load(file)
        self.json = self.documents.get(self.main_document, {})

    @property
    def estimates(self):
        """Every error estimate the command wrote, one row each (a list of dicts:
        ``pandas.DataFrame(result.estimates)`` is a table): ``at`` the estimate's place in its
        document's ``accuracy`` block (``probes/tip/A2/A1``, ``mode/f_bilinear``,
        ``pairs/0/f_open_hz``, ``probes/tip/peak_a2_over_a1/value``), ``value``, ``error`` (the
        estimate, relative), ``sum`` (the sum of the components' moduli, the conservative bound),
        ``signed``, ``rss``, ``verified``, ``asymptotic`` and ``delta <component>`` (each component's
        signed relative error). Empty where nothing was estimated."""
        rows = []

        def walk(node, path):
            if isinstance(node, dict):
                if "error" in node and isinstance(node.get("components"), dict):
                    row = {"at": "/".join(path)}
                    for key in ("value", "error", "sum", "signed", "rss", "verified", "asymptotic"):
                        row[key] = node.get(key)
                    for name, component in node["components"].items():
                        row["delta " + name] = component.get("delta") if isinstance(component, dict) else None
                    rows.append(row)
                    return
                for key, child in node.items():
                    walk(child, path + [str(key)])
            elif isinstance(node, list):
                for index, child in enumerate(node):
                    walk(child, path + [str(index)])

        for name in self._estimate_documents:
            document = self.documents.get(name) or {}
            walk(document.get("accuracy") or {}, [])
        return rows

    _estimate_documents = ()

    def write(self, directory):
        """Writes the command's files into ``directory`` (created if needed), as ``crackle ... -o
        directory`` writes them: where a text file names the output folder (run.json ``output``,
        the scene paths of study cases), it names ``directory``, spelt as given. Each file is
        written whole under a temporary name, then renamed, so no file is ever half written there."""
        directory = os.fspath(directory)
        os.makedirs(directory, exist_ok=True)
        private, given = self._folder.encode(), directory.encode()
        for name in self.files:
            target = os.path.join(directory, name)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(os.path.join(self._folder, name), "rb") as file:
                content = file.read()
            if b"\0" not in content:  # text (CSV, JSON, gnuplot scripts and data)
                content = content.replace(private, given)
            temporary = f"{target}.tmp.{os.getpid()}"
            with open(temporary, "wb") as file:
                file.write(content)
            os.replace(temporary, target)
        return directory

    @property
    def folder(self):
        """The private folder the command wrote into (the paths in ``json`` name it)."""
        return self._folder

    def read_csv(self, name):
        """A CSV file of the result as {header: column array}."""
        return read_table(os.path.join(self._folder, name))

    def nbytes(self):
        """Bytes held in the result's NumPy arrays."""
        return sum(a.nbytes for a in _arrays(self.__dict__))


def _arrays(value):
    if isinstance(value, np.ndarray):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from _arrays(item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _arrays(item)
    elif isinstance(value, Mesh):
        yield from _arrays(value.__dict__)


class ModalResult(Result):
    """``crackle modal``: ``frequencies_hz[variant]`` (n_modes,) [Hz] and ``shapes[variant]``
    (n_modes, n_nodes, 3) mass-normalised nodal displacements [m kg^-1/2] of the elastic modes of
    each variant ("uncracked", "open"); ``pairs`` (uncracked_mode, open_mode 1-based, f_uncracked_hz,
    f_open_hz, ratio, mac, f_bilinear_hz, paired) one entry per uncracked mode; ``mac`` (uncracked x
    open); ``mesh`` the modal mesh the shapes live on."""

    main_document = "modal.json"
    _estimate_documents = ("modal.json",)

    def __init__(self, folder, log, arrays):
        super().__init__(folder, log)
        self.frequencies_hz = dict(arrays["frequencies_hz"])
        self.shapes = dict(arrays["shapes"])
        self.pairs = dict(arrays["pairs"])
        self.mac = arrays["mac"]
        self.mesh = Mesh(arrays["mesh"])

    @property
    def bilinear_hz(self):
        """f_b of each uncracked mode [Hz] (NaN where not paired)."""
        return self.pairs["f_bilinear_hz"]


def _probe_histories(table):
    """probes.csv as {probe: {"time": (n,), quantity: (n, 3) or (n,), ...}} with units."""
    time_key = next((key for key in table if key.startswith("time")), None)
    probes = {}
    for header, column in table.items():
        if header == time_key:
            continue
        name, unit = split_header(header)
        probe, _, quantity = name.partition(" ")
        entry = probes.setdefault(probe, {"time": table[time_key], "units": {"time": "s"}})
        base, _, axis = quantity.rpartition("_")
        if axis in ("x", "y", "z") and base in ("u", "v", "a"):
            stacked = entry.setdefault(base, np.full((column.shape[0], 3), np.nan))
            stacked[:, "xyz".index(axis)] = column
            entry["units"][base] = unit
        else:
            entry[quantity] = column
            entry["units"][quantity] = unit
    return probes


class RunResult(Result):
    """``crackle run``: ``probes[name]`` with ``time`` (n,) [s] and ``u``, ``v``, ``a`` (n, 3) in m,
    m/s, m/s^2 (a crack-opening probe: ``gap``, ``slip_1``, ... (n,)), ``units`` per quantity;
    ``energy`` (energy.csv, {column: (n_rows,)} in J); ``spectrum`` (spectrum.json as a dict, None
    without a spectrum) and ``harmonics[probe]`` its harmonic table (``order`` (n_orders,), halves
    for sub-harmonics, ``frequency_hz``, ``amplitude`` [m], ``phase_rad``); ``modal`` the modal stage's
    modal.json (None when it did not run); ``json`` is run.json."""

    main_document = "run.json"
    _estimate_documents = ("spectrum.json",)  # run.json holds the summary only

    def __init__(self, folder, log):
        super().__init__(folder, log)
        self.probes = _probe_histories(self.read_csv("probes.csv")) if "probes.csv" in self.files else {}
        self.energy = self.read_csv("energy.csv") if "energy.csv" in self.files else {}
        self.spectrum = self.documents.get("spectrum.json")
        self.modal = self.documents.get("modal.json")
        self.transient = self.documents.get("transient.json")
        self.harmonics = {}
        for probe, entry in ((self.spectrum or {}).get("probes") or {}).items():
            rows = entry.get("harmonics", [])
            self.harmonics[probe] = {key: np.array([row[key] for row in rows]) for key in (rows[0] if rows else {})}


class SweepResult(Result):
    """``crackle sweep``: ``table`` (sweep.csv, {header: (n_points,)}), ``frequency_hz``
    (n_points,), and ``curves[probe][quantity]`` (n_points,) per probe and order (``A0``, ``A1``,
    ..., ``phase1``, ..., ``A2/A1``; ``units`` per quantity, ``component`` the analysed one, e.g.
    ``u_z``); ``json`` is sweep.json."""

    main_document = "sweep.json"
    _estimate_documents = ("sweep.json",)

    def __init__(self, folder, log):
        super().__init__(folder, log)
        self.table = self.read_csv("sweep.csv") if "sweep.csv" in self.files else {}
        self.frequency_hz = None
        self.columns = {}
        self.curves = {}
        for header, column in self.table.items():
            name, unit = split_header(header)
            if self.frequency_hz is None and "frequency" in name and unit == "Hz":
                self.frequency_hz = column
            self.columns[name] = column
            # "tip u_z A2" (probe, analysed component, quantity) or "tip stable" (probe, quantity).
            words = name.split(" ")
            if len(words) >= 2 and words[0] in self.probe_names():
                curve = self.curves.setdefault(words[0], {"units": {}})
                if len(words) >= 3:
                    curve["component"] = words[1]
                quantity = " ".join(words[2:] if len(words) >= 3 else words[1:])
                curve[quantity] = column
                curve["units"][quantity] = unit


    def probe_names(self):
        return [probe.get("name") for probe in self.json.get("probes", []) if isinstance(probe, dict)] or \
            [header.split(" ")[0] for header in self.table if " " in header and not header.startswith("excitation")]


class StudyResult(Result):
    """``crackle study``: ``table`` (study.csv, {header: (n_cases,)}; numbers as float, words as
    str), ``exit_code`` (0, or 3 when cases failed); ``json`` is study.json."""

    main_document = "study.json"

    def __init__(self, folder, log, exit_code):
        super().__init__(folder, log)
        self.exit_code = exit_code
        self.table = self.read_csv("study.csv") if "study.csv" in self.files else {}


class IdentifyResult(Result):
    """``crackle identify``: ``map`` (identify_map.csv, {header: column}); ``profiles``: the misfit's 2D
    profile of each pair of unknowns, {(key_x, key_y): (x, y, chi2)} with ``chi2[i, j]`` at ``x[i]``,
    ``y[j]`` (NaN where no finite misfit; identify.json ``profiles``; empty with one unknown); ``json`` is
    identify.json."""

    main_document = "identify.json"

    def __init__(self, folder, log, document):
        super().__init__(folder, log)
        if not self.json:
            self.json = document
        self.map = self.read_csv("identify_map.csv") if "identify_map.csv" in self.files else {}
        self.profiles = {}
        for profile in self.json.get("profiles", []):
            chi2 = np.array([[np.nan if v is None else v for v in row] for row in profile["chi2"]], dtype=float)
            x, y = (np.asarray(axis, dtype=float) for axis in profile["axes"])
            self.profiles[tuple(profile["unknowns"])] = (x, y, chi2)


class PlanResult(Result):
    """``crackle plan``: ``json`` is plan.json; ``sensors`` the candidate sensors' points (n x 3, m) in
    the order of the scene's grid or list; ``candidates`` the ranked candidates as NumPy columns:
    ``rank``, ``sensor`` (index into ``sensors``), ``drive_point`` (n x 3, m), ``drive_mode``,
    ``drive_ratio``, ``responds`` (bool), ``log_det`` (NaN where it does not respond), and
    ``widths_95_mean``, ``widths_95_worst``: {prior key: the predicted 95 % interval widths over the
    samples} (NaN where none)."""

    main_document = "plan.json"

    def __init__(self, folder, log, document):
        super().__init__(folder, log)
        if not self.json:
            self.json = document
        ranked = self.json.get("candidates", [])
        names = {}
        points = []
        for candidate in sorted(ranked, key=lambda c: int(c["sensor"]["name"].lstrip("s"))):
            name = candidate["sensor"]["name"]
            if name not in names:
                names[name] = len(points)
                points.append(candidate["sensor"]["point"])
        self.sensors = np.array(points, dtype=float).reshape(-1, 3)
        number = lambda value: np.nan if value is None else float(value)
        self.candidates = {
            "rank": np.array([c["rank"] for c in ranked], dtype=int),
            "sensor": np.array([names[c["sensor"]["name"]] for c in ranked], dtype=int),
            "drive_point": np.array([c["drive"]["point"] for c in ranked], dtype=float).reshape(-1, 3),
            "drive_mode": np.array([c["drive"]["mode"] for c in ranked], dtype=int),
            "drive_ratio": np.array([c["drive"]["ratio"] for c in ranked], dtype=float),
            "responds": np.array([bool(c["responds"]) for c in ranked], dtype=bool),
            "log_det": np.array([number(c["log_det"]) for c in ranked], dtype=float),
        }
        keys = list(ranked[0]["widths_95"]["mean"]) if ranked else []
        for figure in ("mean", "worst"):
            self.candidates["widths_95_" + figure] = {
                key: np.array([number(c["widths_95"][figure].get(key)) for c in ranked], dtype=float) for key in keys}
