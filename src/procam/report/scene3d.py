"""A calibrated pair in 3-D (the report's rig section): the board poses and the camera's and the projector's
frusta in the camera frame, and an inline SVG view of them that a small inline script turns when dragged (a rig of
N devices is drawn by :mod:`procam.rig.draw` on its own page, :mod:`procam.report.rig_page`).

A board pose is the calibration's own (a multi-pose calibration keeps them: ``calib.poses[k]["R_cam"]``), else
PnP of the pose's corners with the calibrated camera (undistorted first); a pose PnP cannot place is left out
of the picture. A frustum is the device's image corners back-projected out to 0.3 x the mean board distance.
The view is orthographic -- turn about the vertical by yaw, tilt by pitch, camera y (down) stays screen y --
and the script projects the same way, so the first picture and the turned ones agree.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

import numpy as np

from ..residuals import pnp

__all__ = ["rig_geometry", "rig_svg"]


def _board_pose(calib, view, k):
    """Board -> camera pose of a view: the calibration's own (multi-pose) or PnP with the camera's intrinsics."""
    poses = list(calib.poses)
    if k < len(poses) and "R_cam" in poses[k] and str(poses[k].get("name")) == str(view.name):
        return np.asarray(poses[k]["R_cam"], float), np.asarray(poses[k]["t_cam"], float)
    ok = np.isfinite(view.cam_pts).all(1) & np.isfinite(view.obj_pts).all(1)
    if ok.sum() < 4:
        return None
    with np.errstate(all="ignore"):
        und = calib.camera.undistort(view.cam_pts[ok])
    fin = np.isfinite(und).all(1)
    if fin.sum() < 4:
        return None
    try:
        R, t, _ = pnp(view.obj_pts[ok][fin], und[fin], calib.camera.K)
    except Exception:  # noqa: BLE001 -- a pose PnP cannot place is left out of the picture
        return None
    return R, t


def _frustum(K, size, depth, to_cam):
    """Polylines (lists of 3-D camera-frame points) of a device's frustum out to ``depth``."""
    W, H = size
    Ki = np.linalg.inv(np.asarray(K, float))
    corners = np.array([[-0.5, -0.5], [W - 0.5, -0.5], [W - 0.5, H - 0.5], [-0.5, H - 0.5]])
    rays = (Ki @ np.column_stack([corners, np.ones(4)]).T).T
    far = to_cam(rays / rays[:, 2:3] * depth)
    apex = to_cam(np.zeros((1, 3)))[0]
    lines = [[apex.tolist(), p.tolist()] for p in far]
    lines.append([p.tolist() for p in far] + [far[0].tolist()])
    return lines


def rig_geometry(calib, views=()) -> dict:
    """The rig in the camera frame (x right, y down, z forward; board units) as polylines.

    Returns
    -------
    dict with ``paths`` (list of ``{"pts": [[x, y, z], ...], "cls": "camera" | "projector" | "board" |
    "axis", "name": ...}``), ``labels`` (``{"text", "at": [x, y, z], "cls"}``) and ``distance`` (the mean
    board distance, or 3 x the baseline without boards).
    """
    paths, labels, boards = [], [], []
    for k, v in enumerate(views):
        pose = _board_pose(calib, v, k)
        if pose is None:
            continue
        R, t = pose
        obj = v.obj_pts[np.isfinite(v.obj_pts).all(1)]
        xs, ys = np.unique(np.round(obj[:, 0], 9)), np.unique(np.round(obj[:, 1], 9))
        pitch = min([float(np.diff(a).min()) for a in (xs, ys) if len(a) > 1] or [0.0])
        x0, x1, y0, y1 = xs.min() - pitch, xs.max() + pitch, ys.min() - pitch, ys.max() + pitch
        outline = np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0], [x0, y0, 0]])
        X = outline @ R.T + t
        boards.append(X)
        name = Path(str(v.name)).name or str(v.name)
        paths.append({"pts": X.tolist(), "cls": "board", "name": name})
        c0 = (np.array([[obj[0, 0], obj[0, 1], 0.0]]) @ R.T + t)[0]
        paths.append({"pts": [c0.tolist(), X[0].tolist()], "cls": "board0", "name": name})
        labels.append({"text": name, "at": X[:4].mean(0).tolist(), "cls": "board"})
    T = np.zeros(3) if calib.T is None else np.asarray(calib.T, float)
    base = float(np.linalg.norm(T))
    dist = float(np.mean([np.linalg.norm(b[:4].mean(0)) for b in boards])) if boards else max(3 * base, 1.0)
    depth = 0.3 * dist
    paths += [{"pts": p, "cls": "camera", "name": "camera"}
              for p in _frustum(calib.camera.K, calib.camera.image_size, depth, lambda X: X)]
    labels.append({"text": "camera", "at": [0.0, 0.0, 0.0], "cls": "camera"})
    if calib.projector is not None and calib.R is not None:
        R = np.asarray(calib.R, float)
        paths += [{"pts": p, "cls": "projector", "name": "projector"}
                  for p in _frustum(calib.projector.K, calib.projector.image_size, depth, lambda X: (X - T) @ R)]
        labels.append({"text": "projector", "at": (-R.T @ T).tolist(), "cls": "projector"})
    a = 0.12 * dist
    for i, n in enumerate("xyz"):
        e = np.zeros(3)
        e[i] = a
        paths.append({"pts": [[0.0, 0.0, 0.0], e.tolist()], "cls": "axis", "name": n})
        labels.append({"text": n, "at": (1.15 * e).tolist(), "cls": "axis"})
    return {"paths": paths, "labels": labels, "distance": dist}


