"""Benchmark: cold start of the command line, this checkout against another commit, in one run.

Each figure is the median wall time of ``--repeat`` fresh processes, the two checkouts alternating (this
machine's load moves both alike):

1. ``procam --version``, ``procam --help`` and ``procam calibrate --help``;
2. ``procam decode`` of the first of them, and ``procam calibrate`` of five rendered poses of the ``paper`` rig
   (multi-pose), and the time its imports take: the sum of the top-level cumulative times of ``python -X importtime`` (imports done in a thread
   while the captures are decoded count there too, though they cost no wall time).

Both sides' source is byte-compiled first (as an installed package is). The other commit is checked out into a
temporary git worktree and run with the same interpreter
(``PYTHONPATH`` pointing at its ``src``), so only procam's code differs; or, with ``--base-python``, by another
interpreter (another environment: e.g. ``--base HEAD --base-python /tmp/v/bin/python`` times the same code with
that environment's dependencies, such as another typer).

    python benchmarks/cold_start.py [--base REF] [--base-python PY] [--repeat 7] [--cache DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
POSES = ["15,12,0", "-10,20,5", "20,-15,-5", "5,25,10", "-20,-10,0"]
PROCAM = [sys.executable, "-c", "import sys; from procam.cli import main; sys.argv[0] = 'procam'; main()"]


def _run(src: Path, args, cwd, importtime: bool = False, python: str = sys.executable):
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [python, *PROCAM[1:]]
    if importtime:
        cmd.insert(1, "-X")
        cmd.insert(2, "importtime")
    t = time.perf_counter()
    res = subprocess.run(cmd + list(args), cwd=cwd, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t
    if res.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, args))} failed in {src}: {res.stderr.strip()[-500:]}")
    return dt, res.stderr


def _import_seconds(stderr: str) -> float:
    """Sum of the top-level cumulative times (s) of a ``-X importtime`` log."""
    total = 0
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, cum, name = line[len("import time:"):].split("|")
        if name.startswith(" ") and not name.startswith("  "):
            total += int(cum)
    return total / 1e6


def _poses(cache: Path) -> list[Path]:
    out = []
    for i, pose in enumerate(POSES, 1):
        d = cache / f"pose{i}"
        if not d.is_dir():
            subprocess.run([*PROCAM, "simulate", str(d), f"--pose={pose}", "--seed", str(i)], check=True,
                           capture_output=True, env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
        out.append(d)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", default="HEAD~1", help="the commit to compare with (default HEAD~1)")
    ap.add_argument("--base-python", default=sys.executable,
                    help="the interpreter (environment) that runs the base (default: this one)")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--cache", type=Path, default=ROOT / "benchmarks" / ".cache" / "cold_start")
    a = ap.parse_args()
    other = "" if a.base_python == sys.executable else f" run by {a.base_python}"
    print(header(f"cold start: this checkout against {a.base}{other}"))
    a.cache.mkdir(parents=True, exist_ok=True)
    poses = _poses(a.cache)
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "base"
        subprocess.run(["git", "worktree", "add", "--detach", str(base), a.base], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            sides = {"base": base / "src", "this": ROOT / "src"}
            import compileall

            # both sides byte-compiled, as an installed package is: run with PYTHONDONTWRITEBYTECODE=1, a fresh
            # worktree would otherwise compile every module of procam in every run (0.01-0.3 s of each command),
            # and the side that happens to have its bytecode would look that much faster
            for src in sides.values():
                compileall.compile_dir(str(src), quiet=1)
            python = {"base": a.base_python, "this": sys.executable}
            work = Path(tmp) / "out"
            work.mkdir()
            cases = {"procam --version": ["--version"], "procam --help": ["--help"],
                     "procam calibrate --help": ["calibrate", "--help"],
                     "decode, 1 pose": ["decode", str(poses[0]), "-o", str(work / "d.npz")],
                     "calibrate, 5 poses": ["calibrate", *map(str, poses), "--board", "10x6", "--square", "24",
                                            "-o", str(work / "c.json")]}
            times = {(c, s): [] for c in cases for s in sides}
            for _ in range(a.repeat):
                for case, args in cases.items():
                    for side, src in sides.items():
                        times[(case, side)].append(_run(src, args, work, python=python[side])[0])
            imports = {s: _import_seconds(_run(src, cases["calibrate, 5 poses"], work, importtime=True,
                                               python=python[s])[1])
                       for s, src in sides.items()}
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(base)], cwd=ROOT, capture_output=True)
    print(f"median of {a.repeat} fresh processes each, alternating; seconds\n")
    print(f"| command | {a.base}{other} | this checkout | ratio |")
    print("| --- | --- | --- | --- |")
    for case in cases:
        b, t = statistics.median(times[(case, "base")]), statistics.median(times[(case, "this")])
        print(f"| {case} | {b:.3f} | {t:.3f} | {t / b:.2f} |")
    b, t = imports["base"], imports["this"]
    print(f"| imports during the 5-pose calibrate (-X importtime) | {b:.3f} | {t:.3f} | {t / b:.2f} |")


if __name__ == "__main__":
    main()
