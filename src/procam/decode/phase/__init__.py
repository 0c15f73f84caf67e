"""Decoding the phase families (N-step phase shifting, unwrapped by a unit-frequency cue, by three-frequency
heterodyne or by a Gray code) into sub-pixel projector coordinates with a per-pixel noise estimate.

* :func:`decode_phase` (:mod:`~procam.decode.phase.decoder`) - a stack -> :class:`~procam.decode.decoded.DecodeResult`, what
  :func:`procam.decode.decode` returns for a :class:`~procam.patterns.PhaseSet`;
* :mod:`~procam.decode.phase.wrapped` - the N-step wrapped phase, modulation and mean;
* :mod:`~procam.decode.phase.response` - the projector's gamma: its phase error, its correction, its measurement (and
  the camera's noise);
* :mod:`~procam.decode.phase.unwrap` - temporal unwrapping (hierarchical, heterodyne, Gray code, complementary Gray);
* :mod:`~procam.decode.phase.diagnose` - a description that does not match the frames, named.
"""

from .decoder import SAMPLE, BlockStats, PhaseInfo, PhaseOptions, decode_phase, summary_lines  # noqa: F401
