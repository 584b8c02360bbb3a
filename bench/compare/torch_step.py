#!/usr/bin/python3
"""PyTorch side of hnn's comparison harness (bench/compare/README.md).

Trains the same models as hnn_train_step on the same data, from the same initial parameters
(--init, written by hnn_train_step --save-init) with the same minibatch rows (splitmix64, as
compare_common.h's BatchIndices), and prints one JSON line: ms_per_step (median over timed
windows after warm-up), train_loss and test_loss.

Tasks: spring (2-dim, full batch), twobody (8-dim, batch 200), threebody (12-dim, batch 600):
a 200-200 tanh MLP to a scalar H (HNN) or to dx/dt (baseline); pixel: the residual ReLU
autoencoder 1568-200-200-200-2 and back with a 2-200-200-1 HNN (or 2-200-200-2 baseline) on
the latent, loss mean(ae + cc + 0.1 hnn). Adam, lr 1e-3. The peers' cases (torch_peers.py):
realpend with --model dhnn (batch 128, lr 5e-3), dblpend with --model lnn (batch 512), and the
spring HNN with --loss rollout (leapfrog, batch 128), and chain2 with --model chnn (the
2-chain pendulum's CHNN through RK4 chunks, L1, AdamW; its constraints and masses from
<init>.constraints.json), at the widths of --hidden.

Run with Debian's interpreter (/usr/bin/python3 sees python3-torch). Exits 0 with a message
when torch is missing.
"""
import argparse
import json
import os
import sys
import time

try:
    import numpy as np
    import torch
    import torch_peers
except ImportError as error:  # the harness skips PyTorch when it is absent
    print(f"torch_step.py: PyTorch is not available ({error}); skipping", file=sys.stderr)
    sys.exit(0)

DIMS = {"spring": 2, "twobody": 8, "threebody": 12, "pixel": 2 * 28 * 28, "realpend": 2,
        "dblpend": 4, "chain2": 8}
HNN_WEIGHT = 0.1


