"""The exact ground truth of a :class:`~procam.simulate.Scene`, and the fast corner path.

* :func:`corner_truth` - the board's corners in the board frame, the camera (ideal and distorted)
  and the projector panel (ideal and through its lens), and whether each is seen and lit.
* :func:`truth` - everything known about the scene, JSON-able (``truth.json`` of a capture).
* :func:`truth_calibration` - the scene's devices as a :class:`procam.calibration.Calibration`, the
  result a perfect calibration would return; refuses (or, asked to, flags) a lens that procam's
  distortion models do not describe exactly.
* :func:`correspondences` - the fast path: exact corners plus Gaussian noise, no images.

The dense fast path (projector coordinates at every camera pixel) is
:func:`procam.simulate.true_projector_maps`.
"""

from __future__ import annotations

import numpy as np

from ..io.files import to_jsonable
from ..io.formats import SIM_TRUTH_FORMAT
from .lens import matrix_euler, project
from .poses import fit_margin
from .scene import Scene, board_corners, board_extent

__all__ = ["corner_truth", "truth", "truth_calibration", "correspondences"]


def _pose_dict(R, t):
    return {"R": np.asarray(R).tolist(), "t": np.asarray(t).tolist(),
            "angles_deg": matrix_euler(R).tolist()}


def corner_truth(scene: Scene) -> dict[str, np.ndarray]:
    """Exact corners, order ``k = j*cols + i``.

    Returns
    -------
    dict with ``board`` (N, 3) board frame, mm; ``camera_undistorted``, ``camera_distorted`` (N, 2) px
    (ideal pinhole, and as the camera records it); ``projector_undistorted`` (N, 2) (the projector's ideal
    pinhole) and ``projector`` (N, 2), the panel pixel that lights the corner (through the projector's
    lens; the two are equal for an ideal projector); ``hidden`` (N,) bool: a surface of the background lies
    between the corner and the camera; ``shadowed`` (N,) bool: one lies between it and the projector's
    centre; ``visible`` = neither (always, for the default wall behind the board).
    """
    B = board_corners(scene)
    Xc = B @ scene.R_board.T + scene.t_board
    cam_u = project(scene.K_cam, Xc)
    cam_d = scene.cam_lens.distort(scene.K_cam, cam_u)
    Xp = Xc @ scene.R.T + scene.T
    proj_u = project(scene.K_proj, Xp)
    proj = proj_u if scene.proj_distortion == "none" else scene.proj_lens.project(scene.K_proj, Xp)
    bg = scene.surfaces()
    hidden = bg.blocks(np.zeros(3), Xc)
    shadowed = bg.blocks(Xc, scene.proj_center_cam - Xc)
    return {"board": B, "camera_distorted": cam_d, "camera_undistorted": cam_u, "projector": proj,
            "projector_undistorted": proj_u, "hidden": hidden, "shadowed": shadowed, "visible": ~(hidden | shadowed)}


def _background_dict(scene: Scene) -> dict:
    if scene.background is None:
        return {"fixed_in_room": False, "frame": "camera", "surfaces": scene.surfaces().to_dict()["surfaces"],
                "definition": "the default wall, wall_offset mm behind the board centre along camera z: it "
                              "moves with the board"}
    return {"fixed_in_room": True, "frame": "camera", "surfaces": scene.background.to_dict()["surfaces"],
            "definition": "planes (the devices on one side of each) and solids, fixed in the room"}


def _scene_params(scene: Scene) -> dict:
    Kc, Kp = scene.K_cam, scene.K_proj
    cam = {"size": list(scene.cam_size), "K": Kc.tolist(), "f": Kc[0, 0], "alpha": Kc[1, 1] / Kc[0, 0],
           "u0": Kc[0, 2], "v0": Kc[1, 2], "distortion": scene.cam_lens.to_dict(Kc)}
    proj = {"size": list(scene.proj_size), "K": Kp.tolist(), "f": Kp[0, 0], "alpha": Kp[1, 1] / Kp[0, 0],
            "u0": Kp[0, 2], "v0": Kp[1, 2], "distortion": scene.proj_lens.to_dict(Kp)}
    ext = {"R": scene.R.tolist(), "T": scene.T.tolist(), "angles_deg": matrix_euler(scene.R).tolist(),
           "baseline": float(np.linalg.norm(scene.T)), "definition": "x_p = R x_c + T"}
    board = {"cols": scene.board_cols, "rows": scene.board_rows, "square": scene.square,
             "margin": scene.margin, "extent": list(board_extent(scene)),
             "albedo_white": scene.albedo_white, "albedo_black": scene.albedo_black}
    if scene.board_grain:      # only when set: the truth of a uniform print stays what it was
        board["grain"] = scene.board_grain
    wall = None
    if scene.background is None:
        wall = {"normal": scene.wall_normal.tolist(), "offset": scene.wall_offset,
                "point": (scene.t_board + scene.wall_offset * np.array([0, 0, 1.0])).tolist(),
                "albedo": scene.albedo_wall}
    photo = {k: getattr(scene, k) for k in ("gain", "ambient", "proj_black", "proj_gamma", "proj_defocus",
                                            "cam_blur", "cam_vignetting", "proj_vignetting", "full_well",
                                            "read_noise", "gamma", "bits", "supersample")}
    return {"camera": cam, "projector": proj, "extrinsics": ext, "board": board, "wall": wall,
            "background": _background_dict(scene), "photometry": photo}


