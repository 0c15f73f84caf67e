"""A calibrated rig in rows of text: the tables ``procam calibrate`` prints for a rig and its HTML report shows
(:class:`procam.summary.TextTable`, every cell a string, so the terminal and the page show the same cells).

The devices with their intrinsics ± std and verdict (:func:`device_table`), every relative pose with its std
(:func:`relative_table`, projector to projector included) and the pairs' 3-D agreement (:func:`agreement_table`,
:func:`procam.rig.verify.verify_rig`).  Every ± is the calibration's 1 sigma; what it assumes is the rig's
``uncertainty`` text.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..summary import TextTable

__all__ = ["device_table", "relative_table", "agreement_table"]


def _pm(v, s, fmt=".1f") -> str:
    """``v ± s``; ``v`` alone when the std is unknown (None or not finite)."""
    if s is None or not np.isfinite(float(s)):
        return f"{v:{fmt}}"
    return f"{v:{fmt}} ± {float(s):{fmt}}"


def device_table(rc) -> TextTable:
    """One row per device: name (``(ref)`` for the reference camera), kind, f, fy, u0, v0 (px, ± std), its centre
    in the reference frame and its verdict."""
    rows = []
    for d in rc.devices:
        K, s = np.asarray(d.device.K), d.std
        rows.append((d.name + (" (ref)" if d.name == rc.reference else ""), d.kind, _pm(K[0, 0], s.get("f")),
                     _pm(K[1, 1], s.get("fy")), _pm(K[0, 2], s.get("u0")), _pm(K[1, 2], s.get("v0")),
                     "(" + ", ".join(f"{v:.1f}" for v in d.center) + ")", d.verdict))
    return TextTable(("device", "kind", "f (px)", "fy (px)", "u0 (px)", "v0 (px)", "centre (ref frame)", "verdict"),
                     tuple(rows), left=2)


def relative_table(rc) -> TextTable:
    """Every relative pose ``a -> b`` (``x_b = R x_a + T``): which kinds of device it links, the baseline, T and
    the Euler angles, each ± its std."""
    rows = []
    for k, rel in rc.relative.items():
        kinds = f"{rc.device(rel.a).kind} -> {rc.device(rel.b).kind}"
        rows.append((k, kinds, _pm(rel.baseline, rel.std_baseline, ".2f"),
                     ", ".join(_pm(v, s, ".2f") for v, s in zip(rel.T, rel.std_T)),
                     ", ".join(_pm(v, s, ".3f") for v, s in zip(rel.angles_deg, rel.std_angles_deg))))
    return TextTable(("a -> b", "devices", "baseline", "T", "angles (psi, nu, phi)"), tuple(rows), left=2)


def agreement_table(agreement) -> TextTable:
    """The pairs' 3-D agreement per pose (:class:`procam.rig.verify.PairAgreement`); a pair of pairs with too few
    common corners shows n = 0 and empty figures."""
    def f(x, spec):
        return f"{x:{spec}}" if np.isfinite(x) else ""

    rows = tuple((Path(a.pose).name, f"{a.a} vs {a.b}", str(a.n), f(a.rms_mm, ".3f"), f(a.max_mm, ".3f"),
                  f(a.rms_pct, ".3f"), f(a.mean_depth_mm, ".0f")) for a in agreement)
    return TextTable(("pose", "pairs", "n", "rms (mm)", "max (mm)", "rms (% depth)", "depth (mm)"), rows, left=2)
