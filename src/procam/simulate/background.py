"""Backgrounds fixed in the room: walls (a room corner is two), and simple solids in front of them.

The devices of a capture do not move between poses; the board does.  A :class:`Background` is given
in the (reference) camera frame, mm, so it stays where it is in the room while the board moves, as
in a real capture.  (The :class:`~procam.simulate.Scene`'s default background, one wall
``wall_offset`` mm behind the board centre, moves with the board; it is kept so that the existing
renders keep their numbers.)

Primitives (frozen dataclasses, each with an ``albedo``):

* :class:`Plane` - an infinite plane (a wall, a floor).  Planes bound the room: the camera and every
  projector must lie on the same side of each (checked by :meth:`Background.check_devices`), so the
  nearest plane along a ray is the one seen (a room corner is concave) and a plane never shadows a
  surface the camera sees (the segment from such a point to a projector stays on the devices' side).
* :class:`Box` - a solid box (``size`` along its own axes, rotated by ``R``), e.g. a crate in front
  of the wall.
* :class:`Sphere` - a solid ball.

Ray conventions: a ray is ``o + s d`` (arrays broadcast); :meth:`hit` returns the smallest
``s > 0`` at which it enters the primitive (``inf`` where it does not), :meth:`blocks` whether the
open segment ``p + u l``, ``0 < u < 1`` meets it (a shadow test towards a projector at ``p + l``),
:meth:`normal_at` the outward (plane: given) unit normal at surface points.  Solids are convex, so a
point on one never shadows itself except on its faces turned away from the light (the renderer's
facing test).  Surfaces are Lambertian; only the board is textured.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .lens import euler_matrix

__all__ = ["Plane", "Box", "Sphere", "Background"]

#: Relative tolerance of a segment's ends in :meth:`blocks` (a surface does not block itself at its point).
_EPS = 1e-9


def _vec(a, shape=(3,)) -> np.ndarray:
    a = np.array(a, dtype=float).reshape(shape)
    a.setflags(write=False)
    return a


def _check_albedo(a) -> float:
    a = float(a)
    if not 0.0 <= a <= 1.0:
        raise ValueError(f"albedo must be in [0, 1], got {a}")
    return a


@dataclass(frozen=True, eq=False)
class Plane:
    """An infinite plane through ``point`` (3,) mm with unit ``normal`` (3,) (either sign), in the frame
    of the background (the reference camera's)."""

    point: np.ndarray
    normal: np.ndarray
    albedo: float = 0.5

    kind = "plane"

    def __post_init__(self):
        s = object.__setattr__
        n = np.asarray(self.normal, float).reshape(3)
        norm = np.linalg.norm(n)
        if not norm > 0:
            raise ValueError("a plane's normal must not be zero")
        # a unit normal is kept as given (normalising it again could change its last bits)
        s(self, "normal", _vec(n if abs(norm - 1.0) <= 1e-12 else n / norm))
        s(self, "point", _vec(self.point))
        s(self, "albedo", _check_albedo(self.albedo))

    def camera_depth(self, dx, dy):
        """Depth ``s`` of camera rays ``s (dx, dy, 1)`` (origin at the frame's origin) where they meet the
        plane; ``inf`` where they do not ahead.  (The renderer's formula of the default wall.)"""
        n = self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (n @ self.point) / (dx * n[0] + dy * n[1] + n[2])
        return np.where(np.isfinite(s) & (s > 0), s, np.inf)

    def hit(self, o, d):
        o, d = np.asarray(o, float), np.asarray(d, float)
        n = self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            s = ((self.point - o) @ n) / (d @ n)
        return np.where(np.isfinite(s) & (s > _EPS), s, np.inf)

    def side(self, X) -> np.ndarray:
        """Signed distance (mm) of points (..., 3) to the plane, positive on the normal's side."""
        return (np.asarray(X, float) - self.point) @ self.normal

    def blocks(self, p, l):
        a, b = self.side(p), self.side(np.asarray(p, float) + np.asarray(l, float))
        tol = _EPS * (1.0 + np.abs(a) + np.abs(b))
        return ((a > tol) & (b < -tol)) | ((a < -tol) & (b > tol))

    def normal_at(self, X):
        return np.broadcast_to(self.normal, np.shape(X))

    def moved(self, R, T) -> "Plane":
        """The plane in another frame, ``x' = R x + T``."""
        R, T = np.asarray(R, float), np.asarray(T, float)
        return Plane(R @ self.point + T, R @ self.normal, self.albedo)

    def contains(self, X) -> np.ndarray:
        """Points strictly inside the solid: never for a plane."""
        return np.zeros(np.shape(X)[:-1], bool)

    def to_dict(self) -> dict:
        return {"kind": "plane", "point": self.point.tolist(), "normal": self.normal.tolist(), "albedo": self.albedo}


@dataclass(frozen=True, eq=False)
class Box:
    """A solid box: centre (3,) mm, edge lengths ``size`` (3,) mm along its own axes, rotation ``R`` (3, 3)
    box -> background frame (``x = R x_box + center``; default axis-aligned)."""

    center: np.ndarray
    size: np.ndarray
    R: np.ndarray = None
    albedo: float = 0.5

    kind = "box"

    def __post_init__(self):
        s = object.__setattr__
        s(self, "center", _vec(self.center))
        s(self, "size", _vec(self.size))
        if not np.all(self.size > 0):
            raise ValueError(f"a box's size must be positive, got {self.size.tolist()}")
        R = np.eye(3) if self.R is None else np.asarray(self.R, float).reshape(3, 3)
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise ValueError("a box's R must be a rotation")
        s(self, "R", _vec(R, (3, 3)))
        s(self, "albedo", _check_albedo(self.albedo))

    @staticmethod
    def at(center, size, angles_deg=(0.0, 0.0, 0.0), albedo: float = 0.5) -> "Box":
        """A box rotated by Euler angles ``(psi, nu, phi)`` in degrees (:func:`~procam.simulate.euler_matrix`)."""
        return Box(center, size, euler_matrix(angles_deg), albedo)

    def _slabs(self, o, d):
        """Entry and exit parameters (t0, t1) of the ray o + s d through the box's slabs."""
        o = (np.asarray(o, float) - self.center) @ self.R
        d = np.asarray(d, float) @ self.R
        h = 0.5 * self.size
        with np.errstate(divide="ignore", invalid="ignore"):
            a = (-h - o) / d
            b = (h - o) / d
        lo, hi = np.fmin(a, b), np.fmax(a, b)   # (fmin/fmax: a NaN of a ray along a slab's face is ignored)
        t0 = np.fmax(np.fmax(lo[..., 0], lo[..., 1]), lo[..., 2])
        t1 = np.fmin(np.fmin(hi[..., 0], hi[..., 1]), hi[..., 2])
        return t0, t1

    def hit(self, o, d):
        t0, t1 = self._slabs(o, d)
        return np.where((t1 >= t0) & (t0 > _EPS), t0, np.inf)

    def blocks(self, p, l):
        t0, t1 = self._slabs(p, l)
        return (t1 >= t0) & (t0 < 1.0 - _EPS) & (t1 > _EPS)

    def normal_at(self, X):
        q = (np.asarray(X, float) - self.center) @ self.R / (0.5 * self.size)
        axis = np.argmax(np.abs(q), axis=-1)
        sign = np.sign(np.take_along_axis(q, axis[..., None], axis=-1))
        return self.R.T[axis] * sign

    def contains(self, X) -> np.ndarray:
        q = (np.asarray(X, float) - self.center) @ self.R
        return np.all(np.abs(q) < 0.5 * self.size, axis=-1)

    def moved(self, R, T) -> "Box":
        R, T = np.asarray(R, float), np.asarray(T, float)
        return Box(R @ self.center + T, self.size, R @ self.R, self.albedo)

    def to_dict(self) -> dict:
        return {"kind": "box", "center": self.center.tolist(), "size": self.size.tolist(), "R": self.R.tolist(),
                "albedo": self.albedo}


@dataclass(frozen=True, eq=False)
class Sphere:
    """A solid ball: ``center`` (3,) mm, ``radius`` mm."""

    center: np.ndarray
    radius: float
    albedo: float = 0.5

    kind = "sphere"

    def __post_init__(self):
        s = object.__setattr__
        s(self, "center", _vec(self.center))
        if not float(self.radius) > 0:
            raise ValueError(f"a sphere's radius must be positive, got {self.radius}")
        s(self, "radius", float(self.radius))
        s(self, "albedo", _check_albedo(self.albedo))

    def _roots(self, o, d):
        oc = np.asarray(o, float) - self.center
        d = np.asarray(d, float)
        a = np.sum(d * d, axis=-1)
        b = np.sum(oc * d, axis=-1)
        c = np.sum(oc * oc, axis=-1) - self.radius ** 2
        with np.errstate(invalid="ignore", divide="ignore"):
            q = np.sqrt(b * b - a * c)
            return (-b - q) / a, (-b + q) / a

    def hit(self, o, d):
        t0, t1 = self._roots(o, d)
        return np.where(np.isfinite(t0) & (t0 > _EPS), t0, np.inf)

    def blocks(self, p, l):
        t0, t1 = self._roots(p, l)
        return np.isfinite(t0) & (t0 < 1.0 - _EPS) & (t1 > _EPS)

    def normal_at(self, X):
        return (np.asarray(X, float) - self.center) / self.radius

    def contains(self, X) -> np.ndarray:
        return np.sum((np.asarray(X, float) - self.center) ** 2, axis=-1) < self.radius ** 2

    def moved(self, R, T) -> "Sphere":
        R, T = np.asarray(R, float), np.asarray(T, float)
        return Sphere(R @ self.center + T, self.radius, self.albedo)

    def to_dict(self) -> dict:
        return {"kind": "sphere", "center": self.center.tolist(), "radius": self.radius, "albedo": self.albedo}


@dataclass(frozen=True, eq=False)
class Background:
    """Surfaces fixed in the room, in the (reference) camera frame: planes and solids, in any order.

    ``surfaces`` : tuple of :class:`Plane`, :class:`Box`, :class:`Sphere`; the nearest one along each
    ray is seen, with shadows cast by the board and the solids (planes cast none, see the module).
    """

    surfaces: tuple = ()

    def __post_init__(self):
        surfs = tuple(self.surfaces)
        if not surfs:
            raise ValueError("a background needs at least one surface")
        for k in surfs:
            if not isinstance(k, (Plane, Box, Sphere)):
                raise ValueError(f"background surfaces are Plane, Box or Sphere, got {type(k).__name__}")
        object.__setattr__(self, "surfaces", surfs)

    @staticmethod
    def wall(distance: float, normal=(0.0, 0.0, 1.0), albedo: float = 0.5) -> "Background":
        """One wall through ``(0, 0, distance)`` mm (camera frame) with the given normal."""
        return Background((Plane((0.0, 0.0, float(distance)), normal, albedo),))

    def moved(self, R, T) -> "Background":
        """The background in another device's frame, ``x' = R x + T``."""
        return Background(tuple(k.moved(R, T) for k in self.surfaces))

    def check_devices(self, centres, names) -> None:
        """Raise ``ValueError`` unless every device centre ((M, 3), this frame) lies on one side of every
        plane (off it) and outside every solid."""
        C = np.asarray(centres, float).reshape(-1, 3)
        for i, k in enumerate(self.surfaces):
            if isinstance(k, Plane):
                side = k.side(C)
                if np.any(np.abs(side) < 1e-6) or not (np.all(side > 0) or np.all(side < 0)):
                    raise ValueError(f"background surface {i} (plane): the devices ({', '.join(names)}) must all "
                                     f"lie on one side of it (signed distances {np.round(side, 3).tolist()} mm)")
            elif np.any(k.contains(C)):
                inside = [n for n, c in zip(names, k.contains(C)) if c]
                raise ValueError(f"background surface {i} ({k.kind}) contains the {', '.join(inside)}")

    def to_dict(self) -> dict:
        return {"surfaces": [k.to_dict() for k in self.surfaces]}

    # ray casting for the geometry oracle --------------------------------------------------------
    def camera_hits(self, dx, dy):
        """The nearest surface along camera rays ``s (dx, dy, 1)`` from the frame's origin: (depth s, inf where
        none; index of the surface, -1 where none), arrays shaped as ``dx``."""
        best = idx = d = None
        for i, k in enumerate(self.surfaces):
            if isinstance(k, Plane):
                s = k.camera_depth(dx, dy)
            else:
                if d is None:
                    d = np.stack([dx, dy, np.ones_like(dx)], axis=-1)
                s = k.hit(np.zeros(3), d)
            if best is None:
                best, idx = s, np.where(np.isfinite(s), 0, -1)
            else:
                closer = s < best
                best = np.where(closer, s, best)
                idx = np.where(closer, i, idx)
        return best, idx

    def blocks(self, p, l, skip=None):
        """Whether any surface (but the one index ``skip`` (...) int per point, or None) meets the open
        segments ``p + u l``, 0 < u < 1."""
        out = np.zeros(np.broadcast_shapes(np.shape(p)[:-1], np.shape(l)[:-1]), bool)
        for i, k in enumerate(self.surfaces):
            b = k.blocks(p, l)
            out |= b if skip is None else (b & (np.asarray(skip) != i))
        return out
