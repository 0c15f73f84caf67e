"""Decoding the phase families (N-step phase shifting, unwrapped by a unit-frequency cue, by three-frequency
heterodyne or by a Gray code) into sub-pixel projector coordinates with a per-pixel noise estimate.

* :func:`decode_phase` (:mod:`~procam.phase.decoder`) - a stack -> :class:`~procam.decoded.DecodeResult`, what
  :func:`procam.decode.decode` returns for a :class:`~procam.patterns.PhaseSet`;
* :mod:`~procam.phase.wrapped` - the N-step wrapped phase, modulation and mean;
* :mod:`~procam.phase.response` - the projector's gamma: its phase error, its correction, its measurement (and
  the camera's noise);
* :mod:`~procam.phase.unwrap` - temporal unwrapping (hierarchical, heterodyne, Gray code, complementary Gray);
* :mod:`~procam.phase.diagnose` - a description that does not match the frames, named.
"""

from .decoder import SAMPLE, BlockStats, PhaseInfo, PhaseOptions, decode_phase, summary_lines  # noqa: F401
