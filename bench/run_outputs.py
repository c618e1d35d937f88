"""Reads one `crackle run` output folder for the benchmark tables of scripts/bench.sh."""
import json


def read(folder, probe):
    """(run wall time [s], {stage: seconds}, transient.json, A1 of `probe` [m], its damage indices)."""
    run = json.load(open(folder + "/run.json"))
    transient = json.load(open(folder + "/transient.json"))
    spectrum = json.load(open(folder + "/spectrum.json"))
    p = spectrum["probes"][probe]
    a1 = [h["amplitude"] for h in p["harmonics"] if h["order"] == 1][0]
    stages = {x["name"]: x["seconds"] for x in run["stages"]}
    return run["wall_s"], stages, transient, a1, p["indices"]
