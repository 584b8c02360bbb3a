"""PyTorch side of the peers' cases of hnn's comparison harness (bench/compare/README.md).

Imported by torch_step.py. Written the way a PyTorch user would write each peer's model:
- the dissipative HNN (Sosanya & Greydanus 2022): one MLP gives H and D, the field is
  (dH/dp, -dH/dq) + dD/dx, each gradient one torch.autograd.grad with create_graph;
- the Lagrangian NN (Cranmer et al. 2020): their JAX equation of motion translated to functorch
  (the PyTorch 1.13 name of torch.func): per sample, hessian(L) in v, grad(L) in q and
  jacfwd(grad(L) in v) in q, torch.linalg.solve, all under vmap, and loss.backward() through it;
- the rollout loss: the spring HNN stepped by leapfrog `horizon` times with autograd.grad
  (create_graph) of the learned H, the MSE of every reached state, backward.
Each mirrors hnn's operation order (compare_common.h, Note [Same computation]).
"""
import math

import torch
from functorch import grad, hessian, jacfwd, vmap

ACTIVATIONS = {"tanh": torch.tanh, "softplus": torch.nn.functional.softplus,
               "relu": torch.relu, "sigmoid": torch.sigmoid}
SPRING_POINTS, SPRING_T_END = 30, 3.0  # compare_common.h, Note [Rollout windows]


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


def rollout_parts(x, horizon):
    """Windows of horizon + 1 consecutive states of each 30-point trajectory of x, as hnn's
    tasks::rollout_windows(regular_stretches(...)): [start, next_1..next_K, step_1..step_K]."""
    n = SPRING_POINTS
    t = [SPRING_T_END * i / (n - 1) for i in range(n)]  # physics::linspace
    t[-1] = SPRING_T_END
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


def rollout_loss(field, parts, create_graph=True):
    """RolloutObjective's loss: one step per window step, the MSE of every reached state,
    averaged over the steps."""
    horizon = (len(parts) - 1) // 2
    x, total = parts[0], None
    for j in range(horizon):
        x = leapfrog(lambda s: field(s, create_graph), x, parts[1 + horizon + j])
        step_loss = (x - parts[1 + j]).pow(2).mean()
        total = step_loss if total is None else total + step_loss
    return total * (1.0 / horizon)
