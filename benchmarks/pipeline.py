"""Benchmark: a five-pose ``procam calibrate`` against the time it takes to read its PNGs (issue 12).

Renders (once, into ``--data``) five poses of a 1280x1024 camera and a 1024x768 projector with procam's
simulator (42 PNGs each, OpenCV order, ``truth.json`` next to them), then, in one run and alternating the
commands round by round (the machine may be shared, so every command sees the same load):

1. ``procam calibrate pose1 .. pose5`` as a cold process (interpreter start and imports included);
2. a cold process that only reads the 210 PNGs with two threads (``cv2.imread`` grey, the function
   :func:`read_all` below) -- the floor any tool that reads PNGs with OpenCV must pay; and the same with procam's
   own reader (:func:`procam.io.images.read_image`, which decodes these PNGs itself, :mod:`procam.io.png`): the
   floor procam itself cannot go below;
3. ``procam --version`` and ``procam calibrate --help`` as cold processes (start-up; issue 35's targets 0.2 s
   and 0.3 s);
4. ``procam decode`` of a 12-frame phase capture (3 steps + the unit-frequency cue per axis, no white or black
   frame) against a 46-frame Gray capture of the same 1280x800 camera and 1920x1080 projector (the ``paper``
   rig, rendered into ``--data`` too): what a user waits for per capture (issue 35 item 2: a phase capture
   must be no slower);
5. with ``--kamino410 PATH --kamino410-python PY``: kamino410's ``calibrate.py`` (procam-calibration) on the
   same files (linked into its ``capture_*/graycode_*`` layout), run by its own Python (OpenCV contrib);
6. stand-ins for what the targets not met are up against: a cold process that only imports the third-party modules
   a calibrate imports (:data:`IMPORTS`) and the calibrate with the board's corners given (:data:`CORNERS_GIVEN`),
   each against the floor; and ``procam decode`` of the phase capture with the neighbours' ordering pass skipped
   (:data:`WITHOUT_NEIGHBOURS`), against the Gray capture.

The first table is the summary: each command against its baseline, as ratios of the medians of one run; the
second the stand-ins against theirs.

procam's source is byte-compiled first (as an installed package is).

Each command's wall time, CPU time (user + sys) and peak memory (max RSS) come from ``os.wait4``; the
tables print medians (and minima) over ``--repeat`` rounds and the ratios.  Then a per-stage profile of
``procam calibrate`` (in a fresh process: stage functions wrapped with timers, ``--stages`` runs), and the
accuracy of the result (parameters and corners against the simulator's truth; kamino410's too when run).

    OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/pipeline.py [--data DIR] [--repeat 7] [--stages 3]
        [--kamino410 PATH/calibrate.py --kamino410-python PATH/python]

kamino410's script is written for OpenCV 4 (``findChessboardCorners`` corners of shape (N, 1, 2)): its Python
needs ``opencv-contrib-python-headless<5`` (e.g. ``python -m venv K; K/bin/pip install numpy
"opencv-contrib-python-headless<5"``).

Stage times are wall seconds summed over calls; stages that run in a background thread (reading the next
pose while this one is processed) overlap the others, so their sum can exceed the run's wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
BOARD = ("10x6", "24")
N_POSES = 5
#: (psi, nu, phi) board -> camera in degrees, board-centre depth (mm), noise seed
POSES = [((20, 5, 0), 525, 101), ((-22, 10, 3), 500, 102), ((5, 20, -5), 500, 103), ((15, -22, 8), 500, 104),
         ((-12, -30, -6), 500, 105)]


# --------------------------------------------------------------------------------------------
# data
# --------------------------------------------------------------------------------------------

def base_scene():
    """The rig: 1280x1024 camera with Brown distortion, 1024x768 lens-shifted projector, 10x6 board of 24 mm."""
    import numpy as np

    from procam import simulate as S

    K_cam = np.array([[1850.0, 0, 642.0], [0, 1850.0 * 1.001, 508.0], [0, 0, 1]])
    K_proj = np.array([[1350.0, 0, 515.0], [0, 1350.0 * 1.002, 740.0], [0, 0, 1]])
    R = S.euler_matrix((9.0, 15.0, -0.5))
    T = -R @ np.array([165.0, 45.0, 10.0])  # projector centre (165, 45, 10) mm in the camera frame
    return S.Scene(cam_size=(1280, 1024), K_cam=K_cam, cam_distortion="opencv",
                   cam_dist_coeffs=(-0.09, 0.14, 0.0004, -0.0003, 0.0), proj_size=(1024, 768), K_proj=K_proj,
                   R=R, T=T, board_cols=10, board_rows=6, square=24.0, name="bench-5pose")


def pose_dirs(data: Path) -> list[Path]:
    return [data / f"pose{i}" for i in range(1, N_POSES + 1)]


def ensure_data(data: Path) -> None:
    """Render the five poses into ``data`` unless they are there already (checked by file count + truth)."""
    todo = [(i, p) for i, p in enumerate(pose_dirs(data)) if not ((p / "truth.json").is_file()
                                                                 and len(list(p.glob("[0-9][0-9].png"))) == 42)]
    if not todo:
        return
    from procam import simulate as S

    base = base_scene()
    for i, folder in todo:
        ang, dist, seed = POSES[i]
        t0 = time.perf_counter()
        sc = S.with_board_pose(base.replace(name=f"bench-pose{i + 1}"), ang, distance=dist)
        stack, truth = S.render(sc, seed=seed)
        S.write_capture(folder, stack, truth)
        print(f"rendered {folder} in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)


#: the decode captures: name -> (folder under --data, pattern_set keywords for a 1920x1080 projector, the camera's
#: size (None: the ``paper`` rig's 1280x800)).  The first two are the same camera's; the last two have the shapes of
#: the real pair issue 35 measured (a 12-frame 3-step capture of 1688x1352 against a Gray capture of 1280x1024),
#: compared per megapixel
PHASE = dict(family="phase", steps=3, period=64, white_black=False)
DECODE_PAIR = {"gray": ("decode-gray", {}, None), "phase": ("decode-phase", PHASE, None),
               "gray-1280x1024": ("decode-gray-1280x1024", {}, (1280, 1024)),
               "phase-1688x1352": ("decode-phase-1688x1352", PHASE, (1688, 1352))}


def ensure_decode_pair(data: Path) -> dict:
    """Render (unless there) the ``paper`` rig's board at the recommended pose as 46-frame Gray captures and as
    12-frame 3-step phase captures (:data:`DECODE_PAIR`); name -> (folder, frame count, megapixels)."""
    from procam import patterns

    out = {}
    for name, (sub, kw, size) in DECODE_PAIR.items():
        folder, ps = data / sub, patterns.pattern_set(1920, 1080, **kw)
        if not ((folder / "patterns.json").is_file() and len(list(folder.glob("[0-9][0-9].png"))) == ps.count):
            import dataclasses

            import numpy as np

            from procam import simulate as S

            t0 = time.perf_counter()
            scene = S.with_board_pose(S.preset("paper"), S.RECOMMENDED_POSE)
            if size is not None:  # another camera: the same field of view, its principal point scaled
                (w0, h0), K = scene.cam_size, np.array(scene.K_cam, float)
                K[[0, 1, 0], [0, 1, 2]] *= size[0] / w0
                K[1, 2] *= size[1] / h0
                scene = dataclasses.replace(scene, cam_size=tuple(size), K_cam=K)
            stack, truth = S.render(scene, order=ps, seed=7)
            S.write_capture(folder, stack, truth, order=ps)
            print(f"rendered {folder} in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
        w, h = size or (1280, 800)
        out[name] = (folder, ps.count, w * h / 1e6)
    return out


def png_files(data: Path) -> list[Path]:
    return [f for p in pose_dirs(data) for f in sorted(p.glob("[0-9][0-9].png"))]


def kamino_layout(data: Path) -> Path:
    """``data/kamino410/capture_N/graycode_MM.png`` links to the poses' PNGs (the script's layout)."""
    root = data / "kamino410"
    for n, folder in enumerate(pose_dirs(data), start=1):
        d = root / f"capture_{n}"
        d.mkdir(parents=True, exist_ok=True)
        for f in sorted(folder.glob("[0-9][0-9].png")):
            link = d / f"graycode_{f.stem}.png"
            if not link.exists():
                link.symlink_to(f.resolve())
    return root


# --------------------------------------------------------------------------------------------
# the reader (the floor) and the cold processes
# --------------------------------------------------------------------------------------------

def read_all(files, threads: int = 2, reader: str = "opencv"):
    """Read ``files`` as grey images with ``threads`` threads (``reader``: ``opencv``, cv2.imread; ``procam``,
    procam.io.images.read_image); returns the list of arrays."""
    from concurrent.futures import ThreadPoolExecutor

    if reader == "procam":
        from procam.io.images import read_image as read
    else:
        import cv2

        def read(f):
            return cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)

    with ThreadPoolExecutor(threads) as ex:
        return list(ex.map(read, files))


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(SRC)] + [p for p in [env.get("PYTHONPATH")] if p])
    return env


def calibrate_argv(data: Path, out: Path) -> list[str]:
    """``procam calibrate``'s arguments for the five poses in ``data``, writing ``out``."""
    return ["calibrate", *map(str, pose_dirs(data)), "--board", BOARD[0], "--square", BOARD[1], "-o", str(out)]


