"""Calibrate a rig: every camera and projector in the reference camera's frame.

* **One rig pose** (single-pose): each (camera, projector) pair by the single-pose method
  (:func:`procam.single_pose.calibrate`), in the rig pose's pair order.  Every pair estimates the camera with
  its projector (a camera taken from an earlier pair as exact would leave its error out of the projector's
  numbers and ``±``); the rig reports the camera of its first pair, and each projector its own verdict.  Device
  poses are composed along
  the pairs from the reference camera; their std by the delta method from the pairs' std, **taken as
  independent** (the pairs share the camera's corners, so the ± of a projector-to-projector pose is an
  approximation).
* **Several rig poses** (multi-pose): each pair by the multi-pose method (:func:`procam.multi_pose.calibrate`,
  its distortion model choice), which initialises every device's intrinsics (from the first pair that has it),
  the device poses (composed along the pairs) and the board poses (the reference camera's); then the joint
  refinement of everything (:func:`procam.rig.joint.refine_rig`).  The std of every intrinsic and relative pose
  comes from its full covariance (the ± assumes the model right and each device's corner noise independent
  and Gaussian with the sigma of its residuals).

Failure modes: a rig pose without a pair the others have, a device no pair links to the reference camera, or a
pair that cannot be calibrated are :class:`~procam.errors.CalibrationError` naming them; weak or degenerate
devices keep their result with the verdict and its reasons.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .. import models
from .. import uncertainty as unc
from ..calibration import Calibration, Device, Distortion
from ..errors import CalibrationError
from ..stats import rms
from ..calibration import RigCalibration, RigDevice, relative_poses

__all__ = ["RigPoseViews", "calibrate_rig", "rig_views_from_folders", "SINGLE_UNCERTAINTY", "MULTI_UNCERTAINTY"]

SINGLE_UNCERTAINTY = ("std: 1 sigma by the delta method from each pair's single-pose std (the pair's Jacobian, its "
                      "assumptions), the pairs' errors taken as independent (they share the camera's corners: an "
                      "approximation for a pose composed of two pairs)")
MULTI_UNCERTAINTY = ("std: 1 sigma from the joint refinement's Gauss-Newton covariance over every device and pose, "
                     "assuming the model right and each device's corner noise independent and Gaussian with the "
                     "sigma of its residuals; relative poses by the delta method through the full covariance")

_ORDER = ("good", "weak", "degenerate", "failed")


def _worst(levels) -> str:
    levels = [v if v in _ORDER else "failed" for v in levels]
    return max(levels, key=_ORDER.index) if levels else "good"


@dataclass(frozen=True)
class RigPoseViews:
    """One rig pose: its ``name``, ``cameras`` and ``projectors`` (names, the reference first) and ``views``
    ``{(camera, projector): View}``, in the pose's pair order."""

    name: str
    cameras: tuple
    projectors: tuple
    views: dict


def rig_views_from_folders(folders: Sequence, board, projector=None, order=None, *, options=None, step=None,
                           progress=None) -> list[RigPoseViews]:
    """The :class:`RigPoseViews` of rig pose folders (:func:`procam.capture.read_rig_pose`; each pair's folder by
    :func:`procam.pipeline.view_from_folder`).  Every pose must name the same cameras and projectors, and no pair
folder may be another's capture (:func:`procam.capture.distinct.refuse_repeats`).
    ``progress(done, total, folder)`` after each pair's folder."""
    from .. import capture, pipeline

    from ..capture.distinct import refuse_repeats

    refuse_repeats(folders, "rig pose folder", "give each rig pose once")
    rigs = [capture.read_rig_pose(f) for f in folders]
    refuse_repeats([p.folder for r in rigs for p in r.pairs], "pair folder",
                   "each rig pose needs its own capture of each pair")
    first = rigs[0]
    for r in rigs[1:]:
        if (r.cameras, r.projectors) != (first.cameras, first.projectors):
            raise CalibrationError(f"{r.folder}: devices {list(r.cameras + r.projectors)} differ from "
                                   f"{first.folder}'s {list(first.cameras + first.projectors)}; every rig pose must "
                                   "name the same cameras and projectors")
    total = sum(len(r.pairs) for r in rigs)
    opts = {} if options is None else {"options": options}
    out, done = [], 0
    for r in rigs:
        views = {}
        for p in r.pairs:
            view, _ = pipeline.view_from_folder(p.folder, board, projector, order, step=step, keep_maps=False, **opts)
            views[(p.camera, p.projector)] = view
            done += 1
            if progress is not None:
                progress(done, total, str(p.folder))
        out.append(RigPoseViews(str(r.folder), r.cameras, r.projectors, views))
    return out


