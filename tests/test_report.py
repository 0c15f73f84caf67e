"""The HTML report (procam.report): its sections and numbers, its size, and the page in a real headless Chromium."""

from __future__ import annotations

import functools
import html as _html
import os
import re
from pathlib import Path

import numpy as np
import pytest

from procam import multi_pose, simulate, single_pose
from procam.report import SECTIONS, build_report, coverage_fractions, rig_geometry, write_report
from procam.summary import PLUS_MINUS, parameter_rows
from procam.verdict import Verdict, calibration_verdict
from procam.verify import verify_calibration
from procam.view import View
from procam.errors import WeakPoseWarning
from conftest import expect_warning, verdict_warnings

# five poses well inside both devices' fields of view, well away from the single-pose degeneracies
POSES = [(15, 12, 0), (-10, 20, 5), (20, -15, -5), (5, 25, 10), (-20, -10, 0)]


@functools.lru_cache(maxsize=None)
def _views(prefix="/data/run 3/pose"):
    sc = simulate.preset("paper")
    out = []
    for k, p in enumerate(POSES):
        s = simulate.with_board_pose(sc, p)
        obj, cam, proj = simulate.correspondences(s, sigma_cam=0.1, sigma_proj=0.2, seed=k)
        out.append(View(obj, cam, proj, f"{prefix}{k + 1}", s.cam_size, s.proj_size))
    return tuple(out)


@functools.lru_cache(maxsize=None)
def _multi():
    calib = multi_pose.calibrate(list(_views()))
    return calib, verify_calibration(calib)


@functools.lru_cache(maxsize=None)
def _multi_page():
    calib, check = _multi()
    return build_report(calib, check=check, name="five.json")


def _section(page: str, sid: str) -> str:
    m = re.search(rf'<section id="{sid}"[^>]*>(.*?)</section>', page, re.S)
    assert m, f"no section {sid}"
    return m.group(1)


def _text(fragment: str) -> str:
    return " ".join(_html.unescape(re.sub(r"<[^>]+>", " ", fragment)).split())


def _single(angles=simulate.RECOMMENDED_POSE, seed=0, outliers=True, name="/data/single/pose1", **kw):
    sc = simulate.with_board_pose(simulate.preset("paper"), angles)
    obj, cam, proj = simulate.correspondences(sc, 0.1, 0.2, seed=seed)
    if outliers:
        cam[5] += 3.0
        proj[7] += 5.0
    view = View(obj, cam, proj, name, sc.cam_size, sc.proj_size)
    with verdict_warnings():            # the report shows the verdict; the tests check it there
        return single_pose.calibrate(view, **kw), view


# ---------------------------------------------------------------------------------------------------
# content
# ---------------------------------------------------------------------------------------------------

def test_multi_pose_report_has_every_section_in_order_and_is_small():
    page = _multi_page()
    ids = re.findall(r'<section id="([^"]+)"', page)
    assert ids == list(SECTIONS)  # verdict first, leave-one-out last
    size = len(page.encode("utf-8"))
    print(f"5-pose multi-pose report: {size / 1e6:.2f} MB")
    assert size < 5e6
    # self-contained: a CSP that forbids every other source, only data: images, no external reference
    assert "Content-Security-Policy" in page and "default-src 'none'" in page
    assert not re.search(r'(src|href)\s*=\s*"(?!data:|#)', page)
    assert "http://" not in page and "https://" not in page
    assert len(re.findall(r'<img src="data:image/png;base64,', page)) == 2  # coverage, residuals