def commands(args, data: Path, out: Path) -> dict:
    """name -> (argv, cwd)."""
    procam = [sys.executable, "-c", "import sys; from procam.cli import main; sys.argv[0] = 'procam'; main()"]
    cmds = {
        "procam": ([*procam, *calibrate_argv(data, out)], None),
        "read": ([sys.executable, str(Path(__file__).resolve()), "--read-only", "opencv", "--data", str(data)], None),
        "read-procam": ([sys.executable, str(Path(__file__).resolve()), "--read-only", "procam", "--data", str(data)],
                        None),
        "version": ([*procam, "--version"], None),
        "calibrate-help": ([*procam, "calibrate", "--help"], None),
    }
    pair = ensure_decode_pair(data)
    for name, (folder, _, _) in pair.items():
        cmds[f"decode-{name}"] = ([*procam, "decode", str(folder), "-o", str(out.parent / f"{name}.npz")], None)
    # stand-ins for what the two unmet targets are up against (BOUNDS): not procam configurations
    cmds["imports"] = ([sys.executable, "-c", IMPORTS], None)
    cmds["decode-phase-own"] = ([sys.executable, "-c", WITHOUT_NEIGHBOURS, "decode", str(pair["phase"][0]), "-o",
                                 str(out.parent / "phase-own.npz")], None)
    cmds["corners-given"] = ([sys.executable, "-c", CORNERS_GIVEN, str(ensure_corners(data)),
                              *calibrate_argv(data, out.parent / "calib-corners-given.json")], None)
    if args.kamino410:
        root = kamino_layout(data)
        cmds["kamino410"] = ([args.kamino410_python, str(Path(args.kamino410).resolve()), "768", "1024",
                              BOARD[0].split("x")[0], BOARD[0].split("x")[1], BOARD[1], "1"], root)
    return cmds


