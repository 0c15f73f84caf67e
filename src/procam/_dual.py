"""Forward-mode automatic differentiation on numpy arrays, for the Jacobians of the single-pose joint fit.

A :class:`Dual` carries a value ``v`` (any shape ``S``) and its derivatives ``d`` (shape ``S + (P,)``) with
respect to ``P`` parameters. Arithmetic and the few functions the camera and projector models need
(:func:`sqrt`, :func:`sin`, :func:`cos`, :func:`where`, ...) propagate both, broadcasting over ``S`` as numpy
does, so a model written once on plain arrays gives its exact Jacobian when handed :func:`seed` parameters:
one pass instead of one evaluation per parameter (finite differences), and no step size to choose.

>>> x = seed(np.array([2.0, 3.0]))
>>> y = x[0] * x[0] * x[1] + sin(x[1])
>>> float(y.v), [round(float(g), 6) for g in y.d]
(12.141120008059866, [12.0, 3.010008])
"""

from __future__ import annotations

import numpy as np


class Dual:
    """A value and its derivatives: ``v`` (shape S), ``d`` (shape S + (P,))."""

    __slots__ = ("v", "d")
    __array_priority__ = 1000          # numpy defers to Dual's reflected operators

    def __init__(self, v, d):
        self.v = v
        self.d = d

    # shape ---------------------------------------------------------------------------------------------
    @property
    def shape(self):
        return np.shape(self.v)

    def __len__(self):
        return len(self.v)

    def __getitem__(self, idx):
        v = self.v[idx]
        if not isinstance(idx, tuple):
            idx = (idx,)
        return Dual(v, self.d[idx + (Ellipsis,)] if Ellipsis not in idx else self.d[idx])

    # arithmetic ----------------------------------------------------------------------------------------
    def __add__(self, o):
        if isinstance(o, Dual):
            return Dual(self.v + o.v, self.d + o.d)
        return Dual(self.v + o, np.broadcast_to(self.d, np.shape(self.v + o) + self.d.shape[-1:]))

    __radd__ = __add__

    def __neg__(self):
        return Dual(-self.v, -self.d)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if isinstance(o, Dual):
            return Dual(self.v * o.v, self.d * _col(o.v) + _col(self.v) * o.d)
        o = np.asarray(o)
        return Dual(self.v * o, self.d * _col(o))

    __rmul__ = __mul__

    def __truediv__(self, o):
        if isinstance(o, Dual):
            inv = 1.0 / o.v
            v = self.v * inv
            return Dual(v, (self.d - _col(v) * o.d) * _col(inv))
        o = np.asarray(o)
        return Dual(self.v / o, self.d / _col(o))

    def __rtruediv__(self, o):
        inv = 1.0 / self.v
        v = np.asarray(o) * inv
        return Dual(v, -_col(v * inv) * self.d)

    def __pow__(self, n):
        if not np.isscalar(n):
            raise TypeError("Dual ** only takes a constant exponent")
        return Dual(self.v ** n, _col(n * self.v ** (n - 1)) * self.d)


def _col(a):
    """``a`` with a trailing axis for the parameters."""
    return np.asarray(a)[..., None]


def seed(x) -> Dual:
    """The parameter vector ``x`` (P,) as a Dual whose derivatives are the identity."""
    x = np.asarray(x, float)
    return Dual(x.copy(), np.eye(len(x)))


def const(v, n_params: int) -> Dual:
    """A constant (zero derivatives)."""
    v = np.asarray(v, float)
    return Dual(v, np.zeros(v.shape + (n_params,)))


def value(a):
    """The value of a Dual or of a plain array."""
    return a.v if isinstance(a, Dual) else a


def sqrt(a):
    if isinstance(a, Dual):
        s = np.sqrt(a.v)
        return Dual(s, a.d * _col(0.5 / s))
    return np.sqrt(a)


def sin(a):
    if isinstance(a, Dual):
        return Dual(np.sin(a.v), a.d * _col(np.cos(a.v)))
    return np.sin(a)


def cos(a):
    if isinstance(a, Dual):
        return Dual(np.cos(a.v), -a.d * _col(np.sin(a.v)))
    return np.cos(a)


def where(cond, a, b):
    """Elementwise choice between two Duals (or a Dual and an array) of one shape."""
    if not isinstance(a, Dual) and not isinstance(b, Dual):
        return np.where(cond, a, b)
    n = (a if isinstance(a, Dual) else b).d.shape[-1]
    a = a if isinstance(a, Dual) else const(np.broadcast_to(a, np.shape(value(b))), n)
    b = b if isinstance(b, Dual) else const(np.broadcast_to(b, np.shape(a.v)), n)
    return Dual(np.where(cond, a.v, b.v), np.where(_col(cond), a.d, b.d))


def concatenate(parts):
    """Concatenate 1-D Duals and arrays into one 1-D Dual (arrays as constants)."""
    n = next(p.d.shape[-1] for p in parts if isinstance(p, Dual))
    parts = [p if isinstance(p, Dual) else const(p, n) for p in parts]
    return Dual(np.concatenate([p.v.ravel() for p in parts]),
                np.concatenate([p.d.reshape(-1, n) for p in parts]))


def rotation(r):
    """Rotation matrix of a rotation vector ``r`` (3,) (Dual or array): a 3 x 3 nested list of scalars.

    Rodrigues' formula ``R = I + a [k]x + b [k]x^2`` with ``a = sin(t)/t``, ``b = (1 - cos t)/t^2`` written in
    ``r`` directly (``a [r]x + b [r]x^2``), with their Taylor series below ``t = 1e-4`` so that the derivative
    at ``r = 0`` is exact.
    """
    rx, ry, rz = r[0], r[1], r[2]
    t2 = rx * rx + ry * ry + rz * rz
    t2v = float(value(t2))
    if t2v < 1e-8:
        a = 1.0 - t2 / 6.0
        b = 0.5 - t2 / 24.0
    else:
        t = sqrt(t2)
        a = sin(t) / t
        b = (1.0 - cos(t)) / t2
    return [[1.0 - b * (ry * ry + rz * rz), -a * rz + b * rx * ry, a * ry + b * rx * rz],
            [a * rz + b * rx * ry, 1.0 - b * (rx * rx + rz * rz), -a * rx + b * ry * rz],
            [-a * ry + b * rx * rz, a * rx + b * ry * rz, 1.0 - b * (rx * rx + ry * ry)]]


def transform(R, t, X):
    """``R X + t`` for points X given as three (N,) coordinates (arrays or Duals); R 3 x 3 nested, t (3,)."""
    return [R[i][0] * X[0] + R[i][1] * X[1] + R[i][2] * X[2] + t[i] for i in range(3)]
