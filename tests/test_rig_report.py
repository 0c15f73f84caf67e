"""The HTML report of a rig calibration (issue 27): every device's name, verdict and reasons, the relative poses
with their std (projector to projector included), the pairs' 3-D agreement, the rig drawn; from the library, from
``procam calibrate RIGPOSE... --report`` and ``procam report RIG.json``, read back from the file exactly, and in a
headless browser.  On the corner fast path (no rendering)."""

from __future__ import annotations

import functools
import html
import json
import re

import numpy as np
import pytest

from conftest import run_cli, verdict_warnings
from rig_sim import fake_rig_folders, fast_views


@functools.lru_cache(maxsize=None)
def _rig(n_poses=3):
    from procam.rig import calibrate_rig

    _, poses = fast_views("two_projectors", n_poses)
    with verdict_warnings():
        return calibrate_rig(poses), tuple(poses)


def _device_rows(page: str) -> dict:
    """{device: (kind, verdict, [reasons])} from the page's per-device verdict table."""
    out = {}
    for row in re.findall(r'<tr class="device-verdict [a-z]+">(.*?)</tr>', page, re.S):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)
        reasons = [html.unescape(r) for r in re.findall(r"<li>(.*?)</li>", cells[3])]
        out[html.unescape(cells[0])] = (cells[1], re.sub(r"<[^>]+>", "", cells[2]), reasons)
    return out


def test_rig_page_names_every_device_its_verdict_and_the_relative_std():
    from procam.report import build_rig_report
    from procam.rig.verify import verify_rig

    rc, poses = _rig()
    page = build_rig_report(rc, list(poses), name="two.json")
    rows = _device_rows(page)
    assert set(rows) == {"cam", "left", "right"}
    for d in rc.devices:
        kind, verdict, reasons = rows[d.name]
        assert (kind, verdict) == (d.kind, d.verdict)
        assert reasons == (list(d.verdict_reasons) or ["nothing flagged"])
    assert f'class="verdict {rc.verdict}"' in page
    for key, r in rc.relative.items():  # every relative pose, its baseline ± std as the CLI prints it
        assert f"{key}</td>" in page.replace("-&gt;", "->")
        assert f"{r.baseline:.2f} ± {r.std_baseline:.2f}" in page
    pp = rc.relative["left->right"]
    assert pp.std_baseline > 0 and "projector -&gt; projector" in page
    assert f"Projector to projector (left-&gt;right): baseline {pp.baseline:.2f} ± {pp.std_baseline:.2f}" in page
    for a in verify_rig(rc, poses):  # the agreement table holds verify_rig's figures
        assert a.n > 0 and f"{a.a} vs {a.b}" in page and f"<td>{a.rms_mm:.3f}</td>" in page
    for key in rc.pairs:  # each pair's ordinary parameter section
        assert f'id="pair-{key.replace("/", "-")}"' in page
    assert page.count('<img src="data:image/png;base64,') == 1  # the rig drawn, inline
    assert "http://" not in page and "https://" not in page


def test_rig_file_reads_back_exactly_and_its_page_verifies_on_the_poses_it_keeps(tmp_path):
    from procam.report import build_rig_report
    from procam.io import is_rig_calibration, load_rig_calibration, save_rig_calibration

    rc, poses = _rig()
    path = save_rig_calibration(rc, tmp_path / "rig.json")
    assert is_rig_calibration(path) and not is_rig_calibration(tmp_path / "nothing.json")
    back = load_rig_calibration(path)
    assert [d.name for d in back.devices] == [d.name for d in rc.devices]
    for a, b in zip(rc.devices, back.devices):
        assert np.array_equal(a.device.K, b.device.K) and np.array_equal(a.R, b.R) and np.array_equal(a.T, b.T)
        assert a.device.distortion == b.device.distortion and (a.verdict, a.verdict_reasons) == (b.verdict,
                                                                                               b.verdict_reasons)
    for k, r in rc.relative.items():
        assert np.array_equal(r.T, back.relative[k].T) and r.std_baseline == back.relative[k].std_baseline
        assert np.array_equal(r.std_angles_deg, back.relative[k].std_angles_deg)
    assert set(back.pairs) == set(rc.pairs) and all(len(c.views) == 3 for c in back.pairs.values())
    page = build_rig_report(back, name="rig.json")  # no poses given: the ones the pairs keep, said so
    assert "in-sample" in page and "cam/left vs cam/right" in page and "Not measured" not in page


