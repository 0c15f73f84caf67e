"""Rendered captures of a :class:`~procam.simulate.Rig`, written in the rig capture layout.

Each (camera, projector) pair is rendered as its own single-pair scene (:meth:`Rig.scene`: the other
projectors are off, as when the projectors are shown in turn) and written as an ordinary pose folder into a
sub-folder of the rig pose folder (:mod:`procam.capture.rig`), with ``rig.json`` naming the devices and the
rig's ``truth.json`` (:meth:`Rig.truth`) next to them.  Each pair's noise has its own seed (``seed`` plus the
pair's index), so the pairs' images are independent captures of the same board pose.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from ..capture import RIG_MANIFEST, pair_folder_name, prepare_rig_dir, rig_manifest, write_rig_file
from ..io.files import to_jsonable
from .renderer import render, write_capture
from .rig import Rig

__all__ = ["render_rig", "write_rig_capture"]


def render_rig(rig: Rig, order: str = "opencv", seed: int = 0, changes: dict | None = None,
               progress: Callable[[int, int], None] | None = None) -> dict:
    """Render every pair of ``rig``: ``{sub-folder name: (camera, projector, stack, truth)}`` in
    :meth:`Rig.pairs` order (:func:`~procam.simulate.render` of each pair's scene, with ``changes`` to the
    scene such as ``read_noise`` or ``bits``; pair ``i`` with seed ``seed + i``); ``progress(done, total)``
    after each pair."""
    nc, npj = len(rig.cameras), len(rig.projectors)
    out = {}
    pairs = rig.pairs()
    for i, (c, p) in enumerate(pairs):
        sc = rig.scene(c, p)
        if changes:
            sc = sc.replace(**changes)
        stack, truth = render(sc, order=order, seed=seed + i)
        out[pair_folder_name(c, p, nc, npj)] = (c, p, stack, truth)
        if progress is not None:
            progress(i + 1, len(pairs))
    return out


def write_rig_capture(out_dir, rig: Rig, rendered: dict, order: str = "opencv", *, force: bool = False) -> list[Path]:
    """Write :func:`render_rig`'s output as a rig pose folder: ``rig.json``, ``truth.json`` (the rig's truth)
    and one pose folder per pair (:func:`~procam.simulate.write_capture`).  ``out_dir`` must be new, empty or an
    earlier simulator output (``force`` as in :func:`~procam.simulate.write_capture`).  Returns the pairs'
    folders."""
    out = prepare_rig_dir(out_dir, "simulate", force=force, option="OUT_DIR")
    folders = []
    for sub, (_c, _p, stack, truth) in rendered.items():
        write_capture(out / sub, stack, truth, order=order, force=force)
        folders.append(out / sub)
    man = rig_manifest([d.name for d in rig.cameras], [d.name for d in rig.projectors],
                       {sub: [c, p] for sub, (c, p, _, _) in rendered.items()})
    write_rig_file(out, "truth.json", json.dumps(to_jsonable(rig.truth()), indent=1))
    write_rig_file(out, RIG_MANIFEST, json.dumps(man, indent=1))  # last: a folder without it is not a finished rig pose
    return folders
