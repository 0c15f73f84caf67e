"""Benchmark: the capture loop's own cost per frame, and the projector window's show() time.

1. ``capture_pose`` on the virtual procam (the ``paper`` rig: 1280x800 camera, 1920x1080 projector,
   46 patterns) with no settle time and a pre-rendered stack: what remains is procam's work per
   frame (pattern generation, showing, the checks, the PNG write) plus the pre-flight and the
   post-flight frames.  A real capture adds the settle time and the camera's frame period per grab.
2. ``ProjectorWindow.show`` of 1920x1080 patterns on a virtual X server (Xvfb), when Xvfb and
   pygame-ce are installed: the time from the call to the return after the flip (software
   rendering into Xvfb; a GPU desktop differs).
3. ``procam check`` of a written pose folder (46 PNGs of 1280x800, the board found and judged), run
   as a cold process, next to the time to read those PNGs with two threads in the same process.

    python benchmarks/capture.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import patterns, simulate  # noqa: E402
from procam.acquire import CaptureOptions, VirtualCamera, VirtualProjector, capture_pose  # noqa: E402


def _loop(repeat: int) -> list[str]:
    scene = simulate.preset("paper")
    stack, _ = simulate.render(scene, seed=0)
    rows = []
    for r in range(repeat):
        with tempfile.TemporaryDirectory() as tmp, VirtualProjector(scene.proj_size) as proj, \
                VirtualCamera(proj, scene, stack=stack) as cam:
            w, c = time.perf_counter(), time.process_time()
            res = capture_pose(Path(tmp) / "pose", proj, cam, CaptureOptions(settle_s=0.0, board=(10, 6)))
            w, c = time.perf_counter() - w, time.process_time() - c
        n = len(res.files)
        grabs = cam.grabs
        rows.append(f"| {r + 1} | {n} | {grabs} | {w:.2f} | {c:.2f} | {1000 * w / grabs:.1f} |")
    return rows


def _xvfb_show(repeat: int, size=(1920, 1080)) -> list[str]:
    import importlib.util

    if importlib.util.find_spec("pygame") is None or importlib.util.find_spec("screeninfo") is None:
        return ["(skipped: pygame-ce / screeninfo not installed)"]
    if shutil.which("Xvfb") is None:
        return ["(skipped: Xvfb not installed)"]
    from procam.acquire import ProjectorWindow

    r, wfd = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(wfd), "-screen", "0", f"{size[0]}x{size[1]}x24", "-nolisten",
                             "tcp"], pass_fds=(wfd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(wfd)
    text = b""
    while not text.endswith(b"\n"):
        ready, _, _ = select.select([r], [], [], 20)
        chunk = os.read(r, 64) if ready else b""
        if not chunk:
            break
        text += chunk
    os.close(r)
    rows = []
    try:
        os.environ["DISPLAY"] = ":" + text.decode().strip()
        seq = patterns.generate(*size)
        with ProjectorWindow(size, display=0) as win:
            for rep in range(repeat):
                times = []
                for img in seq:
                    t = time.perf_counter()
                    win.show(img)
                    times.append(time.perf_counter() - t)
                t = np.array(times) * 1000
                rows.append(f"| {rep + 1} | {len(t)} | {np.median(t):.1f} | {t.max():.1f} |")
    finally:
        proc.terminate()
        proc.wait(10)
    return rows


def _check_cli(repeat: int) -> list[str]:
    from concurrent.futures import ThreadPoolExecutor

    import cv2

    scene = simulate.with_board_pose(simulate.preset("paper"), simulate.RECOMMENDED_POSE)
    stack, truth = simulate.render(scene, seed=0)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "pose"
        simulate.write_capture(folder, stack, truth)
        files = sorted(folder.glob("*.png"))
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
        exe = Path(sys.executable).with_name("procam")
        argv = [str(exe) if exe.exists() else "procam", "check", str(folder), "--board", "10x6", "--square", "24"]
        for r in range(repeat):
            t = time.perf_counter()
            with ThreadPoolExecutor(2) as ex:
                list(ex.map(lambda f: cv2.imread(str(f), cv2.IMREAD_UNCHANGED), files))
            t_read = time.perf_counter() - t
            t = time.perf_counter()
            done = subprocess.run(argv, env=env, capture_output=True, text=True)
            t_check = time.perf_counter() - t
            lines = done.stdout.strip().splitlines()
            verdict = next((ln for ln in lines if ln.startswith("verdict")), (lines or ["?"])[-1])[:60]
            rows.append(f"| {r + 1} | {len(files)} | {t_read:.2f} | {t_check:.2f} | {done.returncode} | {verdict} |")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(header("procam capture: loop overhead (virtual procam, paper rig) and projector window show()"))
    print(f"load average: {os.getloadavg()[0]:.2f}\n")
    print("capture_pose, settle 0, pre-rendered 1280x800 stack, 46 patterns + pre/post-flight")
    print("| run | frames | grabs | wall s | CPU s | wall ms / grab |\n|---|---|---|---|---|---|")
    print("\n".join(_loop(args.repeat)))
    print("\nProjectorWindow.show, 1920x1080 patterns, Xvfb (software)")
    print("| run | shows | median ms | max ms |\n|---|---|---|---|")
    print("\n".join(_xvfb_show(args.repeat)))
    print("\nprocam check, cold process, paper rig at the recommended pose (46 PNGs of 1280x800)")
    print("| run | images | read (2 threads) s | procam check s | exit | verdict |\n|---|---|---|---|---|---|")
    print("\n".join(_check_cli(args.repeat)))


if __name__ == "__main__":
    main()
