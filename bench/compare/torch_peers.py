"""PyTorch side of the peers' cases of hnn's comparison harness (bench/compare/README.md).

Imported by torch_step.py. Written the way a PyTorch user would write each peer's model:
- the dissipative HNN (Sosanya & Greydanus 2022): one MLP gives H and D, the field is
  (dH/dp, -dH/dq) + dD/dx, each gradient one torch.autograd.grad with create_graph;
- the Lagrangian NN (Cranmer et al. 2020): their JAX equation of motion translated to functorch
  (the PyTorch 1.13 name of torch.func): per sample, hessian(L) in v, grad(L) in q and
  jacfwd(grad(L) in v) in q, torch.linalg.solve, all under vmap, and loss.backward() through it;
- the rollout loss: the spring HNN stepped by leapfrog `horizon` times with autograd.grad
  (create_graph) of the learned H, the MSE of every reached state, backward;
- the constrained HNN (Finzi et al. 2020) on the 2-chain pendulum in Cartesian coordinates:
  V = MLP(positions), dV/dx by autograd.grad, the multipliers from two Cholesky solves per
  state, 4 RK4 steps through a 5-state chunk, the mean absolute error, AdamW.
Each mirrors hnn's operation order (compare_common.h, Note [Same computation]).
"""
import math

import torch
from functorch import grad, hessian, jacfwd, vmap

ACTIVATIONS = {"tanh": torch.tanh, "softplus": torch.nn.functional.softplus,
               "relu": torch.relu, "sigmoid": torch.sigmoid}
# compare_common.h's rollout_stretches (Note [Rollout windows]): points and span of a trajectory.
STRETCHES = {"spring": (30, 3.0), "chain2": (5, 4 * 0.03)}


class DeepMlp(torch.nn.Module):
    """widths[0] -> ... -> widths[-1]; the activation after every layer but the last, which has
    no bias (hnn's Mlp, parameters in its order: layers.<i>.weight, layers.<i>.bias)."""

    def __init__(self, widths, activation):
        super().__init__()
        last = len(widths) - 2
        self.layers = torch.nn.ModuleList(
            torch.nn.Linear(i, o, bias=k < last) for k, (i, o) in enumerate(zip(widths, widths[1:])))
        self.act = ACTIVATIONS[activation]

    def forward(self, x):
        for layer in self.layers[:-1]:
            x = self.act(layer(x))
        return self.layers[-1](x)


class Dhnn(torch.nn.Module):
    """The D-HNN: column 0 of the MLP is H, column 1 is D."""

    def __init__(self, dim, hidden, activation):
        super().__init__()
        self.half = dim // 2
        self.mlp = DeepMlp([dim, *hidden, 2], activation)

    def forward(self, x, create_graph=True):
        if not x.requires_grad:
            x = x.detach().requires_grad_(True)
        out = self.mlp(x)
        (dh,) = torch.autograd.grad(out[:, 0].sum(), x, create_graph=create_graph,
                                    retain_graph=True)
        (dd,) = torch.autograd.grad(out[:, 1].sum(), x, create_graph=create_graph)
        return torch.cat([dh[:, self.half:], -dh[:, :self.half]], 1) + dd


class Lnn(torch.nn.Module):
    """The LNN as hnn's double-pendulum task builds it (nn::DynamicsModel::mlp_input): the state
    divided by its scales (1, 1, 10, 10), the angles given to the MLP as (cos, sin), and the
    kinetic prior L = MLP(x~) + prior |v~|^2 / 2 on the scaled velocities; dv/dt from
    Euler-Lagrange."""

    def __init__(self, dim, hidden, activation, angles=2, scale=(1.0, 1.0, 10.0, 10.0),
                 kinetic_prior=1.0):
        super().__init__()
        self.half, self.angles, self.prior = dim // 2, angles, kinetic_prior
        self.mlp = DeepMlp([dim + angles, *hidden, 1], activation)
        self.register_buffer("inv_scale", 1.0 / torch.tensor(scale, dtype=torch.float64))

    def lagrangian(self, q, v):
        """L of one state."""
        x = torch.cat([q, v]) * self.inv_scale.to(q.dtype)
        a = x[:self.angles]
        features = torch.cat([torch.cos(a), torch.sin(a), x[self.angles:]])
        kinetic = 0.5 * self.prior * (x[self.half:] ** 2).sum()
        return self.mlp(features).squeeze(-1) + kinetic

    def equation_of_motion(self, q, v):
        """Cranmer et al.'s: (d2L/dv2)^-1 (dL/dq - (d2L/dv dq) v), with a solve for their pinv."""
        h_vv = hessian(self.lagrangian, argnums=1)(q, v)
        g_q = grad(self.lagrangian, argnums=0)(q, v)
        h_vq = jacfwd(grad(self.lagrangian, argnums=1), argnums=0)(q, v)
        return torch.linalg.solve(h_vv, g_q - h_vq @ v)

    def forward(self, x, create_graph=True):
        n = self.half
        # Without a graph of the parameters for evaluation: functorch's transforms ignore an
        # outer no_grad, so the derivatives in x are still taken.
        with torch.set_grad_enabled(create_graph):
            a = vmap(self.equation_of_motion)(x[:, :n], x[:, n:])
        return torch.cat([x[:, n:], a], 1)