def calibrate_rig(poses: Sequence[RigPoseViews], *, method: str | None = None, camera=None, background=None,
                  cam_dist: str = "auto", proj_dist: str = "auto", refine: bool = True) -> RigCalibration:
    """Calibrate a rig from its poses (module docstring).

    Parameters
    ----------
    poses : :class:`RigPoseViews`, one per board pose.
    method : ``"single-pose"``, ``"multi-pose"`` or None (single-pose for one pose, multi-pose for several).
    camera, background : single-pose options (:class:`procam.single_pose.CameraOptions`,
        :class:`procam.single_pose.background.BackgroundOptions`).
    cam_dist, proj_dist : multi-pose distortion models of the per-pair initialisation (``"auto"``: the richest
        the poses determine); the joint refinement keeps each device's.
    refine : multi-pose: the joint refinement (without it, the per-pair results composed, std as single-pose's).

    Returns
    -------
    :class:`~procam.calibration.RigCalibration`
    """
    poses = list(poses)
    if not poses:
        raise CalibrationError("a rig calibration needs at least one rig pose")
    from .. import method as calibration_method

    method = calibration_method.choose(len(poses), method)
    if method not in ("single-pose", "multi-pose"):
        raise CalibrationError(f"a rig is calibrated single-pose or multi-pose, not {method!r}")
    calibration_method.check(method, len(poses), unit="rig pose")
    if method == "single-pose":
        return _single(poses[0], camera, background)
    return _multi(poses, cam_dist, proj_dist, refine)


# ------------------------------------------------------------------------------------------------
# device poses along the pairs
# ------------------------------------------------------------------------------------------------

def _tree(ref: str, names, edges) -> list:
    """The edges (indices into ``edges`` of ``(camera, projector, ...)``) that reach every device from ``ref``,
    in the order they are applied; :class:`CalibrationError` naming a device no pair reaches."""
    known, used = {ref}, []
    grew = True
    while grew:
        grew = False
        for k, e in enumerate(edges):
            c, p = e[0], e[1]
            if (c in known) != (p in known):
                known.add(p if c in known else c)
                used.append(k)
                grew = True
    missing = [n for n in names if n not in known]
    if missing:
        raise CalibrationError(f"no pair links {', '.join(missing)} to the reference camera {ref!r}; capture a pair "
                               "that does")
    return used


def _compose(ref: str, edges, tree, x) -> dict:
    """``{name: (R, T)}`` reference -> device from edge parameters ``x`` = per tree edge (Euler deg (3), T (3))
    of ``camera -> projector``."""
    P = {ref: (np.eye(3), np.zeros(3))}
    for n, k in enumerate(tree):
        c, p = edges[k][0], edges[k][1]
        q = x[6 * n:6 * n + 6]
        Re = models.euler_to_matrix(*np.radians(q[:3]))
        Te = q[3:]
        if c in P:
            Rc, Tc = P[c]
            P[p] = (Re @ Rc, Re @ Tc + Te)
        else:
            Rp, Tp = P[p]
            P[c] = (Re.T @ Rp, Re.T @ (Tp - Te))
    return P


def _edge_relatives(ref, names, edges, tree):
    """Relative poses from per-pair results ``edges`` = (camera, projector, R, T, std_euler, std_T), the pairs
    independent."""
    x = np.concatenate([np.r_[models.euler_deg(edges[k][2]), edges[k][3]] for k in tree]) if tree else np.zeros(0)
    sd = np.concatenate([np.r_[edges[k][4], edges[k][5]] for k in tree]) if tree else np.zeros(0)
    cov = np.diag(np.asarray(sd, float) ** 2)
    return _compose(ref, edges, tree, x), relative_poses(names, x, cov, lambda q: _compose(ref, edges, tree, q))


def _std3(std: dict, key: str) -> np.ndarray:
    v = std.get(key)
    return np.full(3, np.inf) if v is None else np.asarray(v, float).reshape(3)


# ------------------------------------------------------------------------------------------------
# single pose
# ------------------------------------------------------------------------------------------------

