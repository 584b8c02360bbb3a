"""Derivatives of the library's own functions at a batch of states, to any order.

A model's learned scalar (an HNN's or D-HNN's H, an LNN's L) and its field's Jacobian, by hnn's
engine; a system's H (hnn.systems: Spring, Pendulum, NBody, DoublePendulum by the engine on
their H written with its ops, Expression symbolically by GiNaC). Not a general NumPy tracer: the
functions are the library's."""

from . import _hnn

__all__ = ["grad", "hessian", "derivative", "jacobian"]


def derivative(f, x, order):
    """The `order`-th derivative of f's scalar at each state of x: [batch] + [dim] * order.

    f is a model (its H, or an LNN's L) or a system (its H); order 0 to 6, 0 being the scalar
    itself. Entry [r, i, j, ...] is d^k f / dx_i dx_j ... at row r of x."""
    if isinstance(f, _hnn.Model):
        return f._derivative(x, int(order))
    if isinstance(f, _hnn._systems.System):
        return _hnn._system_derivative(f, x, int(order))
    raise _hnn.Error(f"autodiff: expected an hnn.Model or a system, got {type(f).__name__}")


def grad(f, x):
    """dH/dx at each state of x, [batch, dim], of a model or a system: derivative(f, x, 1)."""
    return derivative(f, x, 1)


def hessian(f, x):
    """d^2 H / dx^2 at each state of x, [batch, dim, dim], of a model or a system."""
    return derivative(f, x, 2)


def jacobian(model, x):
    """The Jacobian of the model's field at each state of x, [batch, dim, dim]: entry
    [r, i, j] = d f_i / d x_j."""
    return model._field_jacobian(x)