#: a cold process that imports the third-party modules a ``procam calibrate`` imports (``python -X importtime``):
#: scipy.optimize (least_squares, with scipy.special's erf for the corners' model and scipy.linalg), OpenCV, numpy,
#: typer and rich; ISA-L where installed
IMPORTS = ("import numpy, cv2, typer, rich.console, rich.table, scipy.optimize\n"
           "try:\n    import isal.isal_zlib\nexcept ImportError:\n    pass")

def _patched(module: str, patch: str, head: str = "") -> str:
    """A ``python -c`` script running procam's command line with ``module`` patched as it loads (``patch``: lines
    run with the module as ``m`` after it is executed; ``head``: lines run first), so that nothing is imported ahead
    of the command line's fork of its reader."""
    body = "\n".join(" " * 12 + line for line in patch.strip().splitlines())
    return f"""import importlib.abc, importlib.util, sys
{head}
class Patch(importlib.abc.MetaPathFinder):
    def find_spec(self, name, where, target=None):
        if name != {module!r}:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        run = spec.loader.exec_module
        def exec_module(m):
            run(m)
{body}
        spec.loader.exec_module = exec_module
        return spec
sys.meta_path.insert(0, Patch())
from procam.cli import main
sys.argv[0] = "procam"
main()"""


#: ``procam decode`` with the phase decoder's neighbours' ordering pass skipped (``neighbour_orders`` replaced by a
#: function that orders nothing): each pixel from its own fringes only, the pixels ``PhaseOptions(neighbours=False)``
#: decodes (the pass's inputs still made)
WITHOUT_NEIGHBOURS = _patched("procam.decode.phase.unwrap", "m.neighbour_orders = lambda *a, **k: 0")