def test_numbers_are_the_calibrations():
    calib, check = _multi()
    page = _multi_page()
    params = _text(_section(page, "parameters"))
    for name, cam, proj in parameter_rows(calib):
        for cell in (cam, proj):
            assert cell in params, (name, cell)
    assert PLUS_MINUS in params
    res = _text(_section(page, "residuals"))
    # the pooled row of the residual table is the calibration's own RMS
    assert re.search(rf"all\s+{calib.cam_rms:.3f}\s+300\s+0\s+{calib.proj_rms:.3f}\s+300\s+0", res), res
    ver = _text(_section(page, "verification"))
    o = check.in_sample.overall
    cells = [str(o.n_pairs), f"{o.scale_error_pct:+.3f}", f"{o.spacing_rms:.3f}", f"{o.planarity_rms:.3f}"]
    assert re.search(r"all\s+300\s+" + r"\s+".join(map(re.escape, cells)), ver), ver  # the CLI's columns
    loo = _text(_section(page, "leave-one-out"))
    lo = check.leave_one_out.held_out.overall
    assert f"{lo.scale_error_pct:+.3f}" in loo and f"{lo.rigid_rms:.3f}" in loo
    for k in range(1, 6):
        assert f"pose{k}" in loo and "/data/run 3" not in loo  # short pose names
    verdict = _text(_section(page, "verdict"))
    assert "Verdict: good" in verdict and f"{calib.cam_rms:.3f}" in verdict


def test_single_pose_report_names_its_assumptions_and_marks_outliers():
    calib, view = _single()
    page = build_report(calib, name="single.json")
    params = _text(_section(page, "parameters"))
    W = calib.projector.image_size[0]
    assert f"u0p = W/2 = {W / 2:g} px is ASSUMED" in params
    assert "alpha_p = 1" in params and "NO lens distortion" in params
    assert "(assumed W/2)" in params and "(assumed = f)" in params
    assert PLUS_MINUS in params
    res = _text(_section(page, "residuals"))
    assert re.search(rf"pose1\s+{calib.cam_rms:.3f}\s+59\s+1\s+{calib.proj_rms:.3f}\s+59\s+1", res), res
    assert "leave-one-out" not in re.findall(r'<section id="([^"]+)"', page)
    notes = _text(_section(page, "verification"))
    assert "own pose only" in notes


def test_held_out_poses_are_verified_separately():
    calib, view = _single(outliers=False, seed=7)  # (the same corners as a pose of _views() would be that pose)
    page = build_report(calib, [view, *_views()[:2]], name="s.json")
    ver = _text(_section(page, "verification"))
    assert "in-sample" in ver and "held out" in ver
    check = verify_calibration(calib, [view, *_views()[:2]])
    assert [p.name for p in check.in_sample.poses] == [view.name]
    assert [p.name for p in check.held_out.poses] == [v.name for v in _views()[:2]]
    assert f"{check.held_out.overall.scale_error_pct:+.3f}" in ver


def test_user_strings_are_escaped():
    calib, view = _single(outliers=False, name="<script>alert('x')</script> & co")
    page = build_report(calib, name="<b>evil</b>.json")
    assert "<script>alert" not in page and "<b>evil</b>" not in page
    assert "&lt;b&gt;evil&lt;/b&gt;.json" in page
    assert "\\u003cscript\\u003e" in page or "&lt;script&gt;" in page
    assert page.count("<script") == 2  # the rig's data block and its script, nothing else


def test_degenerate_pose_says_so_first():
    calib, _ = _single((20, 0.3, 0), outliers=False)
    v = calibration_verdict(calib)
    assert v.word == "degenerate" and "degenerate pose" in v.reasons[0]
    page = build_report(calib, verify=False)
    first = re.search(r'<section id="([^"]+)" class="verdict (\w+)"', page)
    assert first.groups() == ("verdict", "degenerate")


def test_verdict_words():
    calib, _ = _multi()
    assert calibration_verdict(calib) == Verdict("good", ("5 poses, jointly refined, no warnings",))
    with expect_warning(WeakPoseWarning, match="only 2 poses"):
        two = multi_pose.calibrate(list(_views()[:2]))
    assert calibration_verdict(two).word == "weak"
    assert calibration_verdict(calib.replace(poses=(), verdict="unknown")).word == "unknown"

    def advised(**flags):  # a file that records advice but no verdict: derived from the advice
        adv = {"camera": {"failed": False, "degenerate": False, "weak": False, "message": "camera: pose OK"},
               "projector": {"failed": False, "degenerate": False, "weak": False, "message": "projector: pose OK"}}
        adv["projector"].update(flags, message="projector: " + ",".join(flags))
        return calib.replace(poses=({"name": "p", "advice": adv},), warnings=(), method="single-pose", verdict="unknown")

    assert calibration_verdict(advised()).word == "good"
    assert calibration_verdict(advised(weak=True)).word == "weak"
    assert calibration_verdict(advised(degenerate=True)).word == "degenerate"
    v = calibration_verdict(advised(degenerate=True, failed=True))
    assert v.word == "failed" and v.reasons == ("projector: degenerate,failed",)


