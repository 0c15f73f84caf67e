"""Shared header for benchmark tables: machine, date, commit."""

from __future__ import annotations

import datetime
import os
import platform
import subprocess


def header(title: str) -> str:
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=os.path.dirname(__file__)).stdout.strip() or "unknown"
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                               text=True, cwd=os.path.dirname(__file__)).stdout.strip()
    except OSError:
        commit, dirty = "unknown", ""
    import numpy as np

    try:
        import cv2

        cvv = cv2.__version__
    except ImportError:
        cvv = "-"
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return (f"# {title}\n"
            f"machine: {platform.node()} | {cpu} | {os.cpu_count()} cores | Python {platform.python_version()} | "
            f"numpy {np.__version__} | OpenCV {cvv}\n"
            f"date: {datetime.datetime.now().isoformat(timespec='seconds')} | commit: {commit}{' (+local changes)' if dirty else ''}\n")
