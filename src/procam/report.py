"""A calibration as one self-contained HTML page (``procam report``, ``procam calibrate --report``).

:func:`build_report` returns the page as a string; :func:`write_report` writes it atomically.  The page
reads top to bottom: the verdict in words and why, the parameters with their uncertainty and the model's
assumptions, the coverage of both image planes, the residual vectors (the same residuals and RMS as the
tables, rejected corners marked), the metric verification, the rig in 3-D and, for a multi-pose
calibration, the leave-one-pose-out verification.

Self-contained: the figures are inline PNG (``data:`` URLs), the style sheet and the rig's small script
are inline, and a Content-Security-Policy forbids every other source, so the page makes no request.
Every user string (file and pose names, messages) is HTML-escaped.
"""

from __future__ import annotations

import base64
import html
import io as _stdio
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .residuals import calibration_residuals, pnp
from .summary import PLUS_MINUS, parameter_rows, pose_rows, projector_assumptions, projector_freed
from .verify import CalibrationCheck, check_calibration

__all__ = ["Verdict", "calibration_verdict", "coverage_fractions", "rig_geometry", "rig_svg", "build_report",
           "write_report", "SECTIONS"]

#: The page's sections, in order: ``id -> heading`` (``leave-one-out`` only for multi-pose calibrations).
SECTIONS = {"verdict": "Verdict", "parameters": "Parameters and assumptions", "coverage": "Coverage of the image planes",
            "residuals": "Reprojection residuals", "verification": "Metric verification", "rig": "The rig in 3-D",
            "leave-one-out": "Leave-one-pose-out verification"}

#: The verdict's words, best first.
VERDICTS = ("good", "weak", "degenerate", "failed", "unknown")

_MEANING = {
    "good": "Fit to use: every pose constrains what it must and nothing was flagged.",
    "weak": "Usable with care: some parameters are less certain than a better pose set would make them (see why).",
    "degenerate": "Do not trust the flagged parameters: the poses do not determine them. Re-capture as suggested.",
    "failed": "The calibration failed: an estimate is impossible for a real device. Re-capture as suggested.",
    "unknown": "The file holds no per-pose advice, so there is no verdict; judge from the sections below.",
}


# --------------------------------------------------------------------------------------------------
# the verdict
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Verdict:
    """A calibration's verdict in words.

    Attributes
    ----------
    word : one of :data:`VERDICTS` (``good``, ``weak``, ``degenerate``, ``failed``, ``unknown``).
    reasons : the messages behind it, one line each (most important first).
    """

    word: str
    reasons: tuple = ()

    def line(self) -> str:
        """``"word: first reason"`` (a good verdict: all its reasons), for figure titles and terminals."""
        if not self.reasons:
            return self.word
        return f"{self.word}: " + ("; ".join(self.reasons) if self.word == "good" else self.reasons[0])


def _advice_messages(calib) -> list[str]:
    """Every device's advice message over the poses (the words of a good single-pose verdict)."""
    return [a["message"] for p in calib.poses for k in ("camera", "projector")
            if isinstance(a := (p.get("advice") or {}).get(k), dict) and a.get("message")]


def _multi_pose_words(calib) -> list[str]:
    how = "jointly refined" if calib.info.get("refined") else "without a joint refinement"
    return [f"{len(calib.poses)} poses, {how}, no warnings"]


