"""Simulated rigs for the rig tests: the presets' board turned to well-conditioned poses, and the corner fast
path's views of every pair (no rendering)."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

#: Board angles (reference camera frame) of the three poses: tilted 15-25 degrees in different directions.
ANGLES = ((20.0, 12.0, 0.0), (-16.0, 18.0, 8.0), (10.0, -18.0, -6.0))


@functools.lru_cache(maxsize=None)
def posed(name: str, angles: tuple):
    """The preset rig with the board turned to ``angles`` about its centre and moved back along its line of
    sight until every device sees it with a margin of 15 px (cheaper than Rig.with_board_pose's search)."""
    from procam import simulate as sim

    rig = sim.rig_preset(name)
    t0 = np.asarray(rig.template.t_board, float)
    for scale in np.arange(1.0, 1.8, 0.05):
        r = dataclasses.replace(rig, template=rig.template.replace(R_board=sim.euler_matrix(angles), t_board=t0 * scale))
        if r.fit_margin() > 15.0:
            return r
    raise AssertionError(f"no placement for {angles}")


def fast_views(name: str, n_poses: int = 3, sigma_cam: float = 0.02, sigma_proj: float = 0.03, seed: int = 0,
               angles=ANGLES):
    """(rig at the first pose, [RigPoseViews]) from the corner fast path (exact corners + Gaussian noise; each pair
    of each pose its own draw, as separate captures)."""
    from procam import simulate as sim
    from procam.rig import RigPoseViews
    from procam.view import View

    out, first = [], None
    for j, a in enumerate(angles[:n_poses]):
        r = posed(name, a)
        first = first or r
        views = {}
        for i, (c, p) in enumerate(r.pairs()):
            sc = r.scene(c, p)
            obj, cam, proj = sim.correspondences(sc, sigma_cam, sigma_proj, seed=seed + 10 * j + i)
            views[(c, p)] = View(obj, cam, proj, f"pose{j + 1}", sc.cam_size, sc.proj_size)
        out.append(RigPoseViews(f"pose{j + 1}", tuple(d.name for d in r.cameras), tuple(d.name for d in r.projectors),
                                views))
    return first, out


@functools.lru_cache(maxsize=None)
def bare_wall():
    """The two-projector rig with the board moved out of every view: the projectors light the bare wall."""
    from procam import simulate as sim

    rig = sim.rig_preset("two_projectors")
    t = np.asarray(rig.template.t_board, float)
    return dataclasses.replace(rig, template=rig.template.replace(t_board=(t[0] + 8000.0, t[1], t[2])))


def fake_rig_folders(monkeypatch, root, name="two_projectors", n_poses=3):
    """Rig pose folders whose pairs' views are the fast path's (pipeline.view_from_folder patched)."""
    import json
    from pathlib import Path

    from procam import capture, pipeline
    from procam.view import View

    rig, poses = fast_views(name, n_poses)
    by_path, folders = {}, []
    for pv in poses:
        f = Path(root) / pv.name
        man = capture.rig_manifest(pv.cameras, pv.projectors)
        for sub, (c, p) in man["pairs"].items():
            (f / sub).mkdir(parents=True)
            (f / sub / "patterns.json").write_text("{}")
            by_path[(f / sub).resolve()] = pv.views[(c, p)]
        (f / "rig.json").write_text(json.dumps(man))
        folders.append(f)

    def fake(folder, board, projector=None, order=None, **kw):
        v = by_path[Path(folder).resolve()]
        return View(v.obj_pts, v.cam_pts, v.proj_pts, str(folder), v.cam_size, v.proj_size, board=board), None

    monkeypatch.setattr(pipeline, "view_from_folder", fake)
    return rig, folders
