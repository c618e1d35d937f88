"""Shared helpers of the Python tests: the source tree, the crackle command, file comparison."""
import json
import math
import os
import re
import subprocess

import pytest

SOURCE_DIR = os.environ.get("CRACKLE_SOURCE_DIR", os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
DATA = os.path.join(SOURCE_DIR, "data")


def data(name):
    return os.path.join(DATA, name)


def crackle_cli(arguments, check=True):
    """Runs the crackle command line; returns the CompletedProcess."""
    import crackle

    result = subprocess.run([crackle.executable(), *arguments], capture_output=True, text=True)
    if check and result.returncode != 0:
        raise AssertionError(f"crackle {' '.join(arguments)} exited {result.returncode}:\n{result.stderr}")
    return result


def set_arguments(overrides):
    arguments = []
    for key, value in overrides:
        arguments += ["--set", f"{key}={value}"]
    return arguments


# What differs between two runs of the same computation: wall-clock times, memory figures.
_VARYING_KEY = re.compile(r"(_s$|^seconds|seconds_per|timings|ns_per|rss|wall|elapsed|memory|started|finished|^share$|time_fraction)")
# Wall times in the printed logs of study cases (stdout.txt): "setup 0.017 s", "0.00709 s".
_SECONDS = re.compile(r"\b\d[\d.]*(?:e[-+]?\d+)? s\b")
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|nan|inf)")


def close(a, b, tolerance):
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b or abs(a - b) <= tolerance * max(abs(a), abs(b))


def compare_json(a, b, where, tolerance, replace):
    if isinstance(a, dict) and isinstance(b, dict):
        assert sorted(a) == sorted(b), f"{where}: keys {sorted(set(a) ^ set(b))} differ"
        for key in a:
            # A study's cases run at once: which of two that need the same modes solves them and
            # which reads the cache depends on who comes first (unless a primer solved them).
            if key == "from_cache" and where.startswith("cases" + os.sep):
                continue
            if not _VARYING_KEY.search(key):
                compare_json(a[key], b[key], f"{where}.{key}", tolerance, replace)
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), f"{where}: {len(a)} entries against {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, f"{where}[{i}]", tolerance, replace)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        assert close(float(a), float(b), tolerance), f"{where}: {a} != {b}"
    elif isinstance(a, str) and isinstance(b, str):
        assert replace(a) == replace(b), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def compare_text(a, b, where, tolerance, replace):
    a, b = replace(a), replace(b)
    words_a, words_b = _NUMBER.split(a), _NUMBER.split(b)
    numbers_a, numbers_b = _NUMBER.findall(a), _NUMBER.findall(b)
    assert words_a == words_b, f"{where}: the text differs besides its numbers"
    assert len(numbers_a) == len(numbers_b), f"{where}: {len(numbers_a)} numbers against {len(numbers_b)}"
    for i, (x, y) in enumerate(zip(numbers_a, numbers_b)):
        assert close(float(x), float(y), tolerance), f"{where}: number {i}: {x} != {y}"


def compare_folders(expected, actual, tolerance=1e-12):
    """The same files in both folders, numerically equal to `tolerance` (relative) but for wall
    times and the folders' own names."""
    def names(folder):
        return sorted(os.path.relpath(os.path.join(root, name), folder)
                      for root, _, files in os.walk(folder) for name in files)

    assert names(expected) == names(actual)
    replace = lambda text: text.replace(os.path.abspath(expected), "<out>").replace(os.path.abspath(actual), "<out>") \
        .replace(expected, "<out>").replace(actual, "<out>")
    for name in names(expected):
        path_a, path_b = os.path.join(expected, name), os.path.join(actual, name)
        if name.endswith(".json"):
            with open(path_a) as file_a, open(path_b) as file_b:
                compare_json(json.load(file_a), json.load(file_b), name, tolerance, replace)
        elif (os.sep + name).find(os.sep + "modal-cache" + os.sep) >= 0 and name.endswith(".bin"):
            # A study's cache of modal solves and reduced models: binary, with their set-up
            # times; what was computed from it is in the compared tables.
            assert os.path.getsize(path_a) > 0 and os.path.getsize(path_b) > 0, name
        elif name.endswith(".png"):
            with open(path_a, "rb") as file_a, open(path_b, "rb") as file_b:
                assert file_a.read() == file_b.read(), f"{name}: the images differ"
        else:
            with open(path_a, errors="replace") as file_a, open(path_b, errors="replace") as file_b:
                text_a, text_b = file_a.read(), file_b.read()
            if name.endswith(".txt"):
                text_a, text_b = _SECONDS.sub("<seconds>", text_a), _SECONDS.sub("<seconds>", text_b)
            compare_text(text_a, text_b, name, tolerance, replace)
    return names(expected)


@pytest.fixture
def tmp(tmp_path):
    return str(tmp_path)
