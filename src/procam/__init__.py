"""procam: projector-camera calibration from a single pose of a planar target.

The rooms, from the ground floor up (each imports only rooms below it; ``docs/architecture.md`` says each one's job
and ``tests/test_architecture.py`` holds the code to it)::

    errors, choices, style, parameters, stats, uncertainty, datasheet, mounting     words, numbers, the palette
    models        projection and the one lens-model module (division, OpenCV's k1 k2 p1 p2 k3)
    verdict       a calibration's verdict, the one glossary of its words, the plausibility gates (verdict.gates)
    triangulate   camera pixel + projector coordinate -> 3-D point
    board         the printed chessboard: geometry, corner detection (board.corners), labelling (board.labelling)
    calibration   Calibration, Device, Distortion, RigCalibration (results)
    crlb, distortion, residuals, summary, view, evaluate
    io            every file procam reads or writes, parsed and validated in one place (io.files, io.jsonfile)
    patterns      what each projected frame shows (Gray, phase, heterodyne, Gray + phase)
    export, reconstruct
    decode        a captured stack -> projector coordinates (Gray; phase families in decode.phase), and its
                  plausibility (decode.plausibility)
    capture       the capture-folder format both ways
    correspond    camera corners -> projector corners (local homographies), dense samples (correspond.samples)
    plots         matplotlib figures (matplotlib imported only when a figure is drawn)
    single_pose   the seed method; multi_pose (the one N-device bundle adjuster); advisor; simulate; stream
    pipeline      folder(s) / stack / photo -> View(s)
    method        the one method rule; verify (millimetres); check (one pose judged); paper (the paper's study)
    rig, acquire  several devices; driving the projector and the cameras
    report, world_check
    cli           the ``procam`` command line (thin: parse, call the API, print)

Conventions (``docs/conventions.md``): pixels are (x, y) = (column, row) with the origin at the centre of
the top-left pixel; ``x_p = R @ x_c + T`` maps camera to projector coordinates; lengths are in the board's
square-size unit; angles are degrees at the user surface and radians inside the code.

Submodules load on first use (``import procam; procam.single_pose.calibrate(...)``), so importing procam
is cheap.

>>> import procam
>>> procam.Board(10, 6, 24.0).n_corners
60
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_SUBMODULES = ("errors", "patterns", "capture", "stream", "decode", "board", "correspond", "view", "pipeline", "models",
               "parameters", "distortion", "uncertainty", "crlb", "calibration", "verdict", "residuals", "stats",
               "single_pose", "advisor", "multi_pose", "method", "evaluate", "summary", "io", "simulate", "paper",
               "plots", "report", "triangulate", "verify", "reconstruct", "export", "check", "acquire", "datasheet",
               "rig", "world_check", "style", "mounting", "choices")

#: Public names re-exported here: name -> module.
_EXPORTS = {"ProcamError": "errors", "Board": "board", "View": "view", "Calibration": "calibration",
            "Device": "calibration", "Distortion": "calibration", "PoseOptions": "pipeline"}

__all__ = ["__version__", *_SUBMODULES, *_EXPORTS]


def __getattr__(name: str):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