def task_defaults(a):
    """The per-task defaults of compare_common.h's task_defaults."""
    spring, pixel = a.task == "spring", a.task == "pixel"
    peer = a.task in ("realpend", "dblpend")
    stretch = torch_peers.STRETCHES.get(a.task)
    if a.loss == "rollout" and (stretch is None or not 1 <= a.horizon < stretch[0]):
        sys.exit("torch_step.py: --loss rollout runs spring (horizon 1..29) and chain2 (1..4)")
    if (a.model == "chnn") != (a.task == "chain2") or (a.task == "chain2" and a.loss != "rollout"):
        sys.exit("torch_step.py: chain2 trains --model chnn with --loss rollout, and only it")
    if a.batch is None:
        a.batch = (128 if a.task == "realpend" or a.loss == "rollout" else 512
                   if a.task == "dblpend" else 0 if spring else 600 if a.task == "threebody"
                   else 200)
    if a.steps is None:
        a.steps = 2000 if spring or a.task == "twobody" else 300 if pixel else 1000
    if a.lr is None:
        a.lr = 5e-3 if a.task == "realpend" else 1e-3
    if a.weight_decay is None:
        a.weight_decay = 0.0 if peer else 1e-5 if pixel else 1e-4
    if a.warmup is None:
        a.warmup = max(1, a.steps // 10)
    if a.window is None:
        a.window = max(1, (a.steps - a.warmup) // 20)
    if spring and a.n_train is None:
        a.n_train = a.n_test = 750
    if a.steps < 1 or a.warmup >= a.steps:
        sys.exit("torch_step.py: need steps > warmup >= 0")


def load_data(path, n_train, n_test, dim):
    """Raw little-endian float64: train_x, train_dx, test_x, test_dx (rows x dim each)."""
    if n_train is None or n_test is None:
        sys.exit("torch_step.py: --data needs --n-train and --n-test")
    flat = np.fromfile(path, dtype="<f8")
    sizes = [n_train, n_train, n_test, n_test]
    if flat.size != sum(sizes) * dim:
        sys.exit(f"torch_step.py: {path} holds {flat.size} values, expected {sum(sizes) * dim}")
    out, offset = [], 0
    for n in sizes:
        out.append(flat[offset:offset + n * dim].reshape(n, dim))
        offset += n * dim
    return out


def batch_indices(seed, n, count):
    """compare_common.h's BatchIndices: splitmix64 draws seed + k * golden, k = 1..count, mod n."""
    with np.errstate(over="ignore"):
        k = np.arange(1, count + 1, dtype=np.uint64)
        z = np.uint64(seed) + k * np.uint64(0x9E3779B97F4A7C15)
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return torch.from_numpy((z % np.uint64(n)).astype(np.int64))


# ---- models -------------------------------------------------------------------------------
class Mlp(torch.nn.Module):
    """d_in -> 200 -> 200 -> d_out, tanh, orthogonal weights, no bias on the last layer."""

    def __init__(self, d_in, d_out, hidden=200):
        super().__init__()
        self.l1 = torch.nn.Linear(d_in, hidden)
        self.l2 = torch.nn.Linear(hidden, hidden)
        self.l3 = torch.nn.Linear(hidden, d_out, bias=False)
        for layer in (self.l1, self.l2, self.l3):
            torch.nn.init.orthogonal_(layer.weight)

    def forward(self, x):
        return self.l3(torch.tanh(self.l2(torch.tanh(self.l1(x)))))


class Dynamics(torch.nn.Module):
    """HNN: (dH/dp, -dH/dq) of a scalar MLP; baseline: the MLP's output itself."""

    def __init__(self, dim, hnn):
        super().__init__()
        self.hnn, self.half = hnn, dim // 2
        self.mlp = Mlp(dim, 1 if hnn else dim)

    def forward(self, x, create_graph=True):
        if not self.hnn:
            return self.mlp(x)
        if not x.requires_grad:
            x = x.detach().requires_grad_(True)
        (dh,) = torch.autograd.grad(self.mlp(x).sum(), x, create_graph=create_graph)
        return torch.cat([dh[:, self.half:], -dh[:, :self.half]], 1)


class Autoencoder(torch.nn.Module):
    """h = relu(L1 x); h += relu(L2 h); h += relu(L3 h); z = L4 h; the decoder likewise."""

    def __init__(self, d_in=1568, hidden=200, latent=2):
        super().__init__()
        widths = [(d_in, hidden), (hidden, hidden), (hidden, hidden), (hidden, latent)]
        self.enc = torch.nn.ModuleList(torch.nn.Linear(i, o) for i, o in widths)
        self.dec = torch.nn.ModuleList(torch.nn.Linear(o, i) for i, o in reversed(widths))
        for layer in list(self.enc) + list(self.dec):
            torch.nn.init.orthogonal_(layer.weight)

    @staticmethod
    def _run(layers, x):
        h = torch.relu(layers[0](x))
        h = h + torch.relu(layers[1](h))
        h = h + torch.relu(layers[2](h))
        return layers[3](h)

    def encode(self, x):
        return self._run(self.enc, x)

    def decode(self, z):
        return self._run(self.dec, z)


class PixelModel(torch.nn.Module):
    def __init__(self, hnn):
        super().__init__()
        self.ae = Autoencoder()
        self.dyn = Dynamics(2, hnn)

    def loss_terms(self, x, x_next, create_graph=True):
        """Per-sample total = ae + cc + 0.1 hnn (tasks/pixel/model.h's pixel_loss)."""
        z, z_next = self.ae.encode(x), self.ae.encode(x_next)
        ae = (self.ae.decode(z) - x).pow(2).mean(1)
        hnn = (z_next - (z + self.dyn(z, create_graph))).pow(2).mean(1)
        cc = (z[:, 1] - (z_next[:, 0] - z[:, 0])).pow(2)
        return ae + cc + HNN_WEIGHT * hnn


def load_init(model, path):
    """Copies hnn's initial parameters (float64, torch layout, hnn's order) into `model`."""
    with open(path + ".json") as f:
        manifest = json.load(f)
    flat = np.fromfile(path, dtype="<f8")
    params = list(model.parameters())
    if len(params) != len(manifest):
        sys.exit(f"torch_step.py: {path} has {len(manifest)} parameters, the model {len(params)}")
    offset = 0
    with torch.no_grad():
        for p, entry in zip(params, manifest):
            if list(p.shape) != entry["shape"]:
                sys.exit(f"torch_step.py: {entry['name']} is {entry['shape']}, expected "
                         f"{list(p.shape)}")
            p.copy_(torch.from_numpy(flat[offset:offset + p.numel()].reshape(p.shape)))
            offset += p.numel()


# ---- the timed run ------------------------------------------------------------------------
class StepTimer:
    """compare_common.h's StepTimer: median ms/step over windows after the warm-up."""

    def __init__(self, steps, warmup, window):
        self.steps, self.warmup, self.window = steps, warmup, window
        self.start = self.mark = time.perf_counter()
        self.windows, self.timed_start, self.end = [], None, None

    def tick(self, done):
        if done < self.warmup:
            return
        now = time.perf_counter()
        if done == self.warmup:
            self.timed_start = self.mark = now
        elif (done - self.warmup) % self.window == 0:
            self.windows.append(1e3 * (now - self.mark) / self.window)
            self.mark = now
        if done == self.steps:
            self.end = now

    def to_json(self):
        w = sorted(self.windows)
        n = len(w)
        median = 0 if not w else w[n // 2] if n % 2 else 0.5 * (w[n // 2 - 1] + w[n // 2])
        return {"ms_per_step": median,
                "ms_mean": 1e3 * (self.end - self.timed_start) / (self.steps - self.warmup),
                "ms_min": w[0] if w else 0, "windows": n, "wall_s": self.end - self.start}


def mean_loss(loss_fn, parts, chunk=1000):
    """The mean loss over a whole split, in chunks, without a graph of the parameters."""
    total, rows = 0.0, parts[0].shape[0]
    for s in range(0, rows, chunk):
        chunk_parts = [p[s:s + chunk] for p in parts]
        total += loss_fn(chunk_parts, False).detach().double().item() * chunk_parts[0].shape[0]
    return total / rows


def build_model(a, dtype):
    """The model, its Adam groups and its loss of a batch (a list of parts: [x, dx/dt], or the
    rollout windows of torch_peers.rollout_parts)."""
    hnn = a.model == "hnn"
    if a.task == "pixel":
        model = PixelModel(hnn).to(dtype)
        groups = [{"params": model.ae.parameters(), "weight_decay": a.weight_decay},
                  {"params": model.dyn.parameters(), "weight_decay": a.dynamics_weight_decay}]
        return model, groups, lambda p, graph=True: model.loss_terms(p[0], p[1], graph).mean()
    hidden = a.hidden or [200, 200]
    if a.model == "dhnn":
        model = torch_peers.Dhnn(DIMS[a.task], hidden, a.activation)
    elif a.model == "lnn":
        model = torch_peers.Lnn(DIMS[a.task], hidden, a.activation)
    elif a.model == "chnn":
        if not a.init:
            sys.exit("torch_step.py: --model chnn needs --init (its constraints come beside it)")
        with open(a.init + ".constraints.json") as f:
            model = torch_peers.Chnn(json.load(f), hidden, a.activation)
    elif a.hidden or a.activation != "tanh":
        sys.exit("torch_step.py: --hidden and --activation apply to dhnn and lnn")
    else:
        model = Dynamics(DIMS[a.task], hnn)
    model = model.to(dtype)
    groups = [{"params": model.parameters(), "weight_decay": a.weight_decay}]
    if a.loss == "rollout":
        return model, groups, lambda p, graph=True: torch_peers.rollout_loss(
            model, p, graph, a.integrator, a.norm)
    return model, groups, lambda p, graph=True: (model(p[0], graph) - p[1]).pow(2).mean()


def split_parts(a, x, dx):
    return torch_peers.rollout_parts(x, a.horizon, a.task) if a.loss == "rollout" else [x, dx]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--task", choices=sorted(DIMS), default="spring")
    ap.add_argument("--model", choices=["hnn", "baseline", "dhnn", "lnn", "chnn"], default="hnn")
    ap.add_argument("--dtype", choices=["float32", "float64"], default="float32")
    ap.add_argument("--hidden", type=lambda t: [int(w) for w in t.split(",")],
                    help="hidden widths, e.g. 256,256 (dhnn, lnn)")
    ap.add_argument("--activation", choices=sorted(torch_peers.ACTIVATIONS), default="tanh")
    ap.add_argument("--loss", choices=["field", "rollout"], default="field")
    ap.add_argument("--horizon", type=int, default=4)
    ap.add_argument("--integrator", choices=sorted(torch_peers.INTEGRATORS), default="leapfrog")
    ap.add_argument("--norm", choices=["l2", "l1"], default="l2")
    ap.add_argument("--optimizer", choices=["adam", "adamw"], default="adam")
    ap.add_argument("--threads", type=int, default=1)
    for name in ("steps", "warmup", "window", "batch", "n-train", "n-test"):
        ap.add_argument("--" + name, type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--lr", type=float)
    ap.add_argument("--weight-decay", type=float)
    ap.add_argument("--dynamics-weight-decay", type=float, default=0.0)
    ap.add_argument("--data", required=True, help="raw float64 data (hnn_train_step --save-data)")
    ap.add_argument("--init", help="hnn's initial parameters (hnn_train_step --save-init)")
    a = ap.parse_args()
    task_defaults(a)

    torch.set_num_threads(a.threads)
    dtype = {"float32": torch.float32, "float64": torch.float64}[a.dtype]
    x_tr, dx_tr, x_te, dx_te = (torch.tensor(v, dtype=dtype) for v in
                                load_data(a.data, a.n_train, a.n_test, DIMS[a.task]))
    torch.manual_seed(a.seed)
    model, groups, loss_fn = build_model(a, dtype)
    if a.init:
        load_init(model, a.init)
    opt = (torch.optim.AdamW if a.optimizer == "adamw" else torch.optim.Adam)(groups, lr=a.lr)
    train, test = split_parts(a, x_tr, dx_tr), split_parts(a, x_te, dx_te)
    rows = train[0].shape[0]
    idx = None if a.batch == 0 else batch_indices(a.seed, rows, a.steps * a.batch)

    timer = StepTimer(a.steps, a.warmup, a.window)
    for step in range(a.steps):
        if idx is None:
            batch = train
        else:
            picked = idx[step * a.batch:(step + 1) * a.batch]
            batch = [p.index_select(0, picked) for p in train]
        loss = loss_fn(batch)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        timer.tick(step + 1)

    result = timer.to_json()
    result.update(train_loss=mean_loss(loss_fn, train), test_loss=mean_loss(loss_fn, test),
                  impl="pytorch", task=a.task, model=a.model, dtype=a.dtype,
                  hidden=a.hidden or [200, 200], activation=a.activation, loss=a.loss,
                  threads=torch.get_num_threads(), steps=a.steps, warmup=a.warmup,
                  window=a.window, batch=a.batch or rows, n_train=x_tr.shape[0], train_rows=rows,
                  n_test=x_te.shape[0], init=a.init or "own (torch orthogonal_)",
                  version=torch.__version__, blas_path=os.environ.get("LD_LIBRARY_PATH", ""))
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