def test_single_pose_rig_page_gives_each_projector_its_verdict():
    from procam.report import build_rig_report

    rc, poses = _rig(1)
    assert rc.method == "single-pose"
    page = build_rig_report(rc, list(poses))
    rows = _device_rows(page)
    assert {n: rows[n][1] for n in ("left", "right")} == {d.name: d.verdict for d in rc.projectors}
    assert "single-pose rig calibration of 1 camera and 2 projectors, 1 rig pose" in page


def test_calibrate_rig_with_report_and_report_of_the_rig_file(monkeypatch, tmp_path):
    _, folders = fake_rig_folders(monkeypatch, tmp_path)
    out, page = tmp_path / "rig.json", tmp_path / "rig.html"
    code, stdout, err = run_cli(["calibrate", *folders, "--board", "10x6", "--square", "24", "-o", out,
                                 "--report", page])
    assert code == 0, stdout + err
    text = page.read_text()
    doc = json.loads(out.read_text())
    assert "procam rig calibration report: rig.json" in text and "the rig poses given" in text
    for name, d in {**doc["cameras"], **doc["projectors"]}.items():
        assert f'<td class="l">{name}</td>' in text and d["verdict"]["level"] in text
    again = tmp_path / "again.html"
    code, stdout, err = run_cli(["report", out, "-o", again])
    assert code == 0, stdout + err
    assert "in-sample" in again.read_text() and f"{doc['relative']['left->right']['baseline']:.2f} ±" in again.read_text()
    two = tmp_path / "two.html"
    code, stdout, err = run_cli(["report", out, *folders[:2], "--board", "10x6", "--square", "24", "-o", two])
    assert code == 0, stdout + err
    agreement = two.read_text().split('id="agreement"')[1].split("</section>")[0]
    assert "the rig poses given" in agreement and "pose2" in agreement and "pose3" not in agreement


def test_report_of_a_rig_file_refuses_ordinary_pose_folders(monkeypatch, tmp_path):
    _, folders = fake_rig_folders(monkeypatch, tmp_path, n_poses=2)
    out = tmp_path / "rig.json"
    assert run_cli(["calibrate", *folders, "--board", "10x6", "--square", "24", "-o", out])[0] == 0
    plain = tmp_path / "plain"
    plain.mkdir()
    code, _, err = run_cli(["report", out, plain, "--board", "10x6", "--square", "24", "-o", tmp_path / "r.html"])
    assert code == 2 and "not a rig pose folder" in err and not (tmp_path / "r.html").exists()


def test_rig_report_in_headless_chromium(tmp_path):
    """Headless Chromium renders the rig page: every section there with a visible body, the drawing loaded, the
    console clean and no request but the page and its data: image."""
    from browser import Browser, find_chromium

    from procam.report import build_rig_report, write_report

    exe = find_chromium()
    if exe is None:
        pytest.skip("no Chromium on this machine (Debian: apt-get install chromium)")
    rc, poses = _rig()
    path = write_report(build_rig_report(rc, list(poses), name="rig"), tmp_path / "rig.html")
    with Browser(exe) as b:
        b.open(path.as_uri())
        found = json.loads(b.evaluate("""JSON.stringify([...document.querySelectorAll('section')].map(s => {
            const r = s.getBoundingClientRect(); return [s.id, r.height > 40 && r.width > 500]; }))"""))
        images = b.evaluate("[...document.images].every(i => i.complete && i.naturalWidth > 400)")
        b.drain()
        problems, requests = b.console_problems(), b.requests()
    ids = [f[0] for f in found]
    assert ids[:5] == ["verdict", "drawing", "devices", "relative", "agreement"]
    assert sorted(ids[5:]) == ["pair-cam-left", "pair-cam-right"] and all(f[1] for f in found)
    assert images and problems == [], problems
    assert requests and all(u.startswith(("file:", "data:")) for u in requests), requests
