"""Derivatives of the library's own functions at a batch of states, by hnn's engine.

A model's learned scalar (an HNN's or D-HNN's H, an LNN's L) to any order, its field's
Jacobian, and a system's dH/dx. Not a general NumPy tracer: the functions are the library's."""

from . import _hnn

__all__ = ["grad", "hessian", "derivative", "jacobian"]


def derivative(f, x, order):
    """The `order`-th derivative of f's scalar at each state of x: [batch] + [dim] * order.

    f is a model (its H, or an LNN's L); order 0 is the scalar itself. Entry [r, i, j, ...]
    is d^k f / dx_i dx_j ... at row r of x."""
    if isinstance(f, _hnn.Model):
        return f._derivative(x, int(order))
    if int(order) == 1:
        return grad(f, x)
    raise _hnn.Error("autodiff: a system's H has derivatives of order 1 only (its field)")


def grad(f, x):
    """dH/dx at each state of x, [batch, dim]: a model's (by the engine) or a system's (exact,
    from its field)."""
    if isinstance(f, _hnn.Model):
        return f._derivative(x, 1)
    if isinstance(f, _hnn._systems.System):
        return _hnn._system_gradient(f, x)
    raise _hnn.Error(f"autodiff: expected an hnn.Model or a system, got {type(f).__name__}")


def hessian(f, x):
    """d^2 H / dx^2 at each state of x, [batch, dim, dim] (models)."""
    return derivative(f, x, 2)


def jacobian(model, x):
    """The Jacobian of the model's field at each state of x, [batch, dim, dim]: entry
    [r, i, j] = d f_i / d x_j."""
    return model._field_jacobian(x)
