"""The spring HNN trained by hnn.Model.fit on the reference data set, for a side-by-side run
with ../shared/reference/hnn_torch.py (the same work: 750 states, full batch, 2-200-200-1 tanh,
Adam lr 1e-3 with weight decay 1e-4, 2000 steps, 2 threads). Prints one JSON line like the
reference's: ms per step around the training loop alone, final train and test loss.

  PYTHONPATH=build/apps/python /usr/bin/python3 bench/python/fit_vs_torch.py \\
      ../shared/reference/spring_seed0.f64 [float32|float64] [STEPS]

docs/python.md gives the farm-bench command that runs it beside the reference.
"""

import json
import sys
import time

import numpy as np

import hnn


def load_raw(path, rows=750, dim=2):
    """train_x, train_dx, test_x, test_dx: raw little-endian float64, rows x dim each."""
    data = np.fromfile(path, dtype="<f8")
    if data.size != 4 * rows * dim:
        raise SystemExit(f"{path}: expected {4 * rows * dim} float64 values, got {data.size}")
    return data.reshape(4, rows, dim)


def main():
    path = sys.argv[1]
    dtype = sys.argv[2] if len(sys.argv) > 2 else "float32"
    steps = int(sys.argv[3]) if len(sys.argv) > 3 else 2000
    hnn.set_threads(2)
    train_x, train_dx, test_x, test_dx = load_raw(path)
    model = hnn.HNN(2, hidden=(200, 200), seed=0, dtype=dtype)
    start = time.perf_counter()
    model.fit(train_x, train_dx, steps=steps, lr=1e-3, weight_decay=1e-4, record_every=steps)
    wall = time.perf_counter() - start

    def mse(x, dx):
        return float(np.mean((model.vector_field(x) - dx) ** 2))

    print(json.dumps({"impl": "hnn.Model.fit", "dtype": dtype, "threads": hnn.threads(),
                      "steps": steps, "wall_s": wall, "ms_per_step": 1e3 * wall / steps,
                      "train_loss": mse(train_x, train_dx), "test_loss": mse(test_x, test_dx)}))


if __name__ == "__main__":
    main()
