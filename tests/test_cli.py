"""The CLI end to end on a rendered capture, including its error messages."""

import json
import warnings
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import run_cli

from procam import io
from procam.errors import ProcamWarning


def test_calibrate_single_pose_end_to_end(ideal_capture, tmp_path):
    folder, _, truth, _ = ideal_capture
    out, yml, png = tmp_path / "calib.json", tmp_path / "calib.yml", tmp_path / "res.png"
    code, stdout, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "24", "-o", out,
                                 "--yaml", yml, "--png", png])
    assert code == 0, err
    assert "single-pose" in stdout and "±" in stdout
    c = io.load_calibration(out)
    assert abs(c.camera.K[0, 0] - truth["camera"]["f"]) < 40
    assert abs(c.projector.K[0, 0] - truth["projector"]["f"]) < 15
    assert np.linalg.norm(c.T - truth["extrinsics"]["T"]) < 10
    y = io.load_calibration(yml)
    assert np.allclose(y.projector.K, c.projector.K) and np.allclose(y.R, c.R)
    assert cv2.imread(str(png)) is not None
    doc = json.loads(out.read_text())
    assert doc["poses"][0]["advice"]["camera"]["paper_rule_ok"]


def test_output_in_a_legacy_encoding_writes_escapes_not_an_internal_error(ideal_capture, tmp_path):
    """stdout in cp1252 or ascii (Windows output redirected to a file) cannot encode the table's sigma and +-: they
    are written as backslash escapes and the calibration is written (it was exit 1 before any file), and the
    streams' own error handling is left as it was after the command."""
    import os
    import subprocess

    folder = ideal_capture[0]
    script = ("import sys; from procam.cli import main\ntry:\n    main()\nexcept SystemExit as e:\n    code = e.code\n"
              "print('after', code, sys.stdout.errors, file=sys.stderr)")
    env = {**os.environ, "PYTHONIOENCODING": "ascii",
           "PYTHONPATH": os.pathsep.join([str(Path(__file__).resolve().parents[1] / "src"), os.environ.get("PYTHONPATH", "")])}
    out = tmp_path / "calib.json"
    res = subprocess.run([sys.executable, "-c", script, "calibrate", str(folder), "--board", "10x6", "--square", "24",
                          "-o", str(out)], env=env, capture_output=True, timeout=300)
    assert res.stderr.decode("ascii").strip().splitlines()[-1] == "after 0 strict", res.stderr
    assert "\\xb1" in res.stdout.decode("ascii") and io.load_calibration(out).projector is not None


@pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="the file system takes only valid names")
def test_a_folder_named_with_undecodable_bytes_is_calibrated_decoded_and_reported(ideal_capture, tmp_path):
    """A pose folder whose name is not UTF-8 (a byte 0xFF: an old archive, a USB stick): every figure's title and
    the report show the byte as an escape. Each command was an internal error in matplotlib after its main files
    were written."""
    import os
    import shutil

    folder = Path(os.fsdecode(os.path.join(os.fsencode(tmp_path), b"pose\xff1")))
    shutil.copytree(ideal_capture[0], folder)
    c = tmp_path / "c.json"
    for args in (["calibrate", folder, "--board", "10x6", "--square", "24", "-o", c, "--png", tmp_path / "c.png"],
                 ["decode", folder, "-o", tmp_path / "m.npz", "--png", tmp_path / "m.png"],
                 ["report", c, "-o", tmp_path / "r.html"]):
        code, out, err = run_cli(args)
        assert code == 0, (args[0], err)
    assert "pose\\xff1" in (tmp_path / "r.html").read_text(encoding="utf-8")
    assert cv2.imread(str(tmp_path / "c.png")) is not None and cv2.imread(str(tmp_path / "m.png")) is not None


def test_names_are_shown_with_their_control_characters_and_undecodable_bytes_escaped(tmp_path):
    """A folder named with a terminal's escape sequence is named in the error line with the escape written out (a
    raw ESC would recolour or rewrite the user's terminal); text, tabs and line breaks are left as they are."""
    from procam.style import shown

    assert shown("a\x1b[31mred\tb\nc\r\x85") == "a\\x1b[31mred\tb\nc\\r\\x85"
    assert shown("pose\udcff1 \u00e9\u00b1\u03c3") == "pose\\xff1 \u00e9\u00b1\u03c3"
    code, out, err = run_cli(["decode", tmp_path / "pose\x1b[2J", "-o", tmp_path / "m.npz"])
    assert code == 2 and "\x1b" not in err and "pose\\x1b[2J: no such folder" in err


def test_names_that_look_like_emoji_codes_are_shown_as_typed(tmp_path):
    """rich turned ':smile:' in a folder's name, and 'opencv:thumbs_up' in an option, into emoji."""
    code, out, err = run_cli(["decode", tmp_path / ":smile:", "-o", tmp_path / "m.npz"])
    assert code == 2 and ":smile:: no such folder" in err and "\U0001f604" not in err, err
    code, out, err = run_cli(["capture", tmp_path / "x", "--camera", "opencv:thumbs_up"])
    assert code == 2 and err.startswith("error: --camera opencv:thumbs_up: opencv takes"), err