def truth(scene: Scene) -> dict:
    """Everything known about the scene, JSON-able (lists, floats; NaN written as null).

    Keys: ``format``, ``name``, ``camera``, ``projector`` (each with its ``distortion``:
    :meth:`procam.simulate.Lens.to_dict`, ``describable`` false for a lens procam's models do not hold
    exactly), ``extrinsics``, ``board``, ``wall`` (the default wall; null with a fixed background),
    ``background`` (``fixed_in_room`` and its ``surfaces``, camera frame), ``photometry``, ``corners``
    (:func:`corner_truth`), ``pose`` (``camera`` / ``projector``: ``R``, ``t``, ``angles_deg`` =
    (psi, nu, phi) of board -> device), ``fit_margin_px`` (:func:`fit_margin`) and ``canonical_order``
    (True when corner 0 is the top-left corner in the camera image and the index runs right then down,
    the order a detector canonicalises to; False e.g. for |phi| near 180 deg).
    """
    d = {"format": SIM_TRUTH_FORMAT, "version": 1, "name": scene.name}
    d.update(_scene_params(scene))
    d["corners"] = corner_truth(scene)
    d["pose"] = {"camera": _pose_dict(scene.R_board, scene.t_board),
                 "projector": _pose_dict(scene.R_board_proj, scene.t_board_proj)}
    d["fit_margin_px"] = fit_margin(scene)
    cam = d["corners"]["camera_distorted"]
    n, cols = len(cam), scene.board_cols
    d["canonical_order"] = bool(np.all(np.isfinite(cam)) and np.argmin(cam.sum(axis=1)) == 0
                                and cam[1, 0] > cam[0, 0] and cam[cols, 1] > cam[0, 1] and n > cols)
    return to_jsonable(d)


def _distortion(lens, K, device: str, approximate: bool, left: dict):
    """procam's :class:`~procam.calibration.Distortion` of a simulator lens (see :func:`truth_calibration`)."""
    from ..calibration import Distortion

    if lens.model == "division":
        return Distortion("division", tuple(float(v) for v in lens.center_px(K)), *lens.coeffs)
    if lens.model == "none":
        return Distortion()
    out = lens.left_out(K)
    if out:
        if not approximate:
            raise ValueError(f"the {device}'s lens is not one procam's distortion models describe exactly: "
                             f"{'; '.join(out)}. truth_calibration(scene, approximate=True) returns its OpenCV "
                             "part (k1, k2, p1, p2, k3 about the principal point) and says so")
        left[device] = out
    return Distortion("opencv", coeffs=tuple(lens.coeffs))


def truth_calibration(scene: Scene, method: str = "truth", approximate: bool = False):
    """The scene's exact devices and extrinsics as a :class:`procam.calibration.Calibration` (no ``std``;
    ``stereo_rms`` 0, the per-device RMS not computed): what a perfect calibration of this rig would return, to
    hold a result or a metric against.

    Each device's distortion is its lens in procam's terms: ``Distortion("division", ...)``,
    ``Distortion("opencv", coeffs=(k1, k2, p1, p2, k3))`` or none.  A lens procam's models do not describe
    exactly (radial terms beyond k3, a radial centre off the principal point: :meth:`Lens.describable`)
    raises ``ValueError`` naming what they leave out, unless ``approximate`` is True: its OpenCV part is then
    returned, the result's ``warnings`` say so and ``info["truth_left_out"]`` = {device: [what is left out]}.
    K, R and T are exact either way.
    """
    from ..calibration import Calibration, Device

    left: dict = {}
    cam = _distortion(scene.cam_lens, scene.K_cam, "camera", approximate, left)
    proj = _distortion(scene.proj_lens, scene.K_proj, "projector", approximate, left)
    extra = {}
    if left:
        extra = {"info": {"truth_left_out": left},
                 "warnings": tuple(f"the true {dev} lens is not exactly its OpenCV part here: {'; '.join(what)} "
                                   "left out" for dev, what in left.items())}
    return Calibration(Device(np.array(scene.K_cam), scene.cam_size, cam),
                       Device(np.array(scene.K_proj), scene.proj_size, proj), np.array(scene.R), np.array(scene.T),
                       method, stereo_rms=0.0, **extra)


def correspondences(scene: Scene, sigma_cam: float = 0.1, sigma_proj: float = 0.2, seed: int = 0):
    """Fast path: exact corners plus i.i.d. Gaussian noise, no rendering.

    Returns
    -------
    obj : (N, 3) board corners (board frame, mm).
    cam : (N, 2) distorted camera corners + N(0, sigma_cam^2) per coordinate; NaN for a corner the
        background hides from the camera (:func:`corner_truth`'s ``hidden``: not detected).
    proj : (N, 2) projector corners (the panel pixels that light them, through the projector's lens)
        + N(0, sigma_proj^2) per coordinate; NaN for a hidden corner and for one in a shadow (``shadowed``:
        no code to decode there).

    Every corner keeps its row (order ``k = j*cols + i``); a placed preset hides none.
    """
    c = corner_truth(scene)
    rng = np.random.default_rng(seed)
    n = len(c["board"])
    cam = c["camera_distorted"] + sigma_cam * rng.standard_normal((n, 2))
    proj = c["projector"] + sigma_proj * rng.standard_normal((n, 2))
    cam[c["hidden"]] = np.nan
    proj[c["hidden"] | c["shadowed"]] = np.nan
    return c["board"], cam, proj