#: ``procam calibrate`` with the board's corners given: ``procam.pipeline.find_board`` replaced by a lookup of the
#: corners it found for the same white frame (:func:`ensure_corners`; the file is the first argument; a frame not
#: there fails the run).  The most moving the corner detection into the process that reads the poses could give
#: (there it would still take a core's time, and import scipy.special's erf again).  The calibration file is the
#: same byte for byte.
CORNERS_GIVEN = _patched("procam.pipeline", """
import hashlib
import numpy as np
given = dict(np.load(path))
def find_board(stack, ps, *a, **k):
    c = given.get(hashlib.sha1(stack[ps.white].tobytes()).hexdigest())
    if c is None:
        raise SystemExit(f"{path} has no corners of this pose's white frame: delete it (remade)")
    return c.copy()
m.find_board = find_board""", head="path = sys.argv.pop(1)")


def ensure_corners(data: Path) -> Path:
    """The board's corners procam's ``calibrate`` finds in each pose, keyed by the SHA-1 of the pose's white frame
    (``corners.npz`` in ``data``, made unless there, by the calibrate itself with ``find_board`` recording)."""
    path = data / "corners.npz"
    if not path.is_file():
        import subprocess

        subprocess.run([sys.executable, str(Path(__file__).resolve()), "--record-corners", "--data", str(data)],
                       env=_env(), check=True, stdout=subprocess.DEVNULL)
    return path


def record_corners(data: Path) -> None:
    """Run ``procam calibrate`` on the poses in this process, ``find_board`` recording what it returns."""
    import hashlib
    import tempfile

    import numpy as np

    from procam import pipeline
    from procam.cli import main as cli

    found, find = {}, pipeline.find_board

    def recording(stack, ps, *a, **k):
        c = find(stack, ps, *a, **k)
        found[hashlib.sha1(stack[ps.white].tobytes()).hexdigest()] = np.array(c)
        return c

    pipeline.find_board = recording
    with tempfile.TemporaryDirectory() as tmp:
        try:
            cli(calibrate_argv(data, Path(tmp) / "calib.json"))
        except SystemExit as e:
            if e.code not in (0, None):
                raise
    if len(found) != N_POSES:
        raise SystemExit(f"recorded the corners of {len(found)} poses, not {N_POSES}")
    part = data / "corners.part.npz"
    np.savez(part, **found)
    part.replace(data / "corners.npz")


def run_cold(argv, cwd=None) -> dict:
    """Run ``argv``; wall s, CPU s (user + sys of the process and its children) and max RSS (MB)."""
    import subprocess

    t0 = time.perf_counter()
    p = subprocess.Popen(argv, cwd=cwd, env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    err = p.stderr.read().decode(errors="replace")
    p.stderr.close()
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(argv[:4])} ... failed ({p.returncode}):\n{err[-2000:]}")
    return {"wall": wall, "cpu": ru.ru_utime + ru.ru_stime, "rss": ru.ru_maxrss / 1024}


# --------------------------------------------------------------------------------------------
# per-stage profile (run in a fresh process: --profile)
# --------------------------------------------------------------------------------------------

#: (stage, module, function) -- functions that do not exist in the profiled version are skipped
STAGES = [
    ("read PNGs (all reader threads)", "procam.io.images", "read_image"),
    ("waiting for the images", "procam.io.images", "read_images"),
    ("waiting for the images", "procam.stream", "Prefetcher.read"),
    ("capture checks", "procam.capture.read", "_sample"),
    ("capture checks", "procam.capture.read", "check_light"),
    ("capture checks", "procam.capture.read", "check_white_black"),
    ("capture checks", "procam.capture.read", "check_pairs"),
    ("capture checks", "procam.capture.read", "exposure_warnings"),
    ("capture checks", "procam.capture.read", "check_bit_order"),
    ("decode", "procam.decode", "decode"),
    ("board corners", "procam.pipeline", "find_board"),
    ("local homographies", "procam.correspond", "projector_corners"),
    ("plausibility checks", "procam.decode.plausibility", "check_projector_size"),
    ("plausibility checks", "procam.decode.plausibility", "check_swapped_bits"),
    ("plausibility checks", "procam.decode.plausibility", "check_orientation"),
    ("calibration (multi_pose)", "procam.multi_pose", "calibrate"),
    ("verification (leave-one-out)", "procam.verify", "verify_calibration"),
    ("summary + JSON", "procam.cli._show", "print_calibration"),
    ("summary + JSON", "procam.io", "save_calibration"),
    ("summary + JSON", "procam.cli._show", "print_verification"),
    ("summary + JSON", "procam.cli._show", "print_spread"),
    ("imports during the run (solvers)", "procam.cli.calibrate", "_import_solvers"),
]


