"""procam: projector-camera calibration from a single pose of a planar target.

The modules, from the captures up (each imports only those above it in this list)::

    errors        ProcamError and its subclasses (one-line messages), procam's warning classes
    io.files      image reads, natural sort, atomic writes, JSON helpers, the manifest of procam's files
                  (the bottom floor of the io package; its format modules stand higher, at io below)
    _threads      one OpenCV / BLAS thread where results must not depend on threads
    _fmt          text of a number in a table
    patterns      Gray-code pattern sets and images (pure)
    capture       the capture-folder format: read + validate a pose folder, the one writer of pattern, simulator
                  and camera folders, the names of a sequence's frames
    stream        read pose folders ahead in background threads (the next pose while this one is processed)
    decode        captured stack -> projector column/row per camera pixel, validity, reasons
    plausibility  does a decoded capture look like the projector it claims (size, swapped or mirrored patterns,
                  rows first), and the plausibility gates every calibration passes
    board         Board (inner corners, square size), object points, the board region of a camera image
    corners       chessboard corner detection and refinement (the one caller of OpenCV's chessboard detector)
    correspond    camera corners -> projector corners by local homographies
    view          View: one pose's board, camera and projector points; the per-corner reasons
    labelling     the canonical labelling of a board's corners (no result depends on how they were numbered)
    pipeline      folder(s) / stack / photo -> View(s)
    models        projection, division distortion, homographies, poses, angles (the model every solver fits)
    parameters    one vocabulary of parameter names
    distortion    centre of distortion, division-model coefficients, OpenCV fit of the division model
    uncertainty   the only Jacobian / covariance code
    crlb          Cramer-Rao bounds of single-pose calibration, on the solvers' own model
    calibration   Calibration, Device, Distortion (results)
    datasheet     a projector's intrinsics as its datasheet words them: throw ratio, lens shift, field of view
    verdict       a calibration's verdict from its evidence; the one glossary of the verdict words
    stats         RMS, robust sigma (MAD), total-least-squares plane: one definition each
    residuals     PnP, stereo pose, per-pose residuals
    single_pose   the seed method (camera, projector, extrinsics, the rating of the pose), with its background
                  check and refinement (single_pose.background) and its misfit test (single_pose.misfit)
    advisor       live pose advice from one camera frame: board angles, predicted stds, which way to turn
    multi_pose    Zhang / Moreno-Taubin multi-pose calibration with a joint refinement
    method        which method a set of views calls for (single-pose, multi-pose, camera-only), and the calibration
    evaluate      reprojection, stereo and PnP-precision metrics of a calibration on poses
    summary       a calibration as rows of text: the tables the CLI prints and the report shows
    io            every file format: calibrations (procam JSON, OpenCV YAML/XML, kamino410 XML) read by one
                  reader and checked by one validator set, correspondences, decoded and remap maps, PLY
    triangulate   camera pixel + projector column/row -> 3-D point (the geometry of a scan)
    verify        a calibration measured in millimetres: board scale, planarity, leave-one-out spread
    reconstruct   a decoded capture -> point cloud, the board's plane
    export        a calibration for the next tool: OpenGL/Unity matrices, undistortion and rectification maps
    check         one captured pose judged before calibration (verdict + overlay)
    simulate      synthetic procam captures with ground truth (the test oracle)
    paper         the paper's simulation study and real-data experiment
    plots         matplotlib figures (matplotlib imported only when a figure is drawn)
    acquire       the devices (projector window, cameras by backend), the checked capture loop, live advice,
                  and the whole capture session of ``procam capture``
    report        a calibration as one self-contained HTML page (verdict, parameters, figures, verification)
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
               "plots", "report", "plausibility", "triangulate", "verify", "reconstruct", "export", "check",
               "acquire", "corners", "datasheet", "labelling")

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
