"""The library's Hamiltonian systems: H, the exact field and simulation, on NumPy states.

Each system has .hamiltonian(x) [batch], .vector_field(x) [batch, dim],
.simulate(x0, t, integrator="dopri5", rtol=1e-9, dt=1e-2) [len(t), batch, dim] and
.initial_states(n, seed) drawn as the hnn program's tasks draw them."""

from ._hnn import _systems

System = _systems.System

__all__ = ["System", "Spring", "Pendulum", "NBody", "DoublePendulum", "Expression"]


def Spring(stiffness=1.0, kinetic=1.0):
    """H = stiffness q^2 + kinetic p^2 (the HNN paper's spring: H = q^2 + p^2)."""
    return _systems.spring(float(stiffness), float(kinetic))


def Pendulum(potential=3.0, kinetic=1.0):
    """H = potential (1 - cos q) + kinetic p^2 (the HNN paper's: 3 (1 - cos q) + p^2)."""
    return _systems.pendulum(float(potential), float(kinetic))


def NBody(n=2, masses=None, gravity=1.0):
    """n bodies in the plane, x = (qx_1..qx_n, qy_1..qy_n, px.., py..); masses 1 by default."""
    masses = [1.0] * int(n) if masses is None else [float(m) for m in masses]
    return _systems.nbody(masses, float(gravity))


def DoublePendulum(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81):
    """The planar double pendulum in absolute angles and canonical momenta (not separable)."""
    return _systems.double_pendulum(float(m1), float(m2), float(l1), float(l2), float(g))


def Expression(hamiltonian, coords, momenta):
    """H given as a formula, e.g. Expression("p^2/2 + 9.81*(1 - cos(q))", ["q"], ["p"])."""
    return _systems.expression(str(hamiltonian), list(coords), list(momenta))
