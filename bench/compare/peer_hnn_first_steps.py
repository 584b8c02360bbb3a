#!/usr/bin/env python3
"""Their HNN's first training steps, in PyTorch, on a constrained task's motion.

Finzi, Wang & Wilson's "HNN" (biases/models/hnn.py of mfinzi/constrained-hamiltonian-neural-
networks): H = 1/2 p^T M^-1(q) p + V(q), M^-1 = L L^T + 1e-4 I, V and L tanh MLPs 3 x 256 of
(cos, sin of the angles, the other coordinates), orthogonal weights, torch.nn.Linear's biases
(L's last at zero). Trained as their pl_trainer does: L1 over 5-point chunks through
torchdiffeq's "rk4" (Kutta's 3/8 rule), AdamW lr 3e-3, weight decay 1e-4, shuffled epochs of
batch 200, float32.

--form qp integrates (q, p) from p0 = M(q0) v0 and reads v = M^-1 p at the outputs, as their
HNN.integrate does; --form qv integrates (q, dq/dt), solving for p at every stage, as hnn's
nn/mass_hnn.h does. Each seed starts both forms from the same weights and batches.

The chunks are the true paths of an hnn run of the task in body coordinates (its rollout.csv,
rows "true"): every path cut into 5-point chunks, 800 of them drawn at random. Make one with
  hnn train magnet-pendulum --model hnn-mass --steps 1 --lr 1e-12 --out RUN
and run
  /usr/bin/python3 bench/compare/peer_hnn_first_steps.py RUN --angles 2
It prints, per seed and form, the step at which a batch's loss was first not finite, or the
loss after --steps steps. Their full protocol is --steps 8000 --cosine-epochs 2000.
"""
import argparse
import csv

import torch
import torch.nn as nn


def read_chunks(run, count, generator):
    paths = {}
    with open(f"{run}/rollout.csv") as f:
        for row in csv.DictReader(f):
            if row["source"] == "true":
                state = [float(v) for k, v in row.items() if k.startswith("x_")]
                paths.setdefault(row["traj"], []).append((float(row["t"]), state))
    chunks, dt = [], None
    for path in paths.values():
        dt = path[1][0] - path[0][0]
        states = [s for _, s in path]
        chunks += [states[i:i + 5] for i in range(0, len(states) - 4, 5)]
    chunks = torch.tensor(chunks, dtype=torch.float32)
    return chunks[torch.randperm(len(chunks), generator=generator)[:count]], dt


def linear(fan_in, fan_out, zero_bias=False):
    layer = nn.Linear(fan_in, fan_out)
    if zero_bias:
        nn.init.zeros_(layer.bias)
    nn.init.orthogonal_(layer.weight)
    return layer


def mlp(fan_in, fan_out, zero_bias):
    return nn.Sequential(linear(fan_in, 256), nn.Tanh(), linear(256, 256), nn.Tanh(),
                         linear(256, 256), nn.Tanh(), linear(256, fan_out, zero_bias))


class TheirHnn(nn.Module):
    def __init__(self, n, angles):
        super().__init__()
        self.n, self.angles = n, angles
        self.potential = mlp(n + angles, 1, False)
        self.factor = mlp(n + angles, n * n, True)

    def embed(self, q):
        a = self.angles
        return torch.cat([torch.cos(q[:, :a]), torch.sin(q[:, :a]), q[:, a:]], -1)

    def minv(self, q):
        raw = self.factor(self.embed(q)).view(-1, self.n, self.n)
        diagonal = nn.functional.softplus(torch.diagonal(raw, dim1=-2, dim2=-1))
        lower = torch.tril(raw, -1) + torch.diag_embed(diagonal)
        return lower @ lower.transpose(-1, -2) + 1e-4 * torch.eye(self.n)

    def hamiltonian(self, q, p):
        kinetic = 0.5 * (p.unsqueeze(-2) @ self.minv(q) @ p.unsqueeze(-1)).view(-1)
        return kinetic + self.potential(self.embed(q)).view(-1)

    def momenta(self, q, v):
        return torch.linalg.solve(self.minv(q), v.unsqueeze(-1)).squeeze(-1)

    def velocities(self, q, p):
        return (self.minv(q) @ p.unsqueeze(-1)).squeeze(-1)

    def field_qp(self, z):
        with torch.enable_grad():
            z = z + torch.zeros_like(z, requires_grad=True)
            dh = torch.autograd.grad(self.hamiltonian(z[:, :self.n], z[:, self.n:]).sum(), z,
                                     create_graph=True)[0]
        return torch.cat([dh[:, self.n:], -dh[:, :self.n]], -1)

    def field_qv(self, x):
        with torch.enable_grad():
            x = x + torch.zeros_like(x, requires_grad=True)
            q, v = x[:, :self.n], x[:, self.n:]
            p = self.momenta(q, v)
            p_dot = -torch.autograd.grad(self.hamiltonian(q, p).sum(), q, create_graph=True)[0]
            # dv/dt = M^-1 dp/dt + (d M^-1 / dt) p: the second term a Jacobian-vector product
            # along dq/dt = v, by the double-backward trick.
            ones = torch.ones_like(v, requires_grad=True)
            pulled = torch.autograd.grad(self.velocities(q, p), q, ones, create_graph=True)[0]
            turned = torch.autograd.grad(pulled, ones, v, create_graph=True)[0]
        return torch.cat([v, self.velocities(q, p_dot) + turned], -1)


