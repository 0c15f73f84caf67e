"""Rigs: several cameras and projectors around one board and one room.

A :class:`Rig` is one or more cameras and one or more projectors (:class:`Device`, each named, with
its intrinsics, lens, size and pose relative to the reference camera - the first camera), sharing one
board pose and one background fixed in the room.  :meth:`Rig.scene` gives the ordinary single-pair
:class:`~procam.simulate.Scene` of one camera and one projector: render it to get that projector's
sequence as that camera records it.  The other projectors are then OFF (dark: they add no light, not
even their black level; raise the scene's ``ambient`` to stand for it) and do not occlude anything.

* :meth:`Rig.with_board_pose` - place the board so that every device sees it whole.
* :meth:`Rig.relative_pose`, :meth:`Rig.truth` - every device and every relative pose, exactly.
* :func:`rig_preset`, :data:`RIG_PRESETS` - two projectors side by side with one camera, one
  projector between two cameras.

Conventions: the reference frame is the first camera's; a device's pose is ``x_dev = R x_ref + T``
(mm); board -> reference camera pose ``X_ref = R_board X_b + t_board``; angles in degrees.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

from ..io.files import to_jsonable
from ..io.formats import SIM_RIG_TRUTH_FORMAT
from .background import Background
from .lens import _K, Lens, euler_matrix, matrix_euler
from .poses import _margins, _place
from .presets import RECOMMENDED_POSE
from .scene import Scene, _frozen, board_extent

__all__ = ["Device", "Rig", "RIG_PRESETS", "rig_preset"]

RIG_PRESETS = ("two_projectors", "two_cameras")


@dataclass(frozen=True, eq=False)
class Device:
    """One camera or projector of a :class:`Rig`.

    name : unique in the rig.
    kind : ``"camera"`` or ``"projector"``.
    size : (width, height) px (a projector's panel).
    K : (3, 3) intrinsics (zero skew); a projector's principal point may lie anywhere (lens shift).
    lens : its distortion (:class:`~procam.simulate.Lens`, default none).
    R, T : reference camera -> device, ``x_dev = R x_ref + T`` (mm); the identity for the reference camera.
    """

    name: str
    kind: str
    size: tuple
    K: np.ndarray
    lens: Lens = Lens()
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    T: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        s = object.__setattr__
        if self.kind not in ("camera", "projector"):
            raise ValueError(f"a device's kind is 'camera' or 'projector', got {self.kind!r}")
        s(self, "size", (int(self.size[0]), int(self.size[1])))
        s(self, "K", _frozen(self.K, (3, 3)))
        s(self, "R", _frozen(self.R, (3, 3)))
        s(self, "T", _frozen(self.T, (3,)))
        if not np.allclose(self.R @ self.R.T, np.eye(3), atol=1e-9) or np.linalg.det(self.R) < 0:
            raise ValueError(f"device {self.name!r}: R must be a rotation")
        if not isinstance(self.lens, Lens):
            raise ValueError(f"device {self.name!r}: lens must be a Lens")

    @property
    def center(self) -> np.ndarray:
        """The device's centre of projection in the reference frame, ``-R^T T`` (3,) mm."""
        return -self.R.T @ self.T

    def to_dict(self) -> dict:
        K = self.K
        return {"kind": self.kind, "size": list(self.size), "K": K.tolist(), "f": K[0, 0], "alpha": K[1, 1] / K[0, 0],
                "u0": K[0, 2], "v0": K[1, 2], "distortion": self.lens.to_dict(K), "R": self.R.tolist(),
                "T": self.T.tolist(), "angles_deg": matrix_euler(self.R).tolist(), "center": self.center.tolist(),
                "definition": "x_dev = R x_ref + T"}


@dataclass(frozen=True, eq=False)
class Rig:
    """Cameras and projectors sharing one board pose and one background (immutable).

    cameras, projectors : tuples of :class:`Device`; the first camera is the reference (R = I, T = 0).
    template : a :class:`~procam.simulate.Scene` giving what the devices share - the board (geometry and
        pose, board -> reference camera), the background and the photometry; its own devices are not used.
        Its background is fixed in the room: a template with the default wall (which moves with the board)
        gets that wall fixed where it stands at the template's board pose.
    name : label written to the truth.
    """

    cameras: tuple
    projectors: tuple
    template: Scene = field(default_factory=Scene)
    name: str = "custom"

    def __post_init__(self):
        s = object.__setattr__
        s(self, "cameras", tuple(self.cameras))
        s(self, "projectors", tuple(self.projectors))
        if not self.cameras or not self.projectors:
            raise ValueError("a rig needs at least one camera and one projector")
        for d in self.cameras + self.projectors:
            if not isinstance(d, Device):
                raise ValueError(f"a rig's devices are Device, got {type(d).__name__}")
        if any(d.kind != "camera" for d in self.cameras) or any(d.kind != "projector" for d in self.projectors):
            raise ValueError("cameras must be of kind 'camera' and projectors of kind 'projector'")
        names = [d.name for d in self.devices]
        if len(set(names)) != len(names):
            raise ValueError(f"device names must be unique, got {names}")
        ref = self.cameras[0]
        if not (np.allclose(ref.R, np.eye(3), atol=1e-12) and np.allclose(ref.T, 0.0, atol=1e-9)):
            raise ValueError(f"the first camera ({ref.name!r}) is the reference: its R must be I and T zero")
        if self.template.background is None:
            s(self, "template", self.template.replace(background=self.template.surfaces()))
        self.template.background.check_devices([d.center for d in self.devices], names)

    @property
    def devices(self) -> tuple:
        """Every device, cameras first."""
        return self.cameras + self.projectors

    def device(self, name: str) -> Device:
        """The device called ``name`` (``KeyError`` naming the rig's devices if none)."""
        for d in self.devices:
            if d.name == name:
                return d
        raise KeyError(f"no device {name!r} in the rig (devices: {', '.join(d.name for d in self.devices)})")

    def relative_pose(self, a: str, b: str):
        """``(R, T)`` of device ``a`` -> device ``b``: ``x_b = R x_a + T`` (mm)."""
        da, db = self.device(a), self.device(b)
        R = db.R @ da.R.T
        return R, db.T - R @ da.T

    def scene(self, camera: str | None = None, projector: str | None = None) -> Scene:
        """The single-pair :class:`~procam.simulate.Scene` of one camera and one projector (default: the
        first of each), in that camera's frame: its board pose, background and extrinsics ``x_p = R x_c + T``
        follow from the rig's; the other projectors are off (see the module)."""
        c = self.cameras[0] if camera is None else self.device(camera)
        p = self.projectors[0] if projector is None else self.device(projector)
        if c.kind != "camera" or p.kind != "projector":
            raise ValueError(f"scene(camera=..., projector=...) takes a camera and a projector, got {c.kind} "
                             f"{c.name!r} and {p.kind} {p.name!r}")
        R, T = self.relative_pose(c.name, p.name)
        t = self.template
        return t.replace(
            cam_size=c.size, K_cam=c.K, cam_distortion=c.lens.model, cam_dist_coeffs=c.lens.coeffs,
            cam_dist_center=c.lens.center, cam_dist_higher=c.lens.higher,
            proj_size=p.size, K_proj=p.K, proj_distortion=p.lens.model, proj_dist_coeffs=p.lens.coeffs,
            proj_dist_center=p.lens.center, proj_dist_higher=p.lens.higher, R=R, T=T,
            R_board=c.R @ t.R_board, t_board=c.R @ t.t_board + c.T, background=t.background.moved(c.R, c.T),
            name=f"{self.name}/{c.name}/{p.name}")

    def pairs(self) -> list[tuple[str, str]]:
        """Every (camera, projector) pair of names."""
        return [(c.name, p.name) for c in self.cameras for p in self.projectors]

    def fit_margin(self, R_board=None, t_board=None) -> float:
        """The smallest :func:`~procam.simulate.fit_margin` over every pair (camera px): the board seen whole
        by every device when positive."""
        R_b = self.template.R_board if R_board is None else np.asarray(R_board, float)
        t_b = self.template.t_board if t_board is None else np.asarray(t_board, float)
        return float(self._margins(R_b, t_b)[0])

    def _margins(self, R_b, t_b, scenes=None):
        """(M,) smallest margin over the pairs of board -> reference camera poses (``R_b``, ``t_b`` (M, 3));
        ``scenes`` the pairs' scenes if already built."""
        t_b = np.asarray(t_b, float).reshape(-1, 3)
        m = None
        for (cam, proj), sc in zip(self.pairs(), scenes or [self.scene(c, p) for c, p in self.pairs()]):
            c = self.device(cam)
            mi = _margins(sc, c.R @ R_b, t_b @ c.R.T + c.T)
            m = mi if m is None else np.minimum(m, mi)
        return m

    def with_board_pose(self, angles_deg, distance: float | None = None, frame: str | None = None, center=None,
                        border_px: float = 8.0, max_distance: float = 3000.0, step: float = 25.0) -> "Rig":
        """The rig with the board at a new pose, seen whole by every device: the search of
        :func:`~procam.simulate.with_board_pose` on the smallest margin over the pairs.  ``frame`` names the
        device whose frame ``angles_deg`` (board -> device) and ``center`` are in (default: the reference
        camera)."""
        d = self.cameras[0] if frame is None else self.device(frame)

        def to_camera(R_bd, c):
            if np.ndim(c) == 1:
                return d.R.T @ R_bd, d.R.T @ (c - d.T)
            return d.R.T @ R_bd, (c - d.T) @ d.R

        scenes = [self.scene(c, p) for c, p in self.pairs()]
        R_b, t_b = _place(lambda R, t: self._margins(R, t, scenes), to_camera, angles_deg, distance, center,
                          border_px, max_distance, step)
        return dataclasses.replace(self, template=self.template.replace(R_board=R_b, t_board=t_b))

    def truth(self) -> dict:
        """Every device and every relative pose, JSON-able.

        Keys: ``format`` (``"procam-sim-rig-truth"``), ``version``, ``name``, ``reference`` (the reference
        camera's name), ``devices`` ({name: kind, size, K, f, alpha, u0, v0, distortion, R, T (reference ->
        device), angles_deg, center (reference frame)}), ``relative`` ({"a->b": R, T, angles_deg, baseline
        (mm), for every ordered pair of distinct devices, ``x_b = R x_a + T``}), ``board`` (cols, rows,
        square, margin, extent), ``pose`` ({name: R, t, angles_deg of board -> device}), ``background``
        (fixed in the room, reference frame), ``pairs`` ([camera, projector] names) and ``fit_margin_px``.
        Each pair's own truth (corners, ...) is :func:`~procam.simulate.truth` of :meth:`scene`.
        """
        t = self.template
        rel = {}
        for a in self.devices:
            for b in self.devices:
                if a is not b:
                    R, T = self.relative_pose(a.name, b.name)
                    rel[f"{a.name}->{b.name}"] = {"R": R.tolist(), "T": T.tolist(),
                                                  "angles_deg": matrix_euler(R).tolist(),
                                                  "baseline": float(np.linalg.norm(T))}
        pose = {}
        for d in self.devices:
            R = d.R @ t.R_board
            pose[d.name] = {"R": R.tolist(), "t": (d.R @ t.t_board + d.T).tolist(),
                            "angles_deg": matrix_euler(R).tolist()}
        out = {"format": SIM_RIG_TRUTH_FORMAT, "version": 1, "name": self.name, "reference": self.cameras[0].name,
               "devices": {d.name: d.to_dict() for d in self.devices}, "relative": rel,
               "board": {"cols": t.board_cols, "rows": t.board_rows, "square": t.square, "margin": t.margin,
                         "extent": list(board_extent(t))},
               "pose": pose, "background": {"fixed_in_room": True, "frame": self.cameras[0].name,
                                            "surfaces": t.background.to_dict()["surfaces"]},
               "pairs": [list(p) for p in self.pairs()], "fit_margin_px": self.fit_margin()}
        return to_jsonable(out)


# ------------------------------------------------------------------------------------------------
# presets
# ------------------------------------------------------------------------------------------------

def _pose(angles_deg, center):
    """``(R, T)`` of a device at ``center`` (reference frame, mm) turned by Euler ``angles_deg``."""
    R = euler_matrix(angles_deg)
    return R, -R @ np.asarray(center, float)


def rig_preset(name: str = "two_projectors") -> Rig:
    """A ready rig with the board at :data:`~procam.simulate.RECOMMENDED_POSE` (reference camera frame),
    placed by :meth:`Rig.with_board_pose` so that every device sees it whole.

    ``two_projectors``
        One camera and two projectors side by side whose images overlap on the wall.  Camera ``cam``: the
        paper's (1280x800, f 1539, alpha 1.004, pp (674, 512), division k1 = -3e-8 px^-2), the reference.
        Projector ``left``: the paper's projector (1920x1080, f 2421, alpha 1.002, pp (1013, 1065), no
        distortion) centred at (-250, 40, 60) mm, turned 3 deg towards the middle (Euler (0, -3, 0));
        projector ``right``: a lens-shifted one (f 2421, alpha 1, pp (981, 1166.4), OpenCV k1 = -0.10,
        k2 = 0.015) centred at (250, 40, 60) mm, turned 3 deg towards the middle (Euler (0, 3, 0)).  A
        frontal wall at z = 1500 mm, albedo 0.5, where each image is about 1.2 m wide and they overlap over
        about half of each.
    ``two_cameras``
        One projector between two cameras (a scanner).  Camera ``left``: the paper's camera, the reference;
        projector ``proj``: the paper's projector at the paper's R, T (centre (148.4, 42.9, 105.1) mm);
        camera ``right``: 1280x800, f 1480, alpha 1, pp (650, 395), OpenCV k1 = -0.06, k2 = 0.02,
        centred at (300, 0, 0) mm and turned 20 deg towards the left (Euler (0, 20, 0)).  A frontal wall at
        z = 1200 mm.
    """
    if name not in RIG_PRESETS:
        raise ValueError(f"unknown rig preset {name!r}; choose one of {', '.join(RIG_PRESETS)}")
    return _rig_cached(name)


@functools.lru_cache(maxsize=None)
def _rig_cached(name: str) -> Rig:
    paper = Scene()
    cam = Device("cam" if name == "two_projectors" else "left", "camera", paper.cam_size, paper.K_cam,
                 paper.cam_lens)
    if name == "two_projectors":
        left = Device("left", "projector", paper.proj_size, paper.K_proj, Lens(), *_pose((0, -3, 0), (-250, 40, 60)))
        right = Device("right", "projector", paper.proj_size, _K(2421.0, 1.0, 981.0, 1166.4),
                       Lens("opencv", (-0.10, 0.015, 0.0, 0.0, 0.0)), *_pose((0, 3, 0), (250, 40, 60)))
        rig = Rig((cam,), (left, right), Scene(background=Background.wall(1500.0)), name)
    else:
        proj = Device("proj", "projector", paper.proj_size, paper.K_proj, Lens(), paper.R, paper.T)
        right = Device("right", "camera", (1280, 800), _K(1480.0, 1.0, 650.0, 395.0),
                       Lens("opencv", (-0.06, 0.02, 0.0, 0.0, 0.0)), *_pose((0, 20, 0), (300, 0, 0)))
        rig = Rig((cam, right), (proj,), Scene(background=Background.wall(1200.0)), name)
    return rig.with_board_pose(RECOMMENDED_POSE)
