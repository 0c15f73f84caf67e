"""The figures of docs/datasheet.md and docs/exports.md: the datasheet's throw ratio and lens shift, the engines'
frames and pixel origins, and the rectification of a floor rig (projector below the camera).

    python examples/export_figures.py docs/figures

Every number drawn comes from procam (procam.datasheet, procam.export, the simulator's ``vertical`` rig).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from procam import datasheet, simulate  # noqa: E402
from procam.export import rectify  # noqa: E402

META = {"Creator": "procam"}


def datasheet_figure(path):
    """Side view (vertical shift, throw ratio) and the panel seen from behind the projector (both shifts)."""
    W, H, tr, sh, sv = 1920, 1080, 1.2, 8.0, 62.0
    K = datasheet.intrinsic_matrix(W, H, throw_ratio=tr, shift_h=sh, shift_v=sv)
    v = datasheet.datasheet_view(K, (W, H))
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.4), gridspec_kw={"width_ratios": [1.35, 1]})
    # side view: the lens at the origin, the screen at distance D, y up
    D = 1.0
    top = (K[1, 2] + 0.5) / K[1, 1] * D            # panel row -0.5 (top edge) goes up by (v0 + 0.5) / fy
    bottom = (K[1, 2] - (H - 0.5)) / K[1, 1] * D
    a.plot([0, D], [0, 0], "k-.", lw=1)
    a.text(0.5 * D, -0.035, "lens axis", ha="center", va="top")
    a.fill([0, D, D], [0, top, bottom], color="tab:orange", alpha=0.15)
    a.plot([0, D], [0, top], color="tab:orange")
    a.plot([0, D], [0, bottom], color="tab:orange")
    a.plot([D, D], [bottom, top], color="tab:red", lw=4)
    mid = 0.5 * (top + bottom)
    a.plot([D - 0.02, D + 0.02], [mid, mid], "r-")
    a.annotate("", xy=(D + 0.08, mid), xytext=(D + 0.08, 0), arrowprops=dict(arrowstyle="<->"))
    a.text(D + 0.1, mid / 2, f"shift = {v.shift_v_pct:.0f} % of\nthe image height\n(+ : image above the axis)",
           va="center")
    a.annotate("", xy=(0, -0.12), xytext=(D, -0.12), arrowprops=dict(arrowstyle="<->"))
    a.text(0.5 * D, -0.14, "throw distance D (along the lens axis, screen square to it)", ha="center", va="top")
    a.plot(0, 0, "ks", ms=10)
    a.text(0, 0.05, "projector\n(lens)", ha="center", va="bottom")
    a.set_xlim(-0.15, 1.75)
    a.set_ylim(-0.25, top + 0.1)
    a.set_aspect("equal")
    a.axis("off")
    a.set_title(f"side view: throw ratio = D / image width = f / W = {v.throw_ratio:.2f}")
    # the panel seen from behind the projector (as it throws the image), principal point = the lens axis
    b.add_patch(plt.Rectangle((-0.5, -0.5), W, H, fill=True, color="tab:red", alpha=0.15))
    b.add_patch(plt.Rectangle((-0.5, -0.5), W, H, fill=False, color="tab:red", lw=2))
    b.plot((W - 1) / 2, (H - 1) / 2, "r+", ms=14, mew=2)
    b.text((W - 1) / 2, (H - 1) / 2 - 60, "image centre", ha="center", color="tab:red")
    b.plot(K[0, 2], K[1, 2], "ko")
    b.text(K[0, 2] + 40, K[1, 2] + 40, f"lens axis (u0, v0) = ({K[0, 2]:.0f}, {K[1, 2]:.0f}) px",
           va="top")
    b.annotate("", xy=((W - 1) / 2, K[1, 2]), xytext=(K[0, 2], K[1, 2]), arrowprops=dict(arrowstyle="->"))
    b.text(0.5 * ((W - 1) / 2 + K[0, 2]), K[1, 2] - 30, f"horizontal {v.shift_h_pct:+.0f} %\n(+ : image right)",
           ha="center", va="bottom", fontsize=8)
    b.set_xlim(-200, W + 200)
    b.set_ylim(K[1, 2] + 250, -200)
    b.set_aspect("equal")
    b.set_title("the panel from behind the projector (pixels, y down)")
    b.set_xlabel("x (column)")
    b.set_ylabel("y (row)")
    fig.suptitle("Datasheet conventions (procam.datasheet): offset = 2 x vertical shift "
                 f"= {v.offset_pct:.0f} % of the half height")
    fig.tight_layout()
    fig.savefig(path, metadata=META)
    plt.close(fig)


def frames_figure(path):
    """The device frame (OpenCV) and the engines' frames and pixel origins."""
    fig, axes = plt.subplots(1, 4, figsize=(13, 3.4))
    specs = [("procam / OpenCV device", [("x", (1, 0)), ("y (down)", (0, -1))], "z forward (into the page)",
              "pixel (0, 0) = centre of the top-left pixel", (0.05, 0.95)),
             ("OpenGL / TouchDesigner eye", [("x", (1, 0)), ("y", (0, 1))], "looks down -z",
              "window (0, 0) = bottom-left corner", (0.0, 0.0)),
             ("Blender camera", [("x", (1, 0)), ("y", (0, 1))], "looks down -z; world z up",
              "frame (0, 0) = bottom-left corner, (1, 1) top-right", (0.0, 0.0)),
             ("Unity camera (left-handed)", [("x", (1, 0)), ("y", (0, 1))], "z forward (into the page)",
              "screen (0, 0) = bottom-left corner", (0.0, 0.0))]
    for ax, (title, arrows, depth, origin, o) in zip(axes, specs):
        ax.add_patch(plt.Rectangle((0, 0), 1, 0.7, fill=False, lw=1.5))
        for name, (dx, dy) in arrows:
            ax.annotate("", xy=(0.5 + 0.25 * dx, 0.35 + 0.25 * dy), xytext=(0.5, 0.35),
                        arrowprops=dict(arrowstyle="->", lw=2))
            ax.text(0.5 + 0.3 * dx, 0.35 + 0.3 * dy, name, ha="center", va="center")
        ax.plot(o[0], o[1] * 0.7, "ro")
        ax.text(0.5, -0.08, depth, ha="center", va="top", fontsize=8)
        ax.text(0.5, -0.2, origin, ha="center", va="top", fontsize=8, color="tab:red")
        ax.set_title(title, fontsize=10)
        ax.set_xlim(-0.1, 1.1)
        ax.set_ylim(-0.35, 0.8)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.suptitle("Device frames and pixel origins: procam pixel (x, y) = engine point (x + 0.5, H - y - 0.5) "
                 "(divide by W, H for Blender's frame)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, metadata=META)
    plt.close(fig)


def rectify_figure(path):
    """The vertical rig's corners in both images and after rectification (rows agree; the frame turned)."""
    sc = simulate.preset("vertical")
    calib = simulate.truth_calibration(sc)
    c = simulate.corner_truth(sc)
    rect = rectify.stereo_rectify(calib, scale=0.5)

    def rectified(dev, pts, R, P):
        und = dev.undistort(pts)
        ray = np.column_stack([und, np.ones(len(und))]) @ np.linalg.inv(dev.K).T @ R.T
        h = ray @ P[:, :3].T
        return h[:, :2] / h[:, 2:3]

    rc = rectified(calib.camera, c["camera_distorted"], rect["R1"], rect["P1"])
    rp = rectified(calib.projector, c["projector"], rect["R2"], rect["P2"])
    fig, axes = plt.subplots(1, 4, figsize=(14, 3.8))
    for ax, pts, size, title in ((axes[0], c["camera_distorted"], calib.camera.image_size, "camera image"),
                                 (axes[1], c["projector"], calib.projector.image_size, "projector image"),
                                 (axes[2], rc, rect["size1"], "camera, rectified"),
                                 (axes[3], rp, rect["size2"], "projector, rectified")):
        W, H = size
        ax.add_patch(plt.Rectangle((-0.5, -0.5), W, H, fill=False))
        ax.scatter(pts[:, 0], pts[:, 1], s=6, c=np.arange(len(pts)), cmap="viridis")
        ax.plot(pts[0, 0], pts[0, 1], "r*", ms=10)
        ax.set_xlim(-0.05 * W, 1.05 * W)
        ax.set_ylim(1.05 * H, -0.05 * H)
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=10)
    for ax in axes[2:]:
        for y in rc[:10, 1]:
            ax.axhline(y, color="tab:gray", lw=0.5)
    turn = rect["rows_along_deg"]
    fig.suptitle(f"Floor rig (projector 600 mm below the camera): epipolar lines are rows after rectification; the "
                 f"rectified frame is turned (rows at {turn['camera']:+.0f} deg in the camera image, "
                 f"{turn['projector']:+.0f} deg in the projector's); red star = corner 0", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, metadata=META)
    plt.close(fig)


def main(out="docs/figures"):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    plt.rcParams["svg.hashsalt"] = "procam"       # the same figure gives the same file
    datasheet_figure(out / "datasheet_conventions.svg")
    frames_figure(out / "engine_frames.svg")
    rectify_figure(out / "rectify_vertical.svg")


if __name__ == "__main__":
    main(*sys.argv[1:])