def test_calibrate_errors(ideal_capture, tmp_path):
    folder, _, _, _ = ideal_capture
    out = tmp_path / "c.json"
    code, _, err = run_cli(["calibrate", folder, "--board", "10x6", "--square", "-3", "-o", out])
    assert code != 0 and "--square" in err
    code, _, err = run_cli(["calibrate", folder, "--board", "ten", "--square", "24", "-o", out])
    assert code == 2 and "--board" in err
    code, _, err = run_cli(["calibrate", folder, "--board", "9x6", "--square", "24", "-o", out])
    assert code == 2 and "not found" in err and "inner corners" in err
    assert not out.exists()


def test_camera_only_on_a_real_photo(shared_data, tmp_path):
    out = tmp_path / "cam.json"
    img = shared_data / "opencv-left-right" / "left12.jpg"
    code, stdout, err = run_cli(["calibrate", "--camera-only", img, "--board", "9x6", "--square", "25", "-o", out])
    assert code == 0, err
    c = io.load_calibration(out)
    assert c.projector is None and c.camera.image_size == (640, 480) and c.method == "camera-only"
    assert 400 < c.camera.K[0, 0] < 700  # reference 536; one photo is coarse
    code, _, err = run_cli(["calibrate", "--camera-only", img, "--board", "10x6", "--square", "25", "-o", out])
    assert code == 2 and "not found" in err


def test_demo_runs(tmp_path):
    code, stdout, err = run_cli(["demo", tmp_path / "demo"])
    assert code == 0, err
    assert "estimate vs truth" in stdout
    s = json.loads((tmp_path / "demo" / "demo_summary.json").read_text())
    assert abs(s["projector_f"][1] - s["projector_f"][0]) < 20
    assert (tmp_path / "demo" / "calib.yml").is_file() and (tmp_path / "demo" / "capture" / "truth.json").is_file()


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


#: Examples whose stage other fast tests run already: slow (``pytest -m slow`` runs them).
SLOW_EXAMPLES = ("plot_decode.py", "plot_study_slice.py")


@pytest.mark.parametrize("name", [pytest.param(p.name, marks=pytest.mark.slow) if p.name in SLOW_EXAMPLES else p.name
                                  for p in sorted(EXAMPLES.glob("plot_*.py"))])
def test_gallery_examples_run(name, tmp_path, monkeypatch):
    """Every gallery example (examples/plot_*.py) runs and writes its figure to the path it is given."""
    import runpy

    out = tmp_path / "figure.png"
    monkeypatch.setattr(sys, "argv", [name, str(out)])
    runpy.run_path(str(EXAMPLES / name), run_name="__main__")
    assert out.is_file() and out.read_bytes().startswith(b"\x89PNG")


def test_gallery_is_complete():
    assert {"plot_decode.py", "plot_correspondences.py", "plot_single_pose.py", "plot_residuals.py",
            "plot_study_slice.py"} <= {p.name for p in EXAMPLES.glob("plot_*.py")}


def test_commands_that_draw_nothing_import_no_matplotlib_or_simulator(tmp_path):
    """`procam patterns` and `procam decode` without --png run without importing matplotlib or the simulator
    (checked in a fresh interpreter, through the console-script entry point)."""
    import os
    import subprocess

    script = """
import json, sys
from procam.cli import main
try:
    main(sys.argv[1:])
except SystemExit as e:
    code = e.code
loaded = [m for m in ("matplotlib", "procam.simulate", "procam.plots", "procam.paper") if m in sys.modules]
print(json.dumps({"code": code, "loaded": loaded}), file=sys.stderr)
"""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[1] / "src"), env.get("PYTHONPATH", "")])
    folder = tmp_path / "seq"
    for args in (["patterns", "--projector", "64x32", "-o", folder], ["decode", folder, "-o", tmp_path / "m.npz"]):
        res = subprocess.run([sys.executable, "-c", script, *map(str, args)], env=env, capture_output=True,
                             text=True, timeout=120)
        report = json.loads(res.stderr.strip().splitlines()[-1])
        assert report == {"code": 0, "loaded": []}, (args, res.stderr)
    assert (tmp_path / "m.npz").is_file()


