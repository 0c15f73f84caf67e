"""Regenerate tests/data/opencv_graycode_golden.json from OpenCV's own GrayCodePattern.

Needs opencv-contrib-python-headless (NOT a procam dependency); run it in a throwaway venv:

    python -m venv /tmp/cvc && /tmp/cvc/bin/pip install numpy opencv-contrib-python-headless
    /tmp/cvc/bin/python tools/make_opencv_graycode_golden.py

For every size it records OpenCV's pattern count, the sha256 of the whole (count, H, W)
uint8 stack, its pixel values, and row 0 / column 0 of every pattern as np.packbits(value > 0)
(the patterns are pure 0/255 stripes).
"""

import datetime
import hashlib
import json
import sys
from importlib import metadata

import cv2
import numpy as np

SIZES = [(37, 19), (800, 600), (1024, 768), (1280, 720), (1280, 800), (1920, 1080)]


def main(path="tests/data/opencv_graycode_golden.json"):
    out = {
        "provenance": {
            "generator": "tools/make_opencv_graycode_golden.py",
            "opencv_version": cv2.__version__,
            "package": "opencv-contrib-python-headless " + metadata.version("opencv-contrib-python-headless"),
            "api": "cv2.structured_light.GrayCodePattern.create(w, h).generate()",
            "date": datetime.date.today().isoformat(),
        },
        "sizes": [],
    }
    for w, h in SIZES:
        gc = cv2.structured_light.GrayCodePattern.create(w, h)
        _, pats = gc.generate()
        stack = np.ascontiguousarray(np.array(pats, dtype=np.uint8))
        out["sizes"].append({
            "width": w, "height": h,
            "count": int(gc.getNumberOfPatternImages()),
            "sha256": hashlib.sha256(stack.tobytes()).hexdigest(),
            "values": sorted(int(v) for v in np.unique(stack)),
            "row0_packbits": [np.packbits(p[0] > 0).tobytes().hex() for p in stack],
            "col0_packbits": [np.packbits(p[:, 0] > 0).tobytes().hex() for p in stack],
        })
    with open(path, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main(*sys.argv[1:])