def calibration_verdict(calib) -> Verdict:
    """The verdict of a calibration in words, from what the calibration carries.

    The single place the report, the figures and the CLI read a verdict from: the calibration's own
    ``verdict`` and ``verdict_reasons``. For a file that records none (``verdict == "unknown"``) it is derived
    from each
    pose's advice (``calib.poses[i]["advice"]``: ``failed``, ``degenerate``, ``ok``) and the
    calibration's ``warnings``: any failed device -> ``failed``; any degenerate one -> ``degenerate``;
    any weak one, or any warning -> ``weak``; else ``good``.  A multi-pose calibration (no per-pose
    advice) is ``weak`` with fewer than 3 poses or with warnings, else ``good``; a file with no poses
    (OpenCV YAML) is ``unknown``.

    Returns
    -------
    :class:`Verdict`
    """
    if calib.verdict != "unknown":  # the calibration's own verdict (procam.single_pose.advice / multi_pose)
        reasons = list(calib.verdict_reasons)
        if not reasons:
            reasons = _advice_messages(calib) or (_multi_pose_words(calib) if calib.method == "multi-pose" else [])
        return Verdict(calib.verdict, tuple(reasons))
    word, reasons = "good", []
    rank = {w: i for i, w in enumerate(VERDICTS)}

    def worse(w):
        nonlocal word
        if rank[w] > rank[word] and word != "unknown":
            word = w

    advised = False
    for p in calib.poses:
        adv = p.get("advice") or {}
        if not adv:
            continue
        advised = True
        for key in ("camera", "projector"):
            a = adv.get(key)
            if not isinstance(a, dict):
                continue
            w = ("failed" if a.get("failed") else "degenerate" if a.get("degenerate") else
                 "weak" if a.get("weak") else "good")
            worse(w)
            if w != "good" and a.get("message"):
                name = Path(str(p.get("name", ""))).name
                reasons.append(f"{name}: {a['message']}" if len(calib.poses) > 1 and name else a["message"])
    if not advised and not calib.poses:
        word = "unknown"
    if calib.method == "multi-pose" and 0 < len(calib.poses) < 3:
        worse("weak")
    if word == "good":
        if advised:
            reasons = _advice_messages(calib)
        elif calib.method == "multi-pose" and not calib.warnings:
            reasons = _multi_pose_words(calib)
    for w in calib.warnings:
        if not any(r.split(": ", 1)[-1] in w for r in reasons):
            reasons.append(str(w))
            if not advised and word != "unknown":  # a multi-pose calibration's warnings are all weaknesses
                worse("weak")
    return Verdict(word, tuple(reasons))


# --------------------------------------------------------------------------------------------------
# coverage and the rig
# --------------------------------------------------------------------------------------------------

def coverage_fractions(views, cam_size, proj_size=None) -> dict:
    """Share of each image inside the union of the poses' corner outlines (convex hulls).

    Parameters
    ----------
    views : :class:`procam.view.View` sequence; cam_size, proj_size : (width, height).

    Returns
    -------
    ``{"camera": fraction, "projector": fraction}`` (0..1; the projector only with ``proj_size``).
    """
    from .board import board_region

    out = {}
    for label, key, size in (("camera", "cam_pts", cam_size), ("projector", "proj_pts", proj_size)):
        if size is None:
            continue
        m = np.zeros((int(size[1]), int(size[0])), bool)
        for v in views:
            m |= board_region(getattr(v, key), size)
        out[label] = float(m.mean())
    return out


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


# --------------------------------------------------------------------------------------------------
# HTML pieces
# --------------------------------------------------------------------------------------------------

_e = html.escape

_CSS = """
body{font:15px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;color:#1b1b1b;margin:0;background:#f6f6f4}
main{max-width:1120px;margin:0 auto;padding:18px 28px 40px;background:#fff}
h1{font-size:1.6em;margin:.2em 0}h2{font-size:1.25em;margin:1.6em 0 .4em;border-bottom:1px solid #ddd;padding-bottom:.2em}
h3{font-size:1.05em;margin:1.1em 0 .3em}
.meta{color:#555;font-size:.92em}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.9em}
th,td{border:1px solid #d4d4d4;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#f0f0ee}th[colspan]{text-align:center}td.l,th.l{text-align:left}tr.all td{font-weight:600;background:#fafaf7}
.verdict{border-left:10px solid #777;padding:10px 16px;background:#f7f7f7;margin:10px 0}
.verdict h2{border:0;margin:0 0 .3em;font-size:1.5em}
.verdict.good{border-color:#2e8b3c;background:#eef8ef}.verdict.weak{border-color:#e0901a;background:#fdf5e7}
.verdict.degenerate,.verdict.failed{border-color:#c62828;background:#fdecec}
.word{text-transform:uppercase;letter-spacing:.04em}
.note{color:#555;font-size:.9em}.warn{color:#8a4b00}
figure{margin:.6em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{color:#555;font-size:.88em}
#rig-svg{border:1px solid #ddd;background:#fcfcfc;cursor:grab;max-width:100%;height:auto;touch-action:none;
user-select:none;-webkit-user-select:none}
.rig-camera{stroke:#1f77b4;stroke-width:1.6;fill:none}.rig-projector{stroke:#e07b00;stroke-width:1.6;fill:none}
.rig-board{stroke:#555;stroke-width:1.2;fill:rgba(120,120,120,.12)}.rig-board0{stroke:#c62828;stroke-width:2;fill:none}
.rig-axis{stroke:#999;stroke-width:1;fill:none}
.rig-label{font-size:12px;stroke:none}text.rig-camera{fill:#1f77b4}text.rig-projector{fill:#e07b00}
text.rig-camera{text-anchor:end}text.rig-board{fill:#333;font-size:11px}text.rig-axis{fill:#888;font-size:11px}
code{font-size:.92em}
"""