def _thread_group(t=None) -> str:
    """``main``, or a thread's name without its number (``procam-read``, ``ThreadPoolExecutor``)."""
    import re
    import threading

    t = t or threading.current_thread()
    return "main" if t is threading.main_thread() else re.sub(r"[-_]?\d+(_\d+)?$", "", t.name)


#: what each thread group does in a calibrate, for the rows of the CPU not inside a stage
GROUPS = {"main": "main thread", "procam-read": "reader threads",
          "ThreadPoolExecutor": "worker threads (board corners, leave-one-out refits)"}


def profile_once(data: Path, out: Path) -> dict:
    """Import procam's CLI, wrap the stage functions with timers, run ``calibrate``; stage -> (wall s, CPU s).

    The CPU outside the stages is given per thread group (every thread's CPU is counted when it ends): the main
    thread's, the reader threads' beyond decoding the PNGs, the worker threads'."""
    import importlib
    import io as _io
    import threading
    from contextlib import redirect_stdout

    t0, c0 = time.perf_counter(), time.thread_time()
    from procam.cli import main
    lock = threading.Lock()
    timers: dict = {}
    inside: dict = {}  # thread group -> CPU inside stages
    threads: dict = {}  # thread group -> CPU of its threads
    run = threading.Thread.run

    def counted_run(self):
        c = time.thread_time()
        try:
            run(self)
        finally:
            with lock:
                g = _thread_group(self)
                threads[g] = threads.get(g, 0.0) + time.thread_time() - c

    threading.Thread.run = counted_run

    def wrap(stage, f):
        def timed(*a, **k):
            t, c = time.perf_counter(), time.thread_time()
            try:
                return f(*a, **k)
            finally:
                with lock:
                    w0, c0 = timers.get(stage, (0.0, 0.0))
                    dc = time.thread_time() - c
                    timers[stage] = (w0 + time.perf_counter() - t, c0 + dc)
                    g = _thread_group()
                    inside[g] = inside.get(g, 0.0) + dc
        return timed

    for stage, mod, attr in STAGES:
        try:
            owner = importlib.import_module(mod)
            *path, name = attr.split(".")
            for part in path:
                owner = getattr(owner, part)
            f = getattr(owner, name)
        except (ImportError, AttributeError):
            continue
        setattr(owner, name, wrap(stage, f))
    # the modules calibrate imports lazily are imported here, to wrap them
    t_import = (time.perf_counter() - t0, time.thread_time() - c0)
    argv = calibrate_argv(data, out)
    t2, c2, m2 = time.perf_counter(), time.process_time(), time.thread_time()
    with redirect_stdout(_io.StringIO()):
        try:
            main(argv)
        except SystemExit as e:
            if e.code not in (0, None):
                raise
    threads["main"] = time.thread_time() - m2
    t_run = (time.perf_counter() - t2, time.process_time() - c2)
    threading.Thread.run = run
    out = {"imports": t_import, **timers}
    for g, cpu in threads.items():  # stages nested in one another are counted twice: none of STAGES are
        out[f"other: {GROUPS.get(g, g)}, outside the stages"] = (float("nan"), cpu - inside.get(g, 0.0))
    out["run after imports (wall; CPU of all threads)"] = t_run
    return out


# --------------------------------------------------------------------------------------------
# accuracy
# --------------------------------------------------------------------------------------------