def _single(pose: RigPoseViews, camera, background) -> RigCalibration:
    from .. import single_pose

    camera = single_pose.CameraOptions() if camera is None else camera
    # every pair with its own estimate of the camera: the camera's error then reaches each projector's numbers and
    # their ± (a camera taken from the first pair as exact would put it in neither)
    pairs = {}
    for (c, p), view in pose.views.items():
        try:
            cal = single_pose.calibrate(view, camera=camera, background=background)
        except CalibrationError as e:
            raise CalibrationError(f"pair ({c}, {p}) of {pose.name}: {e}") from None
        pairs[(c, p)] = cal
    names = list(pose.cameras) + list(pose.projectors)
    edges = [(c, p, cal.R, cal.T, _std3(cal.std, "R_euler_deg"), _std3(cal.std, "T")) for (c, p), cal in pairs.items()]
    tree = _tree(pose.cameras[0], names, edges)
    P, rel = _edge_relatives(pose.cameras[0], names, edges, tree)
    devices = {}
    for (c, p), cal in pairs.items():  # each device's intrinsics and verdict from the first pair that has it
        s = cal.std
        if c not in devices:
            devices[c] = RigDevice(c, "camera", cal.camera, *P[c],
                                   {"f": s.get("f_c"), "fy": s.get("fy_c"), "u0": s.get("u0c"), "v0": s.get("v0c")},
                                   cal.verdict, tuple(cal.verdict_reasons))
        if p not in devices:
            devices[p] = RigDevice(p, "projector", cal.projector, *P[p],
                                   {"f": s.get("f_p"), "fy": s.get("fy_p"), "u0": s.get("u0p"), "v0": s.get("v0p")},
                                   cal.verdict, tuple(cal.verdict_reasons))
    return _result("single-pose", pose.cameras, pose.projectors, devices, rel,
                   {f"{c}/{p}": cal for (c, p), cal in pairs.items()}, (pose.name,), SINGLE_UNCERTAINTY,
                   {"pair_order": [f"{c}/{p}" for c, p in pairs]}, [])


def _result(method, cams, projs, devices, rel, pairs, pose_names, note, info, warnings) -> RigCalibration:
    cameras = tuple(devices[c] for c in cams)
    projectors = tuple(devices[p] for p in projs)
    worst = _worst([d.verdict for d in cameras + projectors])
    reasons = tuple(f"{d.name}: {r}" for d in cameras + projectors for r in d.verdict_reasons)
    return RigCalibration(method, cameras, projectors, rel, pairs, tuple(pose_names), note, info,
                          tuple(warnings) + reasons, worst, reasons)


# ------------------------------------------------------------------------------------------------
# several poses
# ------------------------------------------------------------------------------------------------

def _multi(poses, cam_dist, proj_dist, refine) -> RigCalibration:
    from .. import multi_pose
    from .joint import JointDevice, Observation, refine_rig

    keys = list(poses[0].views)
    for pv in poses[1:]:
        if set(pv.views) != set(keys):
            raise CalibrationError(f"{pv.name}: pairs {sorted(pv.views)} differ from {poses[0].name}'s {sorted(keys)}; "
                                   "every rig pose must hold the same pairs")
    init = {}
    for c, p in keys:
        try:
            init[(c, p)] = multi_pose.calibrate([pv.views[(c, p)] for pv in poses], cam_dist=cam_dist,
                                                proj_dist=proj_dist)
        except CalibrationError as e:
            raise CalibrationError(f"pair ({c}, {p}): {e}") from None
    ref = poses[0].cameras[0]
    cams, projs = poses[0].cameras, poses[0].projectors
    names = list(cams) + list(projs)
    edges = [(c, p, cal.R, cal.T, _std3(cal.std, "R_euler_deg"), _std3(cal.std, "T")) for (c, p), cal in init.items()]
    tree = _tree(ref, names, edges)
    P0, rel0 = _edge_relatives(ref, names, edges, tree)
    # each device's start, model and observations: from the first pair that has it
    owner = {}
    for c, p in keys:
        owner.setdefault(c, ((c, p), "camera"))
        owner.setdefault(p, ((c, p), "projector"))
    if not refine:
        return _from_pairs(poses, init, owner, P0, rel0, cams, projs)
    jd, sig = [], []
    for n in names:
        key, role = owner[n]
        cal = init[key]
        dev = cal.camera if role == "camera" else cal.projector
        model = cal.info["cam_dist_model" if role == "camera" else "proj_dist_model"]
        jd.append(JointDevice(n, dev.K, np.asarray(dev.distortion.coeffs, float), model, *P0[n]))
        sig.append(cal.cam_rms if role == "camera" else cal.proj_rms)
    refpair = next(k for k in keys if k[0] == ref)
    board_r = [models.matrix_to_rvec(np.asarray(q["R_cam"], float)) for q in init[refpair].poses]
    board_t = [np.asarray(q["t_cam"], float) for q in init[refpair].poses]
    obs = []
    for j, pv in enumerate(poses):
        for i, n in enumerate(names):
            key, role = owner[n]
            v = pv.views[key]
            m = np.isfinite(v.cam_pts).all(1) if role == "camera" else v.valid
            obs.append(Observation(i, j, v.obj_pts[m], (v.cam_pts if role == "camera" else v.proj_pts)[m]))
    res = refine_rig(jd, obs, board_r, board_t, sigma=np.nan_to_num(np.asarray(sig, float), nan=1.0))
    return _from_joint(poses, init, owner, names, cams, projs, res)