def test_user_mistakes_give_one_line_errors(ideal_capture, tmp_path, shared_data):
    """Review findings: each of these used to print a traceback or a misleading message."""
    folder, _, _, _ = ideal_capture
    img = shared_data / "opencv-left-right" / "left01.jpg"
    base = ["--board", "10x6", "--square", "24"]
    cases = [
        (["calibrate", folder, *base, "-o", "/proc/nope/c.json"], "cannot create the folder"),
        (["calibrate", folder, *base, "-o", tmp_path / "c.json", "--png", tmp_path / "r.xyz"], "must end in"),
        (["calibrate", folder, "--board", "10x6", "--square", "nan", "-o", tmp_path / "c.json"], "--square"),
        (["calibrate", folder, folder, *base, "--method", "multi", "--cam-dist", "fisheye", "-o",
          tmp_path / "c.json"], "--cam-dist"),
        (["calibrate", folder, folder, *base, "--method", "single", "-o", tmp_path / "c.json"], "one pose folder"),
        (["calibrate", "--camera-only", img, "--board", "9x6", "--square", "25", "-o", tmp_path / "c.yml"],
         "camera-only"),
        (["calibrate", "--camera-only", tmp_path, "--board", "9x6", "--square", "25", "-o", tmp_path / "c.json"],
         "no images found"),  # a folder is a pose folder to --camera-only: this one holds none
        (["calibrate", "--camera-only", tmp_path / "nope.jpg", "--board", "9x6", "--square", "25", "-o",
          tmp_path / "c.json"], "no such file"),
        (["correspond", folder, *base, "-o", tmp_path / "c.txt"], "must end in .json"),
        (["patterns", "--projector", "64x32", "-o", "/proc/nope"], "/proc/nope"),
    ]
    for args, needle in cases:
        code, _, err = run_cli(args)
        assert code == 2 and needle in err and "Traceback" not in err, (args, err)
    assert not (tmp_path / "c.json").exists() and not (tmp_path / "c.yml").exists()
    (tmp_path / "list.json").write_text("[1, 2]")
    code, _, err = run_cli(["evaluate", tmp_path / "list.json", folder, *base])
    assert code == 2 and "not a procam calibration" in err


@pytest.mark.parametrize("args, words", [
    (["study", "-o", "x", "--trials", "0"], "Missing argument 'device'. Choose from: camera, projector"),
    (["study", "tripod", "-o", "x"], "'tripod' is not one of"),
    (["calibrate"], "Missing argument 'poses'"),
    (["export", "c.json", "--format", "opengl", "--nope"], "No such option: --nope"),
])
def test_usage_errors_are_one_line(args, words, tmp_path, monkeypatch):
    """click words some usage errors over several lines (a missing choice argument lists its choices one per
    line): every one is a single line naming the command's help, exit code 2."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args)
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1 and "--help'" in err, err
    assert list(tmp_path.iterdir()) == []


def test_bad_patterns_json(ideal_capture, tmp_path):
    import shutil

    folder, _, _, _ = ideal_capture
    copy = tmp_path / "pose"
    shutil.copytree(folder, copy)
    (copy / "patterns.json").write_text('{"height": 1080}')
    code, _, err = run_cli(["decode", copy])
    assert code == 2 and "patterns.json: no valid width/height" in err


def test_readme_python_example_runs(paper_capture, tmp_path, monkeypatch):
    """The README's Python API block, run as written on a rendered pose folder named pose1."""
    import re
    import shutil

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    code = re.search(r"## Python API\s+```python\n(.*?)```", readme, re.S).group(1)
    folder, _, truth, scene = paper_capture
    shutil.copytree(folder, tmp_path / "pose1")
    monkeypatch.chdir(tmp_path)
    ns = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ProcamWarning)
        exec(compile(code, "README.md", "exec"), ns)
    calib = ns["calib"]
    assert calib.verdict in ("good", "weak")
    assert abs(calib.projector.K[0, 0] - scene.K_proj[0, 0]) < 5 * calib.std["f_p"] + 10
    assert (tmp_path / "calib.json").is_file() and (tmp_path / "calib.yml").is_file()


def test_no_command_has_two_options_with_one_name():
    """Every flag of every command means one thing (``procam experiment`` once had two ``--refine``)."""
    import typer.main

    from procam.cli import app

    group = typer.main.get_command(app)
    for name, cmd in group.commands.items():
        flags = [f for p in cmd.params for f in (*p.opts, *p.secondary_opts) if f.startswith("-")]
        dup = {f for f in flags if flags.count(f) > 1}
        assert not dup, (name, dup)


def test_commands_that_read_poses_share_the_capture_options():
    """calibrate, check, correspond, evaluate, experiment and report take the same capture-processing options
    with the same defaults (one definition: ``cli._options.POSE_OPTIONS``)."""
    import typer.main

    from procam.cli import app

    group = typer.main.get_command(app)
    want = {"--decode", "--shadow-threshold", "--contrast-threshold", "--detector", "--refine-window",
            "--corner-refine", "--window", "--estimator"}
    seen = {}
    for name in ("calibrate", "check", "correspond", "evaluate", "experiment", "report"):
        opts = {p.opts[0]: p.default for p in group.commands[name].params if p.opts and p.opts[0] in want}
        assert set(opts) == want, (name, want - set(opts))
        seen[name] = opts
    assert all(v == seen["calibrate"] for v in seen.values())
