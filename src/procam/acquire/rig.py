"""Capture a rig pose: one camera, several projectors shown in turn, the board still (``procam capture --rig``).

:func:`capture_rig_pose` runs the one-projector capture session (:func:`procam.acquire.orchestrate.capture_session`)
once per projector, in the order given, each on its own display (a full-screen window there) and into its own
sub-folder of the rig pose folder, named after the projector (:func:`procam.capture.pair_folder_name`); then it
writes ``rig.json`` (:func:`procam.capture.rig_manifest`), so :func:`procam.capture.read_rig_pose` and ``procam
calibrate`` read the folder as one rig pose.  Each session opens and closes the camera again (its settings are
given again each time); only one projector window is open at a time, so the others show nothing.

Virtual (``--virtual``): the simulator's two-projector rig (:func:`virtual_rig`, the ``two_projectors`` preset,
its projectors renamed and its devices resized), each pair's view rendered from the rig's geometry
(:meth:`procam.simulate.Rig.scene`), its truth in the pair's folder and the rig's (:meth:`procam.simulate.Rig.truth`)
in ``truth.json`` next to ``rig.json``.

Assumptions and failure modes: the board and the camera do not move while the projectors take their turns
(nothing can check that here; the rig's calibration shows it as disagreement between the pairs).  A failed
projector stops the rig pose with its one-line error; the pairs already captured stay, but ``rig.json`` is not
written (the folder is then no rig pose: capture it again into a new folder).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..capture import RIG_MANIFEST, check_out_dir, pair_folder_name, rig_manifest, write_rig_file
from ..capture.rig import check_device_name
from .orchestrate import Devices, Hooks, capture_session
from .session import CaptureOptions, CaptureResult

__all__ = ["RigProjector", "parse_rig_projectors", "virtual_rig", "capture_rig_pose"]


@dataclass(frozen=True)
class RigProjector:
    """One projector of a rig capture: its ``name`` (a device name) and ``display`` (None: the session's
    default, the display that is not the primary)."""

    name: str
    display: int | None = None


def parse_rig_projectors(text: str) -> tuple[RigProjector, ...]:
    """``"left=1,right=2"`` (``NAME=DISPLAY``, or a bare ``NAME`` with ``--virtual``) as :class:`RigProjector`;
    ``ValueError`` with one line saying what is wrong."""
    out = []
    for item in str(text).split(","):
        name, eq, disp = item.strip().partition("=")
        name = check_device_name(name.strip(), "projector name")
        display = None
        if eq:
            try:
                display = int(disp.strip())
            except ValueError:
                raise ValueError(f"projector {name!r}: display {disp.strip()!r} is not a display index "
                                 "(NAME=DISPLAY, e.g. left=1)") from None
            if not 0 <= display <= 64:
                raise ValueError(f"projector {name!r}: display {display} must be an index from 0 to 64")
        out.append(RigProjector(name, display))
    names = [p.name for p in out]
    if len(out) < 2:
        raise ValueError(f"a rig has at least two projectors (NAME=DISPLAY,NAME=DISPLAY), got {len(out)}")
    if len(set(names)) != len(names):
        raise ValueError(f"projector names must be unique, got {', '.join(names)}")
    displays = [p.display for p in out if p.display is not None]
    if len(set(displays)) != len(displays):
        raise ValueError("two projectors on one display: give each projector its own display")
    return tuple(out)


def _scaled(device, size):
    """The simulator's ``device`` resized to ``size`` (same field of view): K scaled per axis, a division
    lens's coefficients by the width's scale (px^-2, px^-4) and its centre with it."""
    from ..simulate.lens import Lens

    sx, sy = size[0] / device.size[0], size[1] / device.size[1]
    K = np.diag([sx, sy, 1.0]) @ np.asarray(device.K)
    lens = device.lens
    if lens.model == "division":
        k = tuple(c / sx ** (2 * (j + 1)) for j, c in enumerate(lens.coeffs))
        centre = None if lens.center is None else (lens.center[0] * sx, lens.center[1] * sy)
        lens = Lens("division", k, centre)
    return dataclasses.replace(device, size=tuple(size), K=K, lens=lens)


def virtual_rig(names=("left", "right"), camera: str = "cam", proj_size=None, cam_size=None):
    """The simulator's ``two_projectors`` rig (:func:`procam.simulate.rig_preset`) with its camera named
    ``camera`` and its projectors ``names`` (two), resized to ``proj_size`` / ``cam_size`` ((width, height);
    None: the preset's 1920x1080 and 1280x800), the board at the preset's pose."""
    from .. import simulate

    rig = simulate.rig_preset("two_projectors")
    names = tuple(names)
    if len(names) != len(rig.projectors):
        raise ValueError(f"the virtual rig has {len(rig.projectors)} projectors; name {len(rig.projectors)}, "
                         f"got {len(names)}")
    cam = rig.cameras[0]
    cam = _scaled(cam, cam_size) if cam_size else cam
    projs = tuple(_scaled(p, proj_size) if proj_size else p for p in rig.projectors)
    projs = tuple(dataclasses.replace(p, name=n) for p, n in zip(projs, names))
    return dataclasses.replace(rig, cameras=(dataclasses.replace(cam, name=camera),), projectors=projs,
                               name="virtual")


def capture_rig_pose(out_dir, projectors, rig: Devices, options: CaptureOptions, *, camera: str = "cam", board=None,
                     hooks: Hooks | None = None, simulated=None,
                     announce: Callable[[int, int, RigProjector], None] | None = None) -> list[CaptureResult]:
    """Capture one rig pose (module docstring).

    Parameters
    ----------
    out_dir : the rig pose folder to create (must not exist, or be empty).
    projectors : :class:`RigProjector` sequence, in the order they are shown.
    rig : the session's devices (:class:`~procam.acquire.orchestrate.Devices`); each projector's session gets its
        ``display`` (and, virtual, the scene of its pair and the seed ``rig.seed + i``).
    options : :class:`~procam.acquire.session.CaptureOptions` of every projector's sequence.
    camera : the camera's device name in ``rig.json``.
    board : :class:`procam.board.Board` for each pair's instant verdict, or None.
    hooks : :class:`~procam.acquire.orchestrate.Hooks` of every session.
    simulated : virtual: the :class:`procam.simulate.Rig` to render (default :func:`virtual_rig` of the
        projectors' names, resized to ``rig.proj_size`` and ``rig.cam_size``).
    announce : ``announce(i, n, projector)`` before projector ``i`` of ``n`` takes its turn.

    Returns
    -------
    list of :class:`~procam.acquire.session.CaptureResult`, one per projector.
    """
    from ..io.files import to_jsonable

    projectors = tuple(projectors)
    names = [check_device_name(p.name, "projector name") for p in projectors]
    check_device_name(camera, "camera name")
    manifest = rig_manifest([camera], names)  # the names' checks, before anything is written
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    if rig.virtual:
        simulated = simulated or virtual_rig(names, camera, rig.proj_size, rig.cam_size)
        if [p.name for p in simulated.projectors] != names or simulated.cameras[0].name != camera:
            raise ValueError(f"the simulated rig's devices ({[d.name for d in simulated.devices]}) are not the "
                             f"camera {camera!r} and projectors {names}")
    results = []
    for i, p in enumerate(projectors):
        if announce is not None:
            announce(i, len(projectors), p)
        sub = out_dir / pair_folder_name(camera, p.name, 1, len(projectors))
        one = dataclasses.replace(rig, display=p.display, seed=rig.seed + i)
        if rig.virtual:
            scene = simulated.scene(camera, p.name)
            one = dataclasses.replace(one, scene=scene, proj_size=tuple(scene.proj_size))
        results += capture_session(sub, 1, one, options, board=board, hooks=hooks)
    if rig.virtual:
        write_rig_file(out_dir, "truth.json", json.dumps(to_jsonable(simulated.truth()), indent=1))
    write_rig_file(out_dir, RIG_MANIFEST, json.dumps(manifest, indent=1))
    return results
