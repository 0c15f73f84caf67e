"""Benchmark: read a 46-image 1280x800 PNG capture and decode it (goal: decode <= 25 % of read time).

Renders a realistic capture once (a 1920x1080 projector's sequence seen through a perspective warp,
with defocus, vignetting, ambient light and camera noise), writes it as PNGs to a temporary folder,
then times, in one run: reading the stack (procam.io.images.read_images, the same path the CLI uses) and
decoding it with both classifiers.  Peak memory is the process's maximum resident set size.

    python benchmarks/decode.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import header  # noqa: E402

from procam import decode, patterns  # noqa: E402
from procam.io import images as _images  # noqa: E402


def render(cam=(1280, 800), proj=(1920, 1080), seed=0):
    rng = np.random.default_rng(seed)
    ps = patterns.pattern_set(*proj)
    pats = patterns.generate(*proj).astype(np.float32) / 255.0
    # camera pixel -> projector pixel homography (a tilted view of the projected image)
    src = np.float32([[100, 60], [1180, 120], [1150, 760], [130, 700]])
    dst = np.float32([[0, 0], [1919, 0], [1919, 1079], [0, 1079]])
    Hm = cv2.getPerspectiveTransform(src, dst)
    yy, xx = np.mgrid[:cam[1], :cam[0]].astype(np.float32)
    vign = 1.0 - 0.3 * (((xx - 640) / 640) ** 2 + ((yy - 400) / 400) ** 2)
    out = np.empty((ps.count, cam[1], cam[0]), np.uint8)
    for k, p in enumerate(pats):
        p = cv2.GaussianBlur(p, (0, 0), 0.8)
        img = cv2.warpPerspective(p, Hm, cam, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderValue=0)
        img = (0.03 + 0.97 * img) * 180 * vign + 15
        img = img + rng.normal(0, 2.0, img.shape)
        out[k] = np.clip(np.round(img), 0, 255).astype(np.uint8)
    return out, ps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    stack, ps = render()
    with tempfile.TemporaryDirectory() as tmp:
        files = []
        for i, img in enumerate(stack):
            f = Path(tmp) / f"{i:02d}.png"
            cv2.imwrite(str(f), img)
            files.append(f)
        size_mb = sum(f.stat().st_size for f in files) / 1e6
        t_read, t_read1, t_simple, t_robust = [], [], [], []
        for _ in range(args.repeat):
            t = time.perf_counter()
            st = _images.read_images(files)
            t_read.append(time.perf_counter() - t)
            t = time.perf_counter()
            _images.read_images(files, threads=1)
            t_read1.append(time.perf_counter() - t)
            t = time.perf_counter()
            decode.decode(st, ps, "simple")
            t_simple.append(time.perf_counter() - t)
            t = time.perf_counter()
            res = decode.decode(st, ps, "robust")
            t_robust.append(time.perf_counter() - t)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    r, r1 = np.median(t_read), np.median(t_read1)
    print(header("decode: 46 x 1280x800 PNG capture of a 1920x1080 projector"))
    print(f"PNG stack: {len(files)} files, {size_mb:.1f} MB; valid pixels {res.valid.mean() * 100:.1f} %; "
          f"median of {args.repeat} runs\n")
    print("| step | seconds | % of read (threaded) | % of read (1 thread) |")
    print("| --- | --- | --- | --- |")
    print(f"| read 46 PNGs (_images.read_images, threads) | {r:.3f} | 100 | {100 * r / r1:.0f} |")
    print(f"| read 46 PNGs (1 thread) | {r1:.3f} | {100 * r1 / r:.0f} | 100 |")
    for name, t in (("decode simple", t_simple), ("decode robust", t_robust)):
        m = np.median(t)
        print(f"| {name} | {m:.3f} | {100 * m / r:.0f} | {100 * m / r1:.0f} |")
    print(f"\npeak memory (max RSS): {peak:.0f} MB")


if __name__ == "__main__":
    main()