class Chnn(torch.nn.Module):
    """The CHNN as hnn's nn/constrained/mechanics.h writes it, for links |x_i - x_j| = l and
    anchors |x_i - a| = l with a known mass matrix M (`spec`: hnn_train_step's
    <init>.constraints.json). Per state, with e_c and w_c = de_c/dt the constraints' vectors and
    B = D M^-1 D^T: S = B * (e_c . e_c'), K = B * (w_c . e_c' - e_c . w_c'), nu = S^-1 G v,
    mu = S^-1 (K nu - Gdot v + G M^-1 dV); x' = v - M^-1 D^T (nu e), v' = -M^-1 dV +
    M^-1 D^T (mu e + nu w)."""

    def __init__(self, spec, hidden, activation):
        super().__init__()
        n, d = spec["points"], spec["dim"]
        self.n, self.d = n, d
        self.mlp = DeepMlp([n * d, *hidden, 1], activation)
        blocks = len(spec["links"]) + len(spec["anchors"])
        incidence, offsets = torch.zeros(blocks, n, dtype=torch.float64), torch.zeros(blocks, d,
                                                                                      dtype=torch.float64)
        for c, (i, j) in enumerate(spec["links"]):  # hnn's order: links, then anchors
            incidence[c, i], incidence[c, j] = 1.0, -1.0
        for c, (i, point) in enumerate(spec["anchors"], start=len(spec["links"])):
            incidence[c, i] = 1.0
            offsets[c] = torch.tensor(point, dtype=torch.float64)
        minv = torch.linalg.inv(torch.tensor(spec["mass"], dtype=torch.float64))
        self.register_buffer("incidence", incidence)
        self.register_buffer("offsets", offsets)
        self.register_buffer("minv", minv)
        self.register_buffer("to_velocity", incidence @ minv)  # D M^-1: blocks x points
        self.register_buffer("gram", incidence @ minv @ incidence.T)  # B

    def forward(self, z, create_graph=True):
        r, nd = z.shape[0], self.n * self.d
        x, v = z[:, :nd], z[:, nd:]
        if not x.requires_grad:
            x = x.detach().requires_grad_(True)
        (dv,) = torch.autograd.grad(self.mlp(x).sum(), x, create_graph=create_graph)
        xs, vs, dvs = (t.reshape(r, self.n, self.d) for t in (x, v, dv))
        e = torch.einsum("bn,rnk->rbk", self.incidence, xs) - self.offsets
        w = torch.einsum("bn,rnk->rbk", self.incidence, vs)
        s = self.gram * torch.bmm(e, e.transpose(1, 2))
        k = self.gram * (torch.bmm(w, e.transpose(1, 2)) - torch.bmm(e, w.transpose(1, 2)))
        r1 = (e * w).sum(-1, keepdim=True)
        r2 = (w * w).sum(-1, keepdim=True) - (
            e * torch.einsum("bn,rnk->rbk", self.to_velocity, dvs)).sum(-1, keepdim=True)
        chol = torch.linalg.cholesky(s)
        nu = torch.cholesky_solve(r1, chol)
        mu = torch.cholesky_solve(torch.bmm(k, nu) - r2, chol)
        x_dot = vs - torch.einsum("bn,rbk->rnk", self.to_velocity, nu * e)
        v_dot = (-torch.einsum("nm,rmk->rnk", self.minv, dvs)
                 + torch.einsum("bn,rbk->rnk", self.to_velocity, mu * e + nu * w))
        return torch.cat([x_dot.reshape(r, nd), v_dot.reshape(r, nd)], 1)


def rollout_parts(x, horizon, task="spring"):
    """Windows of horizon + 1 consecutive states of each trajectory of x (STRETCHES), as hnn's
    tasks::rollout_windows(regular_stretches(...)): [start, next_1..next_K, step_1..step_K]."""
    n, t_end = STRETCHES[task]
    t = [t_end * i / (n - 1) for i in range(n)]  # physics::linspace
    t[-1] = t_end
    rows = [s + i for s in range(0, x.shape[0] - n + 1, n) for i in range(n - horizon)]
    idx = torch.tensor(rows, dtype=torch.long)
    parts = [x.index_select(0, idx)]
    parts += [x.index_select(0, idx + j + 1) for j in range(horizon)]
    local = [r % n for r in rows]
    for j in range(horizon):
        h = [t[i + j + 1] - t[i + j] for i in local]
        parts.append(torch.tensor(h, dtype=torch.float64).reshape(-1, 1).to(x.dtype))
    return parts


def leapfrog(field, x, h):
    """Kick-drift-kick on the field's p- and q-parts (tasks/integrate/integrator_step.cpp's)."""
    n = x.shape[1] // 2
    half = h * 0.5
    q = x[:, :n]
    p_half = x[:, n:] + half * field(x)[:, n:]
    q1 = q + h * field(torch.cat([q, p_half], 1))[:, :n]
    p1 = p_half + half * field(torch.cat([q1, p_half], 1))[:, n:]
    return torch.cat([q1, p1], 1)


def rk4(field, x, h):
    """tasks/integrate/integrator_step.cpp's classical RK4 (h a column)."""
    half = h * 0.5
    k1 = field(x)
    k2 = field(x + half * k1)
    k3 = field(x + half * k2)
    k4 = field(x + h * k3)
    return x + (h * (1.0 / 6.0)) * (k1 + 2 * k2 + 2 * k3 + k4)


INTEGRATORS = {"leapfrog": leapfrog, "rk4": rk4}


def rollout_loss(field, parts, create_graph=True, integrator="leapfrog", norm="l2"):
    """RolloutObjective's loss: one step per window step, the MSE (norm l1: the mean absolute
    error) of every reached state, averaged over the steps."""
    horizon = (len(parts) - 1) // 2
    x, total, step = parts[0], None, INTEGRATORS[integrator]
    for j in range(horizon):
        x = step(lambda s: field(s, create_graph), x, parts[1 + horizon + j])
        d = x - parts[1 + j]
        step_loss = d.abs().mean() if norm == "l1" else d.pow(2).mean()
        total = step_loss if total is None else total + step_loss
    return total * (1.0 / horizon)