def rk4_38(f, z, h):
    k1 = f(z)
    k2 = f(z + h * k1 / 3)
    k3 = f(z + h * (k2 - k1 / 3))
    k4 = f(z + h * (k1 - k2 + k3))
    return z + h * (k1 + 3 * (k2 + k3) + k4) / 8


def chunk_loss(model, chunk, dt, form):
    n = model.n
    x = chunk[:, 0]
    states = [x]
    if form == "qp":
        z = torch.cat([x[:, :n], model.momenta(x[:, :n], x[:, n:])], -1)
        for _ in range(chunk.shape[1] - 1):
            z = rk4_38(model.field_qp, z, dt)
            states.append(torch.cat([z[:, :n], model.velocities(z[:, :n], z[:, n:])], -1))
    else:
        for _ in range(chunk.shape[1] - 1):
            x = rk4_38(model.field_qv, x, dt)
            states.append(x)
    return (torch.stack(states, 1) - chunk).abs().mean()


def train(chunks, dt, angles, form, seed, steps, cosine_epochs):
    torch.manual_seed(seed)
    model = TheirHnn(chunks.shape[-1] // 2, angles)
    optimiser = torch.optim.AdamW(model.parameters(), lr=3e-3, weight_decay=1e-4)
    # Their pl_trainer anneals per epoch: CosineAnnealingLR(T_max=n_epochs, eta_min=0).
    schedule = (torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, T_max=cosine_epochs)
                if cosine_epochs else None)
    order = torch.Generator().manual_seed(seed)
    step = 0
    while True:
        for batch in torch.randperm(len(chunks), generator=order).split(200):
            step += 1
            loss = chunk_loss(model, chunks[batch], dt, form)
            if not torch.isfinite(loss):
                return f"step {step}: loss {float(loss)}"
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            if step % 1000 == 0:
                print(f"  seed {seed} {form}: loss {float(loss):.3g} at step {step}", flush=True)
            if step == steps:
                return f"trains on: loss {float(loss):.3g} at step {step}"
        if schedule:
            schedule.step()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="an hnn run folder of the task in body coordinates")
    ap.add_argument("--angles", type=int, required=True, help="leading coordinates that are angles")
    ap.add_argument("--seeds", type=int, default=6, help="how many seeds")
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--forms", default="qp,qv")
    ap.add_argument("--cosine-epochs", type=int, default=0,
                    help="anneal lr to 0 over N epochs as their runs do (2000; 4 steps each); "
                    "0: a constant lr")
    args = ap.parse_args()
    torch.set_num_threads(1)
    chunks, dt = read_chunks(args.run, 800, torch.Generator().manual_seed(0))
    print(f"{len(chunks)} chunks of {chunks.shape[1]} states, dim {chunks.shape[2]}, dt {dt:g}")
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        for form in args.forms.split(","):
            outcome = train(chunks, dt, args.angles, form, seed, args.steps, args.cosine_epochs)
            print(f"seed {seed} {form}: {outcome}", flush=True)


if __name__ == "__main__":
    main()