_CSP = ("default-src 'none'; img-src data:; style-src 'unsafe-inline'; script-src 'unsafe-inline'; "
        "base-uri 'none'; form-action 'none'")


def _table(headers, rows, *, left=1, row_classes=None) -> str:
    """An HTML table; the first ``left`` columns left-aligned; every cell escaped."""
    h = "".join(f'<th class="l">{_e(str(c))}</th>' if i < left else f"<th>{_e(str(c))}</th>"
                for i, c in enumerate(headers))
    body = []
    for k, r in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        cells = "".join(f'<td class="l">{_e(str(c))}</td>' if i < left else f"<td>{_e(str(c))}</td>"
                        for i, c in enumerate(r))
        body.append(f"<tr{cls}>{cells}</tr>")
    return f"<table><thead><tr>{h}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _png(fig, alt: str, dpi: int = 80) -> str:
    """A matplotlib figure as an inline ``<img>`` (base64 PNG)."""
    buf = _stdio.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{_e(alt)}">'


def _f(x, fmt=".3f") -> str:
    return "" if x is None or not np.isfinite(x) else f"{x:{fmt}}"


def _short(name) -> str:
    s = str(name or "")
    return Path(s).name or s


def _section(sid: str, body: str, cls: str = "") -> str:
    c = f' class="{cls}"' if cls else ""
    return f'<section id="{sid}"{c}>\n<h2>{_e(SECTIONS[sid])}</h2>\n{body}\n</section>'


# --------------------------------------------------------------------------------------------------
# sections
# --------------------------------------------------------------------------------------------------

def _verdict_section(calib, verdict: Verdict, check: CalibrationCheck | None) -> str:
    parts = [f'<p><strong>{_e(_MEANING[verdict.word])}</strong></p>']
    if verdict.reasons:
        parts.append("<ul>" + "".join(f"<li>{_e(r)}</li>" for r in verdict.reasons) + "</ul>")
    facts = [f"camera RMS {_f(calib.cam_rms)} px"]
    if calib.projector is not None:
        facts += [f"projector RMS {_f(calib.proj_rms)} px", f"stereo RMS {_f(calib.stereo_rms)} px"]
    facts.append(f"{len(calib.poses)} pose{'s' if len(calib.poses) != 1 else ''}")
    parts.append(f"<p>{_e(', '.join(facts))}.</p>")
    if check is not None:
        for label, ver in (("held-out poses", check.held_out),
                           ("leave-one-pose-out", check.leave_one_out.held_out if check.leave_one_out else None),
                           ("its own poses (in-sample, optimistic)", check.in_sample)):
            if ver is not None:
                o = ver.overall
                parts.append(f"<p>Measured on {_e(label)}: the triangulated board's squares are "
                             f"{o.scale_error_pct:+.3f} % off the printed size and its corners lie "
                             f"{o.planarity_rms:.3f} (RMS) from a plane, in board units "
                             f"(<a href=\"#verification\">metric verification</a>).</p>")
                break
    word = f'<span class="word">{_e(verdict.word)}</span>'
    return (f'<section id="verdict" class="verdict {_e(verdict.word)}">\n<h2>Verdict: {word}</h2>\n'
            + "\n".join(parts) + "\n</section>")