def accuracy(data: Path, calib_json: Path, kamino_xml: Path | None) -> str:
    import numpy as np
    from scipy.spatial.transform import Rotation

    truth = json.loads((pose_dirs(data)[0] / "truth.json").read_text())
    t = {"Kc": np.array(truth["camera"]["K"]), "Kp": np.array(truth["projector"]["K"]),
         "R": np.array(truth["extrinsics"]["R"]), "T": np.array(truth["extrinsics"]["T"])}
    res = {}
    p = json.loads(calib_json.read_text())
    res["procam"] = {"Kc": np.array(p["camera"]["K"]), "Kp": np.array(p["projector"]["K"]), "R": np.array(p["R"]),
                     "T": np.array(p["T"]), "rms": p.get("stereo_rms_px")}
    if kamino_xml is not None and kamino_xml.is_file():
        import cv2

        fs = cv2.FileStorage(str(kamino_xml), cv2.FILE_STORAGE_READ)
        rot = fs.getNode("rotation").mat()
        if rot is None:
            rot = fs.getNode("roration").mat()  # some versions of the script spell it so
        res["kamino410"] = {"Kc": fs.getNode("cam_int").mat(), "Kp": fs.getNode("proj_int").mat(), "R": rot,
                            "T": fs.getNode("translation").mat().ravel(), "rms": fs.getNode("rms").real()}
        fs.release()

    def params(d):
        Kc, Kp = d["Kc"], d["Kp"]
        return {"f_c": Kc[0, 0], "fy_c": Kc[1, 1], "u0_c": Kc[0, 2], "v0_c": Kc[1, 2], "f_p": Kp[0, 0],
                "fy_p": Kp[1, 1], "u0_p": Kp[0, 2], "v0_p": Kp[1, 2]}

    names = list(res)
    lines = ["| parameter | truth | " + " | ".join(f"{n} | error" for n in names) + " |",
             "| --- | --- | " + " | ".join("--- | ---" for _ in names) + " |"]
    P0 = params(t)
    for k, v0 in P0.items():
        cells = [f"{params(res[n])[k]:.3f} | {params(res[n])[k] - v0:+.3f}" for n in names]
        lines.append(f"| {k} | {v0:.3f} | " + " | ".join(cells) + " |")
    for n in names:
        dT = np.linalg.norm(res[n]["T"] - t["T"])
        dR = np.degrees(Rotation.from_matrix(res[n]["R"] @ t["R"].T).magnitude())
        lines.append(f"\n{n}: |T - T_true| {dT:.3f} mm, rotation error {dR:.4f} deg, stereo RMS {res[n]['rms']:.3f} px")
    # corners of the procam result against the exact ones
    ec, ep = [], []
    for v in p.get("views", []):
        tr = json.loads((Path(v["pose"]) / "truth.json").read_text()) if Path(v["pose"]).is_dir() else None
        if tr is None:
            continue
        cam, proj = np.array(v["camera_points"], float), np.array(v["projector_points"], float)
        ec.append(np.linalg.norm(cam - np.array(tr["corners"]["camera_distorted"]), axis=1))
        ep.append(np.linalg.norm(proj - np.array(tr["corners"]["projector"]), axis=1))
    if ec:
        ec, ep = np.concatenate(ec), np.concatenate(ep)
        ep = ep[np.isfinite(ep)]
        lines.append(f"\nprocam corners against the truth ({ec.size} camera, {ep.size} projector): camera median "
                     f"{np.median(ec):.4f} px, RMS {np.sqrt(np.mean(ec ** 2)):.4f}, max {ec.max():.4f}; projector "
                     f"median {np.median(ep):.4f} px, RMS {np.sqrt(np.mean(ep ** 2)):.4f}, max {ep.max():.4f}")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------------------------

def _med(xs):
    return statistics.median(xs) if xs else float("nan")


#: (what, command, baseline command or a time in seconds, the target ratio) of the summary (issue 35)
TARGETS = [("5-pose Gray calibrate vs reading its PNGs (the floor)", "procam", "read", 1.5),
           ("5-pose Gray calibrate vs kamino410's calibrate.py", "procam", "kamino410", 0.8),
           ("phase capture (12 frames) vs Gray capture (46 frames) of one camera, procam decode", "decode-phase",
            "decode-gray", 1.0),
           ("per megapixel: phase capture of 1688x1352 (12 frames) vs Gray of 1280x1024 (46), procam decode",
            "decode-phase-1688x1352", "decode-gray-1280x1024", 1.0, (1688 * 1352) / (1280 * 1024)),
           ("cold start: procam --version vs 0.2 s", "version", 0.2, 1.0),
           ("cold start: procam calibrate --help vs 0.3 s", "calibrate-help", 0.3, 1.0)]


#: (what, stand-in command, baseline command) of the second table: what the two targets not met are up against
BOUNDS = [("the third-party imports of a calibrate, alone (IMPORTS) vs reading its PNGs (the floor)", "imports",
           "read"),
          ("5-pose Gray calibrate with the board's corners given (CORNERS_GIVEN) vs reading its PNGs (the floor)",
           "corners-given", "read"),
          ("phase capture without the neighbours' ordering pass (WITHOUT_NEIGHBOURS) vs Gray capture, procam decode",
           "decode-phase-own", "decode-gray")]


