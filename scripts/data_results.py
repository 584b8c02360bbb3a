#!/usr/bin/python3
"""The table of scripts/data_results.sh: mean and standard error over seeds of each run group's
metrics, the HNN/baseline energy ratio, and R^2 of the copies in other units.
Usage: /usr/bin/python3 scripts/data_results.py OUT"""

import json
import math
import pathlib
import sys


def load(folder):
    return json.loads((folder / "metrics.json").read_text())


def stats(values):
    values = [v for v in values if v is not None]
    if not values:
        return math.nan, math.nan
    mean = sum(values) / len(values)
    if len(values) < 2:
        return mean, math.nan
    var = sum((v - mean) ** 2 for v in values) / (len(values) - 1)
    return mean, math.sqrt(var / len(values))


def cell(values):
    mean, se = stats(values)
    return f"{mean:.3g} ± {se:.1g}" if math.isfinite(se) else f"{mean:.3g}"


def main(out):
    runs = out / "runs"
    keys = ["test_loss", "test_r2", "energy_mse", "coordinate_mse", "valid_prediction_time"]
    print("| system | model | " + " | ".join(keys) + " |")
    print("| --- | --- | " + " | ".join("---" for _ in keys) + " |")
    ratios = []
    for system in sorted(p for p in runs.iterdir() if p.is_dir()):
        energy = {}
        for model in ("hnn", "baseline"):
            seeds = sorted((system / model).glob("seed-*"))
            if not seeds:
                continue
            metrics = [load(s) for s in seeds]
            energy[model] = stats([m["energy_mse"] for m in metrics])[0]
            print(f"| {system.name} | {model} ({len(seeds)} seeds) | "
                  + " | ".join(cell([m.get(k) for m in metrics]) for k in keys) + " |")
        if "hnn" in energy and "baseline" in energy:
            ratios.append((system.name, energy["baseline"] / energy["hnn"]))
    print()
    print("| system | baseline energy MSE / HNN energy MSE |")
    print("| --- | --- |")
    for name, ratio in ratios:
        print(f"| {name} | {ratio:.3g} |")
    print()
    print("| system | HNN test R² (seed 0) | x100 | x0.01 |")
    print("| --- | --- | --- | --- |")
    for system in sorted(p for p in runs.iterdir() if (p / "hnn-x100").is_dir()):
        r2 = [load(system / d)["test_r2"] for d in ("hnn/seed-0", "hnn-x100", "hnn-x0.01")]
        print(f"| {system.name} | " + " | ".join(f"{v:.6f}" for v in r2) + " |")


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1]))