def _assumptions(calib) -> list[str]:
    out = []
    d = calib.camera.distortion
    if calib.method in ("single-pose", "camera-only"):
        src = calib.info.get("principal_point_source")
        pp = {"cod": "the centre of distortion", "joint": "the joint fit of all camera parameters",
              "image-center": "the image centre, ASSUMED (a prior: the centre of distortion was not reliable)",
              "given": "given"}.get(src, None)
        out.append("Camera: pinhole, zero skew, division-model distortion (k1, k2) about the principal point"
                   + (f"; the principal point comes from {pp}" if pp else "") + ".")
    elif d.model == "opencv":
        out.append(f"Camera: pinhole, zero skew, OpenCV distortion "
                   f"({_e(str(calib.info.get('cam_dist_model', len(d.coeffs))))}).")
    if calib.projector is not None:
        if calib.method == "single-pose":
            out.append("Projector (single-pose model): " + "; ".join(projector_assumptions(calib)) + ". "
                       "The ± of the projector do not cover a projector that breaks what is assumed "
                       "(e.g. a lens-shifted projector with u0p far from W/2 when the background could not tell).")
        elif calib.projector.distortion.model == "opencv":
            out.append(f"Projector: pinhole, zero skew, OpenCV distortion "
                       f"({_e(str(calib.info.get('proj_dist_model', '')))}).")
        out.append("Extrinsics: x_proj = R x_cam + T (camera to projector); T in board units (the unit of the "
                   "board's square).")
    if calib.method == "multi-pose":
        out.append("Multi-pose: " + ("both devices, R, T and every board pose jointly refined (robust loss); "
                                     if calib.info.get("refined") else
                                     "per-device OpenCV calibration and stereoCalibrate with fixed intrinsics "
                                     "(no joint refinement, so no ± are available); ")
                   + "the board is flat and its squares exact.")
    else:
        out.append("The board is flat and its squares exact.")
    out.append(f"{PLUS_MINUS}. It does not cover a wrong model; see the verdict and the metric verification.")
    return out


def _parameters_section(calib) -> str:
    rows = [list(r) for r in parameter_rows(calib)]
    if calib.method == "single-pose" and calib.projector is not None:
        freed = projector_freed(calib)
        for r in rows:
            if r[0].startswith("u0"):
                r[2] += " (from the background)" if "u0p" in freed else " (assumed W/2)"
            elif r[0].startswith("fy"):
                r[2] += " (from the background)" if "alpha_p" in freed else " (assumed = f)"
        rows.append(["projector distortion", "", "none (assumed)"])
    head = ["parameter", "camera"] + (["projector"] if calib.projector is not None else [])
    rows = [r[:len(head)] for r in rows]
    parts = [f'<p class="note">{_e(PLUS_MINUS)}.</p>', _table(head, rows)]
    parts.append("<h3>Model and assumptions</h3><ul>" + "".join(f"<li>{_e(a)}</li>" for a in _assumptions(calib))
                 + "</ul>")
    pr = pose_rows(calib)
    if pr:
        parts.append("<h3>Poses</h3>")
        head = ["pose", "camera ψ, ν, φ (deg)", "projector ψ, ν, φ (deg)", "advice"]
        n = 4 if any(r[3] for r in pr) else 3
        parts.append(_table(head[:n], [list(r)[:n] for r in pr], left=n))
    return "\n".join(parts)