_RIG_W, _RIG_H = 760, 440


def _rig_view(geom, yaw, pitch):
    pts = np.array([p for path in geom["paths"] for p in path["pts"]], float)
    c = pts.mean(0)
    radius = float(np.max(np.linalg.norm(pts - c, axis=1))) or 1.0
    return {"c": c.tolist(), "s": 0.5 * min(_RIG_W, _RIG_H) / radius, "cx": _RIG_W / 2, "cy": _RIG_H / 2,
            "yaw": yaw, "pitch": pitch}


def _project(p, v):
    """The page's projection (the script does the same): turn about the vertical by yaw, tilt by pitch,
    orthographic; camera y (down) stays screen y."""
    a, b = np.radians(v["yaw"]), np.radians(v["pitch"])
    x, y, z = np.asarray(p, float) - v["c"]
    x1 = np.cos(a) * x + np.sin(a) * z
    z1 = -np.sin(a) * x + np.cos(a) * z
    y2 = np.cos(b) * y - np.sin(b) * z1
    return v["cx"] + v["s"] * x1, v["cy"] + v["s"] * y2


def _path_d(pts, v) -> str:
    return " ".join(f"{'L' if k else 'M'}{x:.1f} {y:.1f}" for k, (x, y) in enumerate(_project(p, v) for p in pts))


_RIG_SCRIPT = """(function(){
var d=JSON.parse(document.getElementById('rig-data').textContent),v=d.view,svg=document.getElementById('rig-svg');
function P(p){var a=v.yaw*Math.PI/180,b=v.pitch*Math.PI/180,x=p[0]-v.c[0],y=p[1]-v.c[1],z=p[2]-v.c[2];
var x1=Math.cos(a)*x+Math.sin(a)*z,z1=-Math.sin(a)*x+Math.cos(a)*z;return [v.cx+v.s*x1,v.cy+v.s*(Math.cos(b)*y-Math.sin(b)*z1)];}
function draw(){d.paths.forEach(function(l,i){document.getElementById('rig-p'+i).setAttribute('d',l.pts.map(function(p,k){
var q=P(p);return (k?'L':'M')+q[0].toFixed(1)+' '+q[1].toFixed(1);}).join(' '));});
d.labels.forEach(function(l,i){var q=P(l.at),e=document.getElementById('rig-t'+i);e.setAttribute('x',q[0].toFixed(1));
e.setAttribute('y',q[1].toFixed(1));});}
var g=null;svg.addEventListener('pointerdown',function(e){g=[e.clientX,e.clientY,v.yaw,v.pitch];svg.setPointerCapture(e.pointerId);});
svg.addEventListener('pointermove',function(e){if(!g)return;v.yaw=g[2]+(e.clientX-g[0])*0.4;
v.pitch=Math.max(-89,Math.min(89,g[3]+(e.clientY-g[1])*0.4));draw();});
svg.addEventListener('pointerup',function(){g=null;});
svg.addEventListener('dblclick',function(){v.yaw=d.view0.yaw;v.pitch=d.view0.pitch;draw();});
})();"""


def _json_for_script(obj) -> str:
    """JSON that cannot close or confuse the ``<script>`` element that holds it."""
    return json.dumps(obj, separators=(",", ":")).replace("<", "\\u003c").replace(">", "\\u003e").replace("&",
                                                                                                         "\\u0026")


def rig_svg(geom: dict, yaw: float = 15.0, pitch: float = 35.0, interactive: bool = True) -> str:
    """Inline SVG of :func:`rig_geometry` in a fixed oblique orthographic view, plus (``interactive``) a
    small inline script that turns it when dragged (double-click: back to the start)."""
    v = _rig_view(geom, yaw, pitch)
    out = [f'<svg id="rig-svg" viewBox="0 0 {_RIG_W} {_RIG_H}" width="{_RIG_W}" height="{_RIG_H}" role="img" '
           'aria-label="camera, projector and board poses">']
    for i, p in enumerate(geom["paths"]):
        out.append(f'<path id="rig-p{i}" class="rig-{p["cls"]}" d="{_path_d(p["pts"], v)}">'
                   f'<title>{html.escape(str(p["name"]))}</title></path>')
    for i, lab in enumerate(geom["labels"]):
        x, y = _project(lab["at"], v)
        dx = {"camera": -6, "projector": 6}.get(lab["cls"], 0)
        out.append(f'<text id="rig-t{i}" class="rig-label rig-{lab["cls"]}" x="{x:.1f}" y="{y:.1f}" dx="{dx}" dy="4">'
                   f'{html.escape(str(lab["text"]))}</text>')
    out.append("</svg>")
    if interactive:
        data = {"paths": [{"pts": [[round(c, 3) for c in q] for q in p["pts"]]} for p in geom["paths"]],
                "labels": [{"at": [round(c, 3) for c in lab["at"]]} for lab in geom["labels"]], "view": v,
                "view0": dict(v)}
        out.append(f'<script type="application/json" id="rig-data">{_json_for_script(data)}</script>')
        out.append(f"<script>{_RIG_SCRIPT}</script>")
    return "\n".join(out)