def _pair_calibration(c, p, dc, dp, views, poses_R, poses_t, Rc, Tc, Rp, Tp, std, info, verdict, reasons):
    """The pair (c, p) as an ordinary multi-pose :class:`Calibration` in camera ``c``'s frame."""
    R = Rp @ Rc.T
    T = Tp - R @ Tc
    cam_res, proj_res, pose_list = [], [], []
    for v, Rb, tb in zip(views, poses_R, poses_t):
        R_cb, t_cb = Rc @ Rb, Rc @ tb + Tc
        R_pb, t_pb = Rp @ Rb, Rp @ tb + Tp
        m = v.valid
        rc = v.cam_pts[m] - dc.project(R_cb, t_cb, v.obj_pts[m])
        rp = v.proj_pts[m] - dp.project(R_pb, t_pb, v.obj_pts[m])
        cam_res.append(rc)
        proj_res.append(rp)
        pose_list.append({"name": v.name, "n_corners": int(m.sum()),
                          "camera_angles_deg": models.board_angles_deg(R_cb, t_cb).tolist(),
                          "projector_angles_deg": models.board_angles_deg(R_pb, t_pb).tolist(),
                          "R_cam": R_cb.tolist(), "t_cam": t_cb.tolist(), "cam_rms": rms([rc]),
                          "proj_rms": rms([rp]), "stereo_rms": rms([rc, rp])})
    return Calibration(camera=dc, projector=dp, R=R, T=T, method="multi-pose", cam_rms=rms(cam_res),
                       proj_rms=rms(proj_res), stereo_rms=rms(cam_res + proj_res), std=std, poses=tuple(pose_list),
                       views=tuple(views), warnings=tuple(reasons), info=info, verdict=verdict,
                       verdict_reasons=tuple(reasons))


def _from_pairs(poses, init, owner, P, rel, cams, projs) -> RigCalibration:
    """Without the joint refinement: each device from its first pair, poses composed along the pairs."""
    devices = {}
    for n, (key, role) in owner.items():
        cal = init[key]
        dev = cal.camera if role == "camera" else cal.projector
        sfx = "c" if role == "camera" else "p"
        s = cal.std
        devices[n] = RigDevice(n, role, dev, *P[n], {"f": s.get(f"f_{sfx}"), "fy": s.get(f"fy_{sfx}"),
                                                     "u0": s.get(f"u0{sfx}"), "v0": s.get(f"v0{sfx}"),
                                                     "dist": s.get(f"{'cam' if sfx == 'c' else 'proj'}_dist")},
                               cal.verdict, tuple(cal.verdict_reasons))
    return _result("multi-pose", cams, projs, devices, rel, {f"{c}/{p}": cal for (c, p), cal in init.items()},
                   [pv.name for pv in poses], SINGLE_UNCERTAINTY.replace("single-pose", "multi-pose"),
                   {"refined": False}, ["no joint refinement: each device from its first pair, the pairs' poses "
                                        "composed"])


