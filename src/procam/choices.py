"""The closed sets of words a user can choose from: one definition each, importing nothing.

The library modules take their choices from here (``decode.METHODS is choices.DECODE_METHODS`` ...) and the
command line lists the same tuples in ``--help``, so the two cannot drift; because this module imports nothing,
``procam --help`` and ``procam --version`` start without loading numpy, OpenCV or scipy.
"""

#: Gray-code frame orders (:mod:`procam.patterns`): OpenCV's GrayCodePattern order, Moreno-Taubin's.
PATTERN_ORDERS = ("opencv", "moreno")
#: Pattern families (:mod:`procam.patterns`): Gray codes with inverses; N-step phase shifting unwrapped by a
#: unit-frequency cue, by three-frequency heterodyne, or by a Gray code.
PATTERN_FAMILIES = ("gray", "phase", "heterodyne", "gray-phase")
#: What the phase decoder does about the projector's response (:mod:`procam.decode.phase`).
GAMMA_MODES = ("auto", "none")
#: Bit classifiers of the decoder (:mod:`procam.decode`).
DECODE_METHODS = ("robust", "simple")
#: Chessboard detectors and corner refinements (:mod:`procam.board.corners`).
DETECTORS = ("auto", "classic", "sb")
REFINERS = ("fit", "subpix", "none")
#: Local-homography estimators (:mod:`procam.correspond`).
ESTIMATORS = ("trimmed", "lsq", "ransac", "lmeds")
#: Single-pose camera: where its principal point comes from, and its final refinement (:mod:`procam.single_pose`).
COD_MODES = ("auto", "paper", "image-center")
CAMERA_REFINE_MODES = ("joint", "none")
#: What the single-pose fit does with the scene behind the board (:mod:`procam.single_pose.background`).
BACKGROUND_MODES = ("off", "check", "auto", "free")
#: OpenCV distortion models of the multi-pose fit (:mod:`procam.multi_pose`), and ``auto``.
DIST_MODELS = ("none", "k1", "k1k2", "k1k2p1p2", "k1k2p1p2k3", "rational")
DIST_CHOICES = ("auto", *DIST_MODELS)
#: Calibration methods (:mod:`procam.method`).
METHODS = ("single-pose", "multi-pose", "camera-only")
#: Export formats and the world frame of engine exports (:mod:`procam.export`).
EXPORT_FORMATS = ("opengl", "blender", "unity", "maps", "kamino410", "yaml", "projector-view")
WORLDS = ("camera", "projector")
#: The two devices of a camera-projector pair (a frame, a swept device).
DEVICES = ("camera", "projector")
#: The simulator's ready rigs (:data:`procam.simulate.PRESETS`).
SIM_PRESETS = ("paper", "ideal", "lensshift", "hard", "vertical", "ceiling")
#: The length unit of a calibration (the board's square), which the engine exports turn into metres.
LENGTH_UNITS = ("mm", "cm", "m", "in")
#: Which projector coordinates a triangulation uses (:mod:`procam.triangulate`).
TRIANGULATION_USES = ("both", "col", "row")
