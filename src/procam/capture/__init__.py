"""The capture-folder format, both ways: a pose's folder -> validated image stack and its
:class:`~procam.patterns.PatternSet` (:mod:`~procam.capture.read`: :func:`load_capture`), and a pattern or
capture sequence -> a folder of zero-padded PNGs plus ``patterns.json`` (:mod:`~procam.capture.write`:
:func:`write_sequence`); :mod:`~procam.capture.describe` is the sequence a folder holds (its ``patterns.json`` and
the options given); :mod:`~procam.capture.frames` names the frames of a sequence;
:mod:`~procam.capture.phase` checks a phase family's folder and makes its board image; :mod:`~procam.capture.rig`
is the layout of a rig pose (one pose folder per camera-projector pair).
"""

from .frames import describe_frame, frame_role, pair_role  # noqa: F401
from .phase import board_image, check_phase_capture  # noqa: F401
from .read import (Capture, check_light, check_memory, check_pairs, check_white_black, diagnose,  # noqa: F401
                   exposure_warnings, foreign_frames, frame_levels, load_capture, resolve_pattern_set, sample_index,
                   saturated_fraction, sequence_files)
from .rig import (RIG_MANIFEST, RigPair, RigPose, is_rig_pose, pair_folder_name, prepare_rig_dir,  # noqa: F401
                  read_rig_pose, rig_manifest, write_rig_file)
from .write import (SequenceWriter, check_out_dir, check_sequence_dir, remove_stale, sequence_names,  # noqa: F401
                    write_sequence)