def test_coverage_and_rig_geometry():
    calib, _ = _multi()
    cov = coverage_fractions(calib.views, calib.camera.image_size, calib.projector.image_size)
    assert 0.1 < cov["camera"] < 0.6 and 0.1 < cov["projector"] < 0.6
    g = rig_geometry(calib, calib.views)
    boards = [p for p in g["paths"] if p["cls"] == "board"]
    assert [b["name"] for b in boards] == [f"pose{k}" for k in range(1, 6)]
    # a board outline lies at the board's distance, the projector's frustum apex at its centre
    assert 500 < g["distance"] < 800
    apex = [p["pts"][0] for p in g["paths"] if p["cls"] == "projector"][0]
    assert np.allclose(apex, -calib.R.T @ calib.T, atol=1e-9)


def test_write_report_is_atomic_utf8(tmp_path):
    path = write_report("<p>ψ ± σ</p>", tmp_path / "r.html")
    assert path.read_bytes() == "<p>ψ ± σ</p>".encode("utf-8")
    assert [p.name for p in tmp_path.iterdir()] == ["r.html"]


# ---------------------------------------------------------------------------------------------------
# the page in a real browser
# ---------------------------------------------------------------------------------------------------

def test_report_in_headless_chromium(tmp_path):
    """Headless Chromium renders the 5-pose report: every section there and visible, the console clean, no
    request but the page itself and its data: images, the rig turns when dragged; a full-page screenshot
    is saved (to $PROCAM_REPORT_SCREENSHOT if set) and its path, the size and the load time printed."""
    from browser import Browser, find_chromium

    exe = find_chromium()
    if exe is None:
        pytest.skip("no Chromium on this machine (Debian: apt-get install chromium)")
    page = _multi_page()
    path = write_report(page, tmp_path / "report.html")
    shot = Path(os.environ.get("PROCAM_REPORT_SCREENSHOT") or tmp_path / "report.png")
    with Browser(exe) as b:
        b.open(path.as_uri())
        found = b.evaluate("""JSON.stringify([...document.querySelectorAll('section')].map(s => {
            const r = s.getBoundingClientRect();
            return [s.id, s.querySelector('h2').textContent, r.height > 50 && r.width > 500]; }))""")
        import json

        found = json.loads(found)
        assert [f[0] for f in found] == list(SECTIONS)
        assert [f[1] for f in found][1:] == list(SECTIONS.values())[1:]
        assert found[0][1] == "Verdict: good" and all(f[2] for f in found)
        images = b.evaluate("[...document.images].every(i => i.complete && i.naturalWidth > 300)")
        assert images
        load_ms = b.evaluate("performance.getEntriesByType('navigation')[0].loadEventEnd")
        before = b.evaluate("document.getElementById('rig-p0').getAttribute('d')")
        b.evaluate("document.getElementById('rig-svg').scrollIntoView()")
        r = json.loads(b.evaluate("JSON.stringify(document.getElementById('rig-svg').getBoundingClientRect())"))
        cx, cy = r["x"] + r["width"] / 2, r["y"] + r["height"] / 2
        b.drag(cx, cy, cx + 120, cy + 40)
        after = b.evaluate("document.getElementById('rig-p0').getAttribute('d')")
        assert after != before  # the rig turned
        b.evaluate("window.scrollTo(0, 0)")
        w, h = b.screenshot(shot)
        b.drain()
        problems = b.console_problems()
        requests = b.requests()
    assert problems == [], problems
    assert requests and all(u.startswith(("file:", "data:")) for u in requests), requests
    assert shot.read_bytes().startswith(b"\x89PNG")
    print(f"\nreport {len(page.encode('utf-8')) / 1e6:.2f} MB, loaded in {load_ms:.0f} ms (navigation timing); "
          f"screenshot {w}x{h} px: {shot}")