def summary(runs: dict, rows=None) -> str:
    """The summary table: each command against its baseline, ratios of the medians of this run's rounds (wall and
    CPU) and the median of the per-round wall ratios (each round's commands ran back to back, under one load).
    ``rows``: (what, command, baseline) without a target (:data:`BOUNDS`) instead of :data:`TARGETS`."""
    lines = ["| what | seconds (median wall) | baseline | wall ratio | per-round wall ratio | CPU ratio | target |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for what, a, b, target, *per in TARGETS if rows is None else [(*r, None) for r in rows]:
        scale = per[0] if per else 1.0  # a per-megapixel comparison: a's camera has this many times b's pixels
        goal = "" if target is None else f"<= {target:g}"
        if a not in runs or (isinstance(b, str) and b not in runs):
            lines.append(f"| {what} | - | not run | | | | {goal} |")
            continue
        wa, ca = [x["wall"] for x in runs[a]], [x["cpu"] for x in runs[a]]
        if isinstance(b, str):
            wb, cb = [x["wall"] * scale for x in runs[b]], [x["cpu"] * scale for x in runs[b]]
            base, per_round = f"{_med(wb):.2f} s", _med([x / y for x, y in zip(wa, wb)])
            if scale != 1.0:
                base = f"{_med(wb) / scale:.2f} s x {scale:.2f} (pixels)"
            cpu = f"{_med(ca) / _med(cb):.2f}"
        else:
            wb, base, per_round, cpu = [b], f"{b:g} s (target)", _med([x / b for x in wa]), ""
        ratio = _med(wa) / _med(wb)
        if target is not None:
            goal += " (met)" if ratio <= target else " (NOT met)"
        lines.append(f"| {what} | {_med(wa):.3f} | {base} | {ratio:.2f} | {per_round:.2f} | {cpu} | {goal} |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=HERE / ".cache" / "pipeline",
                    help="folder of the rendered poses (rendered there when missing, reused otherwise)")
    ap.add_argument("--repeat", type=int, default=7, help="rounds of the cold-process comparison")
    ap.add_argument("--stages", type=int, default=3, help="runs of the in-process per-stage profile (0: none)")
    ap.add_argument("--kamino410", help="path of kamino410's calibrate.py (procam-calibration), to run it too")
    ap.add_argument("--kamino410-python", default=None, help="the Python that runs it (with opencv-contrib)")
    ap.add_argument("--read-only", choices=("opencv", "procam"), default=None, help=argparse.SUPPRESS)
    ap.add_argument("--profile", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--render-only", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--record-corners", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    data = args.data.resolve()
    sys.path.insert(0, str(SRC))  # this checkout's procam, as in the cold processes

    if args.read_only:  # the cold reader process
        t0 = time.perf_counter()
        imgs = read_all(png_files(data), reader=args.read_only)
        assert len(imgs) == 42 * N_POSES and all(i is not None for i in imgs)
        print(json.dumps({"read": time.perf_counter() - t0}))
        return
    if args.profile:  # one in-process per-stage run
        print(json.dumps(profile_once(data, args.out)))
        return
    if args.record_corners:  # the corners CORNERS_GIVEN looks up
        record_corners(data)
        return
    if args.render_only:  # the captures, rendered in a process of their own (below)
        ensure_data(data)
        ensure_decode_pair(data)
        return
    if args.kamino410 and not args.kamino410_python:
        ap.error("--kamino410 needs --kamino410-python (a Python with opencv-contrib)")

    sys.path.insert(0, str(HERE))
    from _common import header

    # rendered in a child process: on Linux a child's peak memory (ru_maxrss) starts from its parent's at the fork,
    # and rendering here would make every command's peak the renderer's
    import subprocess

    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--render-only", "--data", str(data)], env=_env(),
                   check=True)
    import compileall
    import tempfile

    # an installed procam has its bytecode; a checkout run with PYTHONDONTWRITEBYTECODE=1 would compile every module
    # in every cold process (0.07 s of procam --help)
    compileall.compile_dir(str(SRC), quiet=1)

    tmp = Path(tempfile.mkdtemp(prefix="procam-bench-"))
    out = tmp / "calib.json"
    cmds = commands(args, data, out)
    names = list(cmds)
    runs = {n: [] for n in names}
    loads = []
    for r in range(args.repeat):
        order = names[r % len(names):] + names[:r % len(names)]  # rotate who goes first
        for n in order:
            argv, cwd = cmds[n]
            runs[n].append(run_cold(argv, cwd))
        loads.append(os.getloadavg()[0])

    stage_runs = []
    for _ in range(args.stages):
        import subprocess

        res = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--profile", "--data", str(data),
                              "--out", str(tmp / "calib_profile.json")], env=_env(), capture_output=True,
                             text=True, check=True)
        stage_runs.append(json.loads(res.stdout.strip().splitlines()[-1]))

    import procam

    print(header(f"pipeline: procam calibrate of {N_POSES} poses (42 PNGs of 1280x1024 each, projector 1024x768)"))
    print(f"procam from {Path(procam.__file__).parent}; data {data} "
          f"({sum(f.stat().st_size for f in png_files(data)) / 1e6:.0f} MB of PNG); {args.repeat} rounds, "
          f"commands alternating; 1-min load average during the rounds: median {_med(loads):.1f} "
          f"(min {min(loads):.1f}, max {max(loads):.1f}); OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS', '-')}\n")
    print(summary(runs))
    print("What the two targets not met are up against (stand-ins, not procam configurations):\n")
    print(summary(runs, BOUNDS))
    print("| command | wall median (s) | wall min | CPU median (s) | peak memory (MB) |")
    print("| --- | --- | --- | --- | --- |")
    pair = ensure_decode_pair(data)
    label = {"procam": "procam calibrate, 5 poses (cold process)",
             "read": "read the 210 PNGs, 2 threads, cv2.imread (cold process)",
             "read-procam": "read the 210 PNGs, 2 threads, procam's reader (cold process)",
             "kamino410": "kamino410 calibrate.py, 5 poses (cold process)", "version": "procam --version",
             "calibrate-help": "procam calibrate --help",
             "imports": "import the third-party modules of a calibrate (cold process)",
             "decode-phase-own": "procam decode, phase capture, without the neighbours' ordering pass",
             "corners-given": "procam calibrate, 5 poses, the board's corners given (cold process)",
             **{f"decode-{n}": f"procam decode, {n} capture ({k} frames, {mp:.2f} MP)"
                for n, (_, k, mp) in pair.items()}}
    for n in names:
        w = [x["wall"] for x in runs[n]]
        print(f"| {label[n]} | {_med(w):.2f} | {min(w):.2f} | {_med([x['cpu'] for x in runs[n]]):.2f} | "
              f"{max(x['rss'] for x in runs[n]):.0f} |")
    print("\n| ratio | median of the per-round ratios | ratio of the medians | ratio of the minima |")
    print("| --- | --- | --- | --- |")
    pairs = [("procam", "read"), ("procam", "read-procam"), ("read-procam", "read")] + \
        ([("procam", "kamino410")] if "kamino410" in runs else []) + [("decode-phase", "decode-gray")]
    for a, b in pairs:
        wa, wb = [x["wall"] for x in runs[a]], [x["wall"] for x in runs[b]]
        per_round = [x / y for x, y in zip(wa, wb)]
        print(f"| {a} / {b}, wall | {_med(per_round):.2f} | {_med(wa) / _med(wb):.2f} | {min(wa) / min(wb):.2f} |")
        ca, cb = [x["cpu"] for x in runs[a]], [x["cpu"] for x in runs[b]]
        print(f"| {a} / {b}, CPU | {_med([x / y for x, y in zip(ca, cb)]):.2f} | {_med(ca) / _med(cb):.2f} | "
              f"{min(ca) / min(cb):.2f} |")

    if stage_runs:
        keys = list(dict.fromkeys(k for s in stage_runs for k in s))
        print(f"\nper stage (in-process, fresh interpreter per run; median of {len(stage_runs)} runs; seconds summed "
              "over calls; CPU = the CPU time of the thread(s) running the stage; the images are read in reader "
              "threads, and 'waiting for the images' is the main thread's wait for them):\n")
        print("| stage | wall median | wall min | CPU median | CPU min |")
        print("| --- | --- | --- | --- | --- |")
        for k in keys:
            w = [s.get(k, (0.0, 0.0))[0] for s in stage_runs]
            c = [s.get(k, (0.0, 0.0))[1] for s in stage_runs]
            print(f"| {k} | {_med(w):.3f} | {min(w):.3f} | {_med(c):.3f} | {min(c):.3f} |")

    print("\naccuracy against the simulator's truth:\n")
    print(accuracy(data, out, (cmds["kamino410"][1] / "calibration_result.xml") if "kamino410" in cmds else None))


if __name__ == "__main__":
    main()
