"""Seconds per call on a large batch with the states read in place (a C-contiguous float64
array: apps/python/arrays.h StatesIn) against the same states copied first, as every array was
before: the same values one byte off alignment, which StatesIn does not read in place, so they
take states()'s one copy (copy_strided), the path a C-contiguous array took until then. Both in
one process, alternated; prints the medians and their ratio. The copy counter
(hnn._hnn._state_copies) confirms which path each took.

  PYTHONPATH=build/apps/python /usr/bin/python3 bench/python/arrays_in.py [ROWS] [REPEATS] \
      [WIDTH]     # the HNN's two hidden layers (default 32: the paper's 200 makes a call
                  # of 10^6 rows take seconds, beside which a copy is lost)
"""

import statistics
import sys
import time

import numpy as np

import hnn


def unaligned_copy(x):
    """x's values, C-contiguous float64, at an address one byte past an aligned one."""
    raw = np.empty(x.nbytes + 1, dtype=np.uint8)
    out = np.frombuffer(raw.data, dtype=np.float64, count=x.size, offset=1).reshape(x.shape)
    out[...] = x
    assert out.flags.c_contiguous and not out.flags.aligned
    return out


def seconds(f, x):
    start = time.perf_counter()
    f(x)
    return time.perf_counter() - start


def main():
    rows = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    width = int(sys.argv[3]) if len(sys.argv) > 3 else 32
    hnn.set_threads(2)
    x = np.random.default_rng(0).uniform(-1, 1, (rows, 4))
    moved = unaligned_copy(x)
    model = hnn.HNN(4, hidden=(width, width), seed=0)
    calls = {f"HNN 4-{width}-{width}-1 vector_field": model.vector_field,
             f"HNN 4-{width}-{width}-1 hamiltonian": model.hamiltonian,
             "DoublePendulum.vector_field": hnn.systems.DoublePendulum().vector_field,
             "DoublePendulum.hamiltonian": hnn.systems.DoublePendulum().hamiltonian,
             "Expression (two oscillators).vector_field": hnn.systems.Expression(
                 "(p1^2 + p2^2)/2 + (q1^2 + q2^2)/2", ["q1", "q2"], ["p1", "p2"]).vector_field}
    for name, f in calls.items():
        np.testing.assert_array_equal(f(x), f(moved))  # the same bits either way
        in_place, copied = [], []
        for _ in range(repeats):
            before = hnn._hnn._state_copies()
            in_place.append(seconds(f, x))
            assert hnn._hnn._state_copies() == before
            copied.append(seconds(f, moved))
            assert hnn._hnn._state_copies() == before + 1
        a, b = statistics.median(in_place), statistics.median(copied)
        print(f"{name}: {rows} x 4, in place {a * 1e3:.2f} ms, copied {b * 1e3:.2f} ms, "
              f"copied / in place {b / a:.3f}")


if __name__ == "__main__":
    main()
