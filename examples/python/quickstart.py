"""hnn from Python in a minute: simulate a pendulum, fit an HNN and a baseline to its field, roll
both out, and draw the HNN paper's Figure 2 (trajectories in phase space, and the energy along
them) with matplotlib.

  PYTHONPATH=build/apps/python /usr/bin/python3 examples/python/quickstart.py [OUT.png]
"""

import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt
import numpy as np

import hnn

hnn.set_threads(2)
pendulum = hnn.systems.Pendulum()  # H = 3 (1 - cos q) + p^2, the paper's pendulum
x = pendulum.initial_states(1000, seed=0)
dxdt = pendulum.vector_field(x) + np.random.default_rng(0).normal(0, 0.1, x.shape)  # noisy

models = {"baseline": hnn.Baseline(2, hidden=(64, 64)), "hnn": hnn.HNN(2, hidden=(64, 64))}
for name, model in models.items():
    losses = model.fit(x, dxdt, steps=2000, lr=1e-3)
    print(f"{name}: loss {losses[0]:.3g} -> {losses[-1]:.3g}")

t = np.linspace(0, 20, 400)
x0 = np.array([[1.5, 0.0]])
paths = {"truth": pendulum.simulate(x0, t)[:, 0, :]}
for name, model in models.items():
    paths[name] = model.rollout(x0, t)[:, 0, :]

fig, (phase, energy) = plt.subplots(1, 2, figsize=(10, 4))
for name, path in paths.items():
    phase.plot(path[:, 0], path[:, 1], label=name)
    energy.plot(t, pendulum.hamiltonian(path), label=name)
phase.set(xlabel="q", ylabel="p", title="Trajectories")
energy.set(xlabel="t", ylabel="true H", title="Energy along them")
phase.legend()
out = sys.argv[1] if len(sys.argv) > 1 else "quickstart.png"
fig.tight_layout()
fig.savefig(out, dpi=100)
print(f"wrote {out}")
