"""A calibration's verdict from its evidence, and the one glossary of the verdict words.

Every calibration ends in one word -- ``good``, ``weak``, ``degenerate`` or ``failed`` (:data:`LEVELS`) -- with
its reasons in words; a file that records none (an OpenCV YAML file, an old JSON file) is ``unknown``.
:data:`MEANING` says what each word means; the JSON and YAML writers store it next to the word, the HTML
report prints it under the verdict, so a reader meets one wording everywhere.

:func:`calibration_verdict` is the single place the report, the figures and the CLI read a verdict from.
Its evidence, in order:

1. the calibration's own ``verdict`` and ``verdict_reasons`` (set by the solver that made it:
   :mod:`procam.single_pose.rating` rates a single pose, :mod:`procam.multi_pose` calls a pose set with
   warnings weak);
2. failing that, each pose's rating (the ``"advice"`` entry of ``calib.poses[i]``, the name the file format
   has kept: per device ``failed``, ``degenerate``, ``weak`` flags and a message) -- the worst device wins;
3. then the calibration's ``warnings``: every warning not already a reason is added, and for a calibration
   without per-pose ratings (multi-pose) each one makes it weak, as do fewer than 3 poses.

No statistics are computed here: the verdict only reads what the solvers measured. A file with no poses and
no recorded verdict stays ``unknown`` -- the word says there is no evidence, not that the calibration is bad.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["LEVELS", "VERDICTS", "MEANING", "Verdict", "calibration_verdict"]

#: The verdict levels a solver gives, from best to worst.
LEVELS = ("good", "weak", "degenerate", "failed")

#: Every verdict word, best first: the levels and ``unknown`` (no evidence recorded).
VERDICTS = (*LEVELS, "unknown")

#: What each verdict word means: written next to the word in the calibration files and under it in the report.
MEANING = {
    "good": "fit to use",
    "weak": "usable: less precise than a better pose (set) would make it; see the reasons",
    "degenerate": "do not use: the poses do not determine some parameters, whose values may be anything",
    "failed": "do not use: an estimate is impossible for a real device",
    "unknown": "the file records no verdict",
}


@dataclass(frozen=True)
class Verdict:
    """A calibration's verdict in words.

    Attributes
    ----------
    word : one of :data:`VERDICTS` (``good``, ``weak``, ``degenerate``, ``failed``, ``unknown``).
    reasons : the messages behind it, one line each (most important first).
    """

    word: str
    reasons: tuple = ()

    @property
    def meaning(self) -> str:
        """What the word means (:data:`MEANING`)."""
        return MEANING[self.word]

    def line(self) -> str:
        """``"word: first reason"`` (a good verdict: all its reasons), for figure titles and terminals."""
        if not self.reasons:
            return self.word
        return f"{self.word}: " + ("; ".join(self.reasons) if self.word == "good" else self.reasons[0])


def _rating_messages(calib) -> list[str]:
    """Every device's rating message over the poses (the words of a good single-pose verdict)."""
    return [a["message"] for p in calib.poses for k in ("camera", "projector")
            if isinstance(a := (p.get("advice") or {}).get(k), dict) and a.get("message")]


def _multi_pose_words(calib) -> list[str]:
    how = "jointly refined" if calib.info.get("refined") else "without a joint refinement"
    return [f"{len(calib.poses)} poses, {how}, no warnings"]


def calibration_verdict(calib) -> Verdict:
    """The verdict of a calibration in words, from what the calibration carries.

    The calibration's own ``verdict`` and ``verdict_reasons`` when it records them. For a file that records
    none (``verdict == "unknown"``) it is derived from each pose's rating (``calib.poses[i]["advice"]``:
    ``failed``, ``degenerate``, ``weak``) and the calibration's ``warnings``: any failed device -> ``failed``;
    any degenerate one -> ``degenerate``; any weak one, or any warning -> ``weak``; else ``good``.  A
    multi-pose calibration (no per-pose rating) is ``weak`` with fewer than 3 poses or with warnings, else
    ``good``; a file with no poses (OpenCV YAML) is ``unknown``.

    Returns
    -------
    :class:`Verdict`
    """
    if calib.verdict != "unknown":  # the calibration's own verdict (procam.single_pose.rating / multi_pose)
        reasons = list(calib.verdict_reasons)
        if not reasons:
            reasons = _rating_messages(calib) or (_multi_pose_words(calib) if calib.method == "multi-pose" else [])
        return Verdict(calib.verdict, tuple(reasons))
    word, reasons = "good", []
    rank = {w: i for i, w in enumerate(VERDICTS)}

    def worse(w):
        nonlocal word
        if rank[w] > rank[word] and word != "unknown":
            word = w

    rated = False
    for p in calib.poses:
        rating = p.get("advice") or {}
        if not rating:
            continue
        rated = True
        for key in ("camera", "projector"):
            a = rating.get(key)
            if not isinstance(a, dict):
                continue
            w = ("failed" if a.get("failed") else "degenerate" if a.get("degenerate") else
                 "weak" if a.get("weak") else "good")
            worse(w)
            if w != "good" and a.get("message"):
                name = Path(str(p.get("name", ""))).name
                reasons.append(f"{name}: {a['message']}" if len(calib.poses) > 1 and name else a["message"])
    if not rated and not calib.poses:
        word = "unknown"
    if calib.method == "multi-pose" and 0 < len(calib.poses) < 3:
        worse("weak")
    if word == "good":
        if rated:
            reasons = _rating_messages(calib)
        elif calib.method == "multi-pose" and not calib.warnings:
            reasons = _multi_pose_words(calib)
    for w in calib.warnings:
        if not any(r.split(": ", 1)[-1] in w for r in reasons):
            reasons.append(str(w))
            if not rated and word != "unknown":  # a multi-pose calibration's warnings are all weaknesses
                worse("weak")
    return Verdict(word, tuple(reasons))