def _coverage_section(calib, views, decodes) -> str:
    if not views:
        return '<p class="note">No poses to show: the calibration file holds no corners; give the pose folders.</p>'
    from .plots.coverage import coverage_figure

    proj_size = calib.projector.image_size if calib.projector is not None else None
    cov = coverage_fractions(views, calib.camera.image_size, proj_size)
    fig = coverage_figure(views, calib.camera.image_size, proj_size, decodes=decodes, coverage=cov)
    rows = [[k, f"{100 * v:.0f} %"] for k, v in cov.items()]
    return "\n".join([
        "<figure>" + _png(fig, "coverage of the camera and projector images") + "<figcaption>Each pose's corners "
        "and their outline (convex hull)" + (", over the pixels decoded in any pose (grey)" if decodes else "")
        + ". Corners near the edges pin the lens distortion there; outside the outlines the model extrapolates."
        "</figcaption></figure>",
        _table(["image", "inside the union of the corners' outlines"], rows)])


def _residuals_section(calib, per_pose, verdict: Verdict) -> str:
    if not per_pose:
        return '<p class="note">No poses to show: the calibration file holds no corners; give the pose folders.</p>'
    from .plots.residuals import residual_figure

    has_proj = calib.projector is not None
    fig = residual_figure(per_pose, calib.camera.image_size, calib.projector.image_size if has_proj else None,
                          verdict=verdict.line())
    source = per_pose[0].get("source")
    how = {"single-pose": "each device's PnP pose with the calibrated intrinsics, on the corners the solver kept; "
                          "camera residuals in undistorted pixels, as the single-pose RMS is defined",
           "multi-pose": "the refined model at its own board poses, in distorted pixels",
           "pnp": "each device's PnP pose with the calibrated intrinsics, in distorted pixels"}.get(source, "")
    rows, classes = [], []
    pooled = {"cam": [], "proj": []}
    n_rej = {"cam": 0, "proj": 0}
    for p in per_pose:
        r = [_short(p.get("name"))]
        for key in ("cam", "proj") if has_proj else ("cam",):
            res, used = p.get(f"{key}_res"), p.get(f"{key}_used")
            if res is None:
                r += ["", "", ""]
                continue
            fin = np.isfinite(res).all(1)
            used = fin if used is None else (np.asarray(used, bool) & fin)
            e = np.linalg.norm(res[used], axis=1)
            pooled[key].append(e)
            n_rej[key] += int((fin & ~used).sum())
            r += [_f(float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")), str(int(used.sum())),
                  str(int((fin & ~used).sum()))]
        rows.append(r)
        classes.append("")
    if len(per_pose) > 1:
        r = ["all"]
        for key in ("cam", "proj") if has_proj else ("cam",):
            e = np.concatenate(pooled[key]) if pooled[key] else np.zeros(0)
            r += [_f(float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")), str(e.size), str(n_rej[key])]
        rows.append(r)
        classes.append("all")
    head = ["pose", "camera RMS (px)", "corners", "rejected"]
    if has_proj:
        head += ["projector RMS (px)", "corners", "rejected"]
    return "\n".join([
        "<figure>" + _png(fig, "reprojection residual vectors") + "<figcaption>Residual = observed - predicted, "
        "drawn as arrows at the observed corners, magnified as the key arrow says; red x: corners rejected as "
        f"outliers (not in the RMS). Measured as the calibration measures its RMS: {_e(how)}.</figcaption></figure>",
        _table(head, rows, row_classes=classes)])


_VCOLS = ["pose", "corners", "scale error (%)", "spacing RMS", "planarity RMS", "planarity max", "rigid RMS",
          "reproj RMS (px)", "distance"]


def _vrow(p, name=None):
    return [name or _short(p.name), str(p.n_corners), f"{p.scale_error_pct:+.3f}", f"{p.spacing_rms:.3f}",
            f"{p.planarity_rms:.3f}", f"{p.planarity_max:.3f}", f"{p.rigid_rms:.3f}", f"{p.reproj_rms:.3f}",
            f"{p.distance:.0f}"]


def _verification_table(ver) -> str:
    rows = [_vrow(p) for p in ver.poses]
    classes = [""] * len(rows)
    if len(ver.poses) > 1:
        rows.append(_vrow(ver.overall, "all"))
        classes.append("all")
    return _table(_VCOLS, rows, row_classes=classes)


def _verification_section(calib, check: CalibrationCheck | None) -> str:
    if check is None:
        return '<p class="note">Not computed.</p>'
    parts = ['<p>The chessboard corners of every pose triangulated from the camera and the projector with this '
             "calibration, compared with the printed board: <em>scale error</em> = mean distance of adjacent corners "
             "against the printed square (positive: too large); <em>spacing RMS</em> = RMS of that distance minus the "
             "square; <em>planarity</em> = distances of the corners to their best plane; <em>rigid RMS</em> = corner "
             "distance after the best rigid fit of the printed board (the whole shape error); lengths in board units "
             "(the unit of the square, e.g. mm). A correct calibration gives a scale error near 0 and the corner "
             "noise as planarity.</p>"]
    if check.in_sample is not None:
        parts += ["<h3>On the poses the calibration was fitted to (in-sample, optimistic)</h3>",
                  _verification_table(check.in_sample)]
    if check.held_out is not None:
        parts += ["<h3>On other poses (held out: the honest figure)</h3>", _verification_table(check.held_out)]
    if check.leave_one_out is not None and check.leave_one_out.held_out is not None:
        o = check.leave_one_out.held_out.overall
        parts.append(f'<p>Leave-one-pose-out (each pose verified by a calibration fitted without it): scale error '
                     f'{o.scale_error_pct:+.3f} %, rigid RMS {o.rigid_rms:.3f}; per pose in '
                     f'<a href="#leave-one-out">the last section</a>.</p>')
    if check.notes:
        parts.append("<ul class=\"warn\">" + "".join(f"<li>{_e(n)}</li>" for n in check.notes) + "</ul>")
    return "\n".join(parts)


def _loo_section(check: CalibrationCheck | None) -> str:
    loo = check.leave_one_out if check is not None else None
    if loo is None or loo.held_out is None:
        why = [n for n in (check.notes if check is not None else ()) if "leave-one" in n]
        return '<p class="note">' + _e(why[0] if why else "Not available.") + "</p>"
    held = {p.name: p for p in loo.held_out.poses}
    rows, classes = [], []
    for p in loo.in_sample.poses:
        h = held.get(p.name)

        def g(attr, fmt, q=None):
            return "" if q is None else f"{getattr(q, attr):{fmt}}"

        rows.append([_short(p.name), g("scale_error_pct", "+.3f", p), g("scale_error_pct", "+.3f", h),
                     g("planarity_rms", ".3f", p), g("planarity_rms", ".3f", h), g("rigid_rms", ".3f", p),
                     g("rigid_rms", ".3f", h), g("reproj_rms", ".3f", p), g("reproj_rms", ".3f", h)])
        classes.append("")
    i, o = loo.in_sample.overall, loo.held_out.overall
    rows.append(["all", f"{i.scale_error_pct:+.3f}", f"{o.scale_error_pct:+.3f}", f"{i.planarity_rms:.3f}",
                 f"{o.planarity_rms:.3f}", f"{i.rigid_rms:.3f}", f"{o.rigid_rms:.3f}", f"{i.reproj_rms:.3f}",
                 f"{o.reproj_rms:.3f}"])
    classes.append("all")
    groups = ["scale error (%)", "planarity RMS", "rigid RMS", "reproj RMS (px)"]
    table = _table(["pose"] + ["in-sample", "left out"] * len(groups), rows, row_classes=classes)
    top = '<tr><th class="l"></th>' + "".join(f'<th colspan="2">{_e(g)}</th>' for g in groups) + "</tr>"
    table = table.replace("<thead>", "<thead>" + top, 1)
    parts = ["<p>For every pose, the calibration is refitted without it (same options) and the left-out pose is "
             "verified with the refit: the figure to expect on a new capture. In-sample: the calibration from all "
             "poses on the same pose. A left-out figure much worse than the in-sample one means the calibration "
             "depends on that pose.</p>", table]
    if loo.failures:
        parts.append("<ul class=\"warn\">" + "".join(f"<li>refit without {_e(_short(n))} failed: {_e(m)}</li>"
                                                      for n, m in loo.failures) + "</ul>")
    return "\n".join(parts)


def _rig_section(calib, views) -> str:
    geom = rig_geometry(calib, views)
    n_boards = sum(1 for p in geom["paths"] if p["cls"] == "board")
    T = calib.T
    facts = []
    if T is not None:
        facts.append(f"baseline |T| = {np.linalg.norm(T):.1f}")
        if calib.R is not None:
            facts.append("projector centre in the camera frame = ("
                         + ", ".join(f"{c:.1f}" for c in (-np.asarray(calib.R).T @ np.asarray(T))) + ")")
    if n_boards:
        facts.append(f"mean board distance {geom['distance']:.0f}")
    return "\n".join([
        "<figure>" + rig_svg(geom) + "<figcaption>Camera (blue) and projector (orange) frustums and the "
        f"{n_boards} board pose{'s' if n_boards != 1 else ''} (grey; red tick: the first corner) in the camera "
        "frame (x right, y down, z forward; axes grey), board units. Drag to turn, double-click to reset.</figcaption>"
        "</figure>",
        f"<p>{_e('; '.join(facts))}.</p>" if facts else ""])


# --------------------------------------------------------------------------------------------------
# the page
# --------------------------------------------------------------------------------------------------

def build_report(calib, views=None, *, decodes=None, check: CalibrationCheck | None = None, verify: bool = True,
                 name: str = "calibration", notes=()) -> str:
    """The HTML page of a calibration.

    Parameters
    ----------
    calib : :class:`procam.calibration.Calibration`.
    views : the poses to show and verify (default: the calibration's own ``views``).  Residuals are
        those of the calibration's own poses when it holds them (:func:`procam.residuals.calibration_residuals`),
        else of ``views``.
    decodes : optional :class:`procam.decode.DecodeResult` per view (coverage of the decoded pixels).
    check : the metric verification (:func:`procam.verify.check_calibration`); computed here when None
        and ``verify`` (leave-one-pose-out refits included for a multi-pose calibration of >= 4 poses).
    name : the calibration's name in the title (e.g. its file name).
    notes : extra lines for the top of the page (e.g. what was decoded).

    Returns
    -------
    str : the whole page (UTF-8 text).
    """
    from . import __version__

    views = list(calib.views) if views is None else list(views)
    if check is None and verify and calib.projector is not None:
        check = check_calibration(calib, views)
    verdict = calibration_verdict(calib)
    own = list(calib.views)
    per_pose = calibration_residuals(calib) if own else (calibration_residuals(calib, views) if views else [])
    shown = own or views
    multi = calib.method == "multi-pose"
    sections = [_verdict_section(calib, verdict, check),
                _section("parameters", _parameters_section(calib)),
                _section("coverage", _coverage_section(calib, shown if not decodes else views, decodes)),
                _section("residuals", _residuals_section(calib, per_pose, verdict))]
    if calib.projector is not None:
        sections.append(_section("verification", _verification_section(calib, check)))
    sections.append(_section("rig", _rig_section(calib, shown)))
    if multi:
        sections.append(_section("leave-one-out", _loo_section(check)))
    head = (f'<p class="meta">{_e(calib.method)} calibration of a {calib.camera.image_size[0]}x'
            f'{calib.camera.image_size[1]} camera'
            + (f" and a {calib.projector.image_size[0]}x{calib.projector.image_size[1]} projector"
               if calib.projector is not None else "")
            + f", {len(calib.poses)} pose{'s' if len(calib.poses) != 1 else ''}; procam {_e(__version__)}.</p>")
    extra = "".join(f'<p class="note">{_e(n)}</p>' for n in notes)
    return "\n".join([
        "<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
        f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>procam report: {_e(name)}</title>", f"<style>{_CSS}</style>", "</head>", "<body>", "<main>",
        f"<h1>procam calibration report: {_e(name)}</h1>", head, extra, *sections,
        '<p class="meta">Self-contained page: every figure is inline; it loads nothing from anywhere.</p>',
        "</main>", "</body>", "</html>", ""])


def write_report(text: str, path) -> Path:
    """Write the page ``text`` to ``path`` (UTF-8, atomically: temporary name, then rename)."""
    from ._files import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(text.encode("utf-8"))
    return path