def _from_joint(poses, init, owner, names, cams, projs, res) -> RigCalibration:
    from ..multi_pose import undetermined_distortion

    sd = unc.std(res.cov)
    finite = bool(np.all(np.isfinite(res.cov)))
    warnings = [] if res.status > 0 else ["joint refinement stopped at its evaluation limit; the result may not be "
                                          "converged"]
    devices, cal_dev, dstd = {}, {}, {}
    for i, n in enumerate(names):
        role = owner[n][1]
        idx = res.intr_index[i]
        dist_sd = np.zeros(len(res.dist[i]))
        dist_sd[list(res.free[i])] = sd[idx[4:]]
        dstd[n] = {"f": float(sd[idx[0]]), "fy": float(sd[idx[1]]), "u0": float(sd[idx[2]]), "v0": float(sd[idx[3]]),
                   "dist": dist_sd.tolist()}
        dev = Device(res.K[i], _owner_size(init, owner[n]), Distortion("opencv", coeffs=tuple(map(float, res.dist[i]))))
        cal_dev[n] = dev
        pts = [(pv.views[owner[n][0]].cam_pts if role == "camera" else pv.views[owner[n][0]].proj_pts) for pv in poses]
        msgs, _ = undetermined_distortion(dev.K, res.dist[i], dist_sd, dev.image_size,
                                          init[owner[n][0]].info[f"{'cam' if role == 'camera' else 'proj'}_dist_model"],
                                          n, "--cam-dist" if role == "camera" else "--proj-dist", pts)
        if not finite:
            verdict, reasons = "degenerate", ("the rig's poses do not determine every parameter (singular "
                                              "covariance); add poses that tilt the board differently",)
        else:
            verdict, reasons = ("weak" if msgs or warnings else "good"), tuple(msgs + warnings)
        devices[n] = RigDevice(n, role, dev, res.R[i], res.T[i], dstd[n], verdict, reasons)

    def pose_fn(q):
        out = {}
        for i, n in enumerate(names):
            pi = res.pose_index[i]
            out[n] = (np.eye(3), np.zeros(3)) if pi is None else (models.rvec_to_matrix(q[pi[:3]]), q[pi[3:]])
        return out

    # the relative poses need only the device poses' covariance block
    pidx = [k for i in range(len(names)) if res.pose_index[i] is not None for k in res.pose_index[i]]

    def sub_pose_fn(q):
        full = res.x.copy()
        full[pidx] = q
        return pose_fn(full)

    rel = relative_poses(names, res.x[pidx], res.cov[np.ix_(pidx, pidx)], sub_pose_fn)
    pairs = {}
    for (c, p) in init:
        r = rel[f"{c}->{p}"]
        std = {"f_c": dstd[c]["f"], "fy_c": dstd[c]["fy"], "u0c": dstd[c]["u0"], "v0c": dstd[c]["v0"],
               "cam_dist": dstd[c]["dist"], "f_p": dstd[p]["f"], "fy_p": dstd[p]["fy"], "u0p": dstd[p]["u0"],
               "v0p": dstd[p]["v0"], "proj_dist": dstd[p]["dist"], "R_euler_deg": np.asarray(r.std_angles_deg).tolist(),
               "T": np.asarray(r.std_T).tolist()}
        info = {"rig_joint": True, "cam_dist_model": init[owner[c][0]].info["cam_dist_model"],
                "proj_dist_model": init[owner[p][0]].info["proj_dist_model"], "refined": True,
                "pose_names": [pv.name for pv in poses]}
        reasons = [f"{d}: {m}" for d in (c, p) for m in devices[d].verdict_reasons]
        verdict = _worst([devices[c].verdict, devices[p].verdict])
        pairs[f"{c}/{p}"] = _pair_calibration(c, p, cal_dev[c], cal_dev[p], [pv.views[(c, p)] for pv in poses],
                                              res.board_R, res.board_t, res.R[names.index(c)], res.T[names.index(c)],
                                              res.R[names.index(p)], res.T[names.index(p)], std, info, verdict,
                                              reasons)
    info = {"refined": True, "status": res.status, "nfev": res.nfev, "cost": res.cost,
            "sigma_px": {n: float(s) for n, s in zip(names, res.sigma)},
            "dist_models": {n: init[owner[n][0]].info[f"{'cam' if owner[n][1] == 'camera' else 'proj'}_dist_model"]
                            for n in names},
            "board_poses": [{"name": pv.name, "R": R.tolist(), "t": t.tolist()}
                            for pv, R, t in zip(poses, res.board_R, res.board_t)]}
    return _result("multi-pose", cams, projs, devices, rel, pairs, [pv.name for pv in poses], MULTI_UNCERTAINTY, info,
                   warnings)


def _owner_size(init, own) -> tuple:
    key, role = own
    cal = init[key]
    return tuple(cal.camera.image_size if role == "camera" else cal.projector.image_size)

