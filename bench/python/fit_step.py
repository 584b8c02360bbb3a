"""Seconds per training step: hnn.Model.fit from Python against the hnn program's own step on
the same work (the spring task: 750 states, full batch, an HNN 2-200-200-1, float64 or with a
fourth argument float32, Adam, 2 threads), each measured by its own clock around the steps
alone (metrics.json's train_seconds for the program). Alternates the two, prints each pair and
the medians.

  PYTHONPATH=build/apps/python /usr/bin/python3 bench/python/fit_step.py \
      build/apps/hnn [STEPS] [PAIRS] [float32]
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import hnn


def program_step(exe, steps, out, dtype):
    args = [exe, "train", "spring", "--steps", str(steps), "--threads", "2", "--quiet", "--json",
            "--force", "--out", out, "--dtype", "float" if dtype == "float32" else "double"]
    metrics = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    return metrics["train_seconds"] / steps, metrics["n_train"]


def fit_step(steps, rows, dtype):
    spring = hnn.systems.Spring()
    x = spring.initial_states(rows, seed=0)
    dxdt = spring.vector_field(x)
    model = hnn.HNN(2, hidden=(200, 200), seed=0, dtype=dtype)
    start = time.perf_counter()
    model.fit(x, dxdt, steps=steps, lr=1e-3, record_every=steps)
    return (time.perf_counter() - start) / steps


def main():
    exe = sys.argv[1]
    steps = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    pairs = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    dtype = sys.argv[4] if len(sys.argv) > 4 else "float64"
    hnn.set_threads(2)
    ratios, ours, theirs = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(pairs):
            program, rows = program_step(exe, steps, os.path.join(tmp, "run"), dtype)
            fit = fit_step(steps, rows, dtype)
            ours.append(fit)
            theirs.append(program)
            ratios.append(fit / program)
            print(f"fit {fit * 1e3:.3f} ms/step  hnn train {program * 1e3:.3f} ms/step  "
                  f"ratio {fit / program:.3f}")
    print(f"median: fit {statistics.median(ours) * 1e3:.3f} ms/step, hnn train "
          f"{statistics.median(theirs) * 1e3:.3f} ms/step, ratio {statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()
