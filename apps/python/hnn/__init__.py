"""hnn from Python: Hamiltonian neural networks and their kin on hnn's C++ library.

States are NumPy arrays [batch, 2n], q then p (an LNN's: q then dq/dt); derivatives have the
same shape. Models compute in float64 unless made with dtype="float32". See docs/python.md.
"""

import json

from . import _hnn
from ._hnn import Error, Model, set_threads, threads
from . import autodiff, systems
from .runs import Run, load_run, train

__all__ = ["HNN", "DHNN", "Baseline", "LNN", "Model", "Error", "load", "train", "load_run",
           "Run", "systems", "autodiff", "set_threads", "threads"]


def _make(kind, dim, hidden, activation, dtype, seed, angles=0, kinetic_prior=1.0):
    widths = [hidden] if isinstance(hidden, int) else list(hidden)  # hidden=64: one layer
    return Model(kind, int(dim), [int(w) for w in widths], activation, dtype, int(seed),
                 int(angles), float(kinetic_prior))


def HNN(dim, hidden=(200, 200), activation="tanh", *, dtype="float64", seed=0, angles=0):
    """A Hamiltonian neural network: an MLP learns H(q, p); dx/dt = (dH/dp, -dH/dq).

    dim is the state's size 2n; the first `angles` coordinates are seen as (cos, sin).
    Weights are initialised from `seed` as the hnn program does (orthogonal)."""
    return _make("hnn", dim, hidden, activation, dtype, seed, angles)


def DHNN(dim, hidden=(200, 200), activation="tanh", *, dtype="float64", seed=0, angles=0):
    """The dissipative HNN (Sosanya & Greydanus 2022): H and a dissipation potential D."""
    return _make("dhnn", dim, hidden, activation, dtype, seed, angles)


def Baseline(dim, hidden=(200, 200), activation="tanh", *, dtype="float64", seed=0, angles=0):
    """The baseline: an MLP that outputs dx/dt directly."""
    return _make("baseline", dim, hidden, activation, dtype, seed, angles)


def LNN(dim, hidden=(200, 200), activation="tanh", *, dtype="float64", seed=0, angles=0,
        kinetic_prior=1.0):
    """The Lagrangian NN (Cranmer et al. 2020): L(q, v) learned, states x = (q, v = dq/dt)."""
    return _make("lnn", dim, hidden, activation, dtype, seed, angles, kinetic_prior)


def load(path, *, angles=0, kinetic_prior=1.0):
    """A model from a parameter file (Model.save's, or a run's params.bin), or a run folder's.

    A parameter file records the model's kind, activation and widths; `angles` and
    `kinetic_prior` it does not: give them when the model was made with others. A run folder
    gives its model in the data's units, in float64, as `hnn export` does."""
    return Model.load(str(path), angles=int(angles), kinetic_prior=float(kinetic_prior))


# fit's options by what takes them, with their defaults.
_ADAM = {"steps": 1000, "lr": 1e-3, "batch": 0, "record_every": 1, "weight_decay": 0.0}
_ROLLOUT = {"horizon": 1, "integrator": "rk4", "dt": 0.0}
_SAMPLED = ("sampler", "swim_scale", "rcond", "solver", "regularization", "solver_tolerance",
            "solver_iterations")


def _refuse(options, names, why):
    given = [n for n in names if n in options]
    if given:
        raise Error(f"fit: {given[0]} is not taken {why}")


def _fit(self, x, target, *, loss="derivative", fit="adam", seed=0, callback=None, **options):
    """Trains the model; returns the loss history. The hnn program's loop, losses and fits.

    loss="derivative" (the default): x and target are states and their derivatives dx/dt,
    [rows, dim] each; the loss is the mean squared error of the field.
    loss="rollout": x is trajectories [len(t), batch, dim] (as simulate returns them) and
    target their times t; the field is integrated `horizon` sampling intervals from each state
    with `integrator` (rk4, leapfrog, yoshida4 or midpoint; steps of `dt`, which must divide
    the interval, or one per interval for 0) and compared with the states there. No
    derivatives are needed.

    fit="adam" (the default) takes steps=1000, lr=1e-3, batch=0 (rows, or windows, drawn with
    replacement each step from `seed`; 0: all), record_every=1, weight_decay=0. The history is
    the loss over every row (window) at every `record_every`-th step and the last;
    `callback(step, loss)` is called at each of them (an exception it raises ends the fit).
    Ctrl-C stops after the current step, raising KeyboardInterrupt with the model at that step.
    fit="sampled" (the derivative loss; not an LNN) samples the hidden layers from the data and
    solves the last layer by least squares, without backpropagation: sampler (uswim, aswim,
    elm), swim_scale ("auto", the default, or a number > 0: how steep a SWIM neuron is), rcond
    ("auto", the default, or a number), solver (qr, the default; lsqr, cholesky),
    regularization, solver_tolerance,
    solver_iterations as `hnn train --fit sampled` takes them; its history is the one loss
    after the solve. fit="sampled+adam" samples, then trains with Adam as fit="adam".
    The GIL is released while it trains."""
    unknown = sorted(set(options) - set(_ADAM) - set(_ROLLOUT) - set(_SAMPLED))
    if unknown:
        raise Error(f"fit: unknown option {unknown[0]!r} (options: "
                    f"{', '.join([*_ADAM, *_ROLLOUT, *_SAMPLED])})")
    if loss not in ("derivative", "rollout"):
        raise Error(f"fit: loss must be derivative or rollout, got {loss!r}")
    if loss == "derivative":
        _refuse(options, _ROLLOUT, "with loss='derivative' (it is the rollout loss's)")
    if fit == "sampled":
        _refuse({**options, **({"callback": 1} if callback else {})}, [*_ADAM, "callback"],
                "with fit='sampled', which takes no training steps")
    if loss == "rollout" and fit != "adam":
        raise Error(f"fit: loss='rollout' trains with fit='adam' only, got {fit!r}")
    values = {**_ADAM, **_ROLLOUT, **options}
    spec = _hnn._FitSpec()
    spec.steps, spec.lr = int(values["steps"]), float(values["lr"])
    spec.batch, spec.record_every = int(values["batch"]), int(values["record_every"])
    spec.weight_decay, spec.seed, spec.callback = float(values["weight_decay"]), int(seed), callback
    spec.horizon, spec.integrator = int(values["horizon"]), str(values["integrator"])
    spec.dt = float(values["dt"])
    spec.fit = json.dumps({"fit": fit, **{k: v for k, v in options.items() if k in _SAMPLED}})
    if loss == "derivative":
        return self._fit(x, target, spec)
    return self._fit_rollout(x, target, spec)


Model.fit = _fit
