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

The metric verification (:mod:`procam.verify`) is evidence too: :func:`evidence_reasons` reads it (the
triangulated board's scale error, in-sample and held out; the held-out reprojection RMS against the in-sample
one) and :func:`with_evidence` makes the verdict worse where it says so -- ``procam calibrate`` does this before
it writes anything, the report before it shows the verdict. :func:`flagged` lists everything a careful reader
should know, the list the report prints under the verdict.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import isfinite
from pathlib import Path

__all__ = ["LEVELS", "VERDICTS", "MEANING", "Verdict", "calibration_verdict", "EvidenceOptions", "evidence_reasons",
           "with_evidence", "flagged"]

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


# --------------------------------------------------------------------------------------------------
# the verdict with the metric verification's evidence, and what was flagged
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class EvidenceOptions:
    """Thresholds of :func:`evidence_reasons`.

    Attributes
    ----------
    weak_scale_pct, failed_scale_pct : a triangulated board whose squares are this many percent off the printed
        size (in-sample or held out) makes the calibration weak / failed.
    weak_reproj_ratio, degenerate_reproj_ratio : held-out reprojection RMS over the in-sample one above which the
        calibration does not carry to other poses (weak), or not at all (degenerate) ...
    min_reproj_px : ... when the held-out RMS is also above this (noise-free data have ratios of tiny numbers).
    """

    weak_scale_pct: float = 2.0
    failed_scale_pct: float = 10.0
    weak_reproj_ratio: float = 3.0
    degenerate_reproj_ratio: float = 10.0
    min_reproj_px: float = 1.0


def evidence_reasons(check, options: EvidenceOptions = EvidenceOptions()) -> list[tuple[str, str]]:
    """``[(level, reason)]`` from a calibration's metric verification (a
    :class:`procam.verify.CalibrationVerification`): the triangulated board's scale error, in-sample and on poses
    the calibration was not fitted to (given held-out poses, or leave-one-pose-out), and the held-out
    reprojection RMS against the in-sample one. Empty when nothing is off or there is no verification."""
    if check is None:
        return []
    out = []
    o = options
    held = [(label, ver) for label, ver in (("on the held-out poses", check.held_out),
                                            ("leaving each pose out", check.leave_one_out.held_out
                                             if check.leave_one_out is not None else None)) if ver is not None]
    for label, ver in [("on its own poses", check.in_sample)] + held:
        if ver is None:
            continue
        s = ver.overall.scale_error_pct
        if isfinite(s) and abs(s) > o.weak_scale_pct:
            level = "failed" if abs(s) > o.failed_scale_pct else "weak"
            out.append((level, f"metric verification {label}: the triangulated board's squares are {s:+.1f} % off "
                               f"the printed size (a calibration fit to use measures within a few tenths of a %)"))
    if check.in_sample is not None:
        r_in = check.in_sample.overall.reproj_rms
        for label, ver in held:
            r = ver.overall.reproj_rms
            if not (isfinite(r) and isfinite(r_in) and r > o.min_reproj_px and r_in > 0):
                continue
            ratio = r / r_in
            if ratio > o.weak_reproj_ratio:
                level = "degenerate" if ratio > o.degenerate_reproj_ratio else "weak"
                out.append((level, f"{label}, the reprojection RMS is {r:.2f} px, {ratio:.0f} times the in-sample "
                                   f"{r_in:.2f} px: the calibration does not carry over to other poses of this rig"))
    return out


def with_evidence(calib, check, options: EvidenceOptions = EvidenceOptions()):
    """The calibration with its verdict made worse where its metric verification says so
    (:func:`evidence_reasons`): :func:`with_reasons` of them."""
    return with_reasons(calib, evidence_reasons(check, options), stacklevel=3)


def with_reasons(calib, reasons, *, stacklevel: int = 2):
    """The calibration with its verdict made worse by ``reasons`` (``[(level, message)]``, level ``weak``,
    ``degenerate`` or ``failed``): the messages join ``verdict_reasons`` and ``warnings`` and are emitted as the
    procam warning of their level. Unchanged when there are none (or only what it already says)."""
    import warnings as _warnings

    from ..errors import DegeneratePoseWarning, FailedEstimateWarning, WeakPoseWarning

    new = [(lvl, r) for lvl, r in reasons if r not in calib.verdict_reasons]
    if not new:
        return calib
    rank = LEVELS.index
    word = max([calib.verdict if calib.verdict in LEVELS else "good"] + [lvl for lvl, _ in new], key=rank)
    worst = [r for lvl, r in new if lvl == word]
    rest = [r for lvl, r in new if lvl != word]
    category = {"weak": WeakPoseWarning, "degenerate": DegeneratePoseWarning, "failed": FailedEstimateWarning}
    for lvl in ("failed", "degenerate", "weak"):
        msgs = [r for level, r in new if level == lvl]
        if msgs:
            _warnings.warn("; ".join(msgs), category[lvl], stacklevel=stacklevel)
    return calib.replace(verdict=word, verdict_reasons=tuple(worst) + tuple(calib.verdict_reasons) + tuple(rest),
                         warnings=tuple(calib.warnings) + tuple(r for _, r in new if r not in calib.warnings))


def _pose_name(p, n_poses) -> str:
    name = Path(str(p.get("name", ""))).name
    return f"pose {name!r}: " if name and n_poses > 1 else ""


def flagged(calib, check=None, views=None) -> list[str]:
    """Everything about a calibration a careful reader should know, one short line each: its verdict's reasons
    (other than a good pose's "pose OK"), every warning it carries, the warnings of the poses' capture (e.g.
    saturation), corners rejected as outliers, a principal point taken from a prior, and the metric
    verification's notes and evidence (:func:`evidence_reasons`). The report's verdict lists them; "nothing was
    flagged" is said only when this is empty.

    Parameters
    ----------
    calib : :class:`~procam.calibration.Calibration`; check : its :class:`procam.verify.CalibrationVerification`
        (optional); views : the poses shown with it (default: its own).
    """
    out: list[str] = []

    def add(line):
        line = str(line)
        if line and not any(line in o or o in line for o in out):
            out.append(line)

    verdict = calibration_verdict(calib)
    if verdict.word != "good":
        for r in verdict.reasons:
            add(r)
    for w in calib.warnings:
        add(w)
    own = list(calib.views)
    for v in own + [v for v in (views or ()) if not any(v is w for w in own)]:
        for w in (getattr(v, "diagnostics", None) or {}).get("warnings", []):
            add(w)
    n = len(calib.poses)
    for p in calib.poses:
        for device, rej in (p.get("rejected_corners") or {}).items():
            if rej:
                add(f"{_pose_name(p, n)}{len(rej)} {device} corner{'s' if len(rej) != 1 else ''} rejected as outliers "
                    f"(#{', #'.join(str(r['index'] if isinstance(r, dict) else r) for r in rej[:8])}"
                    + (" ..." if len(rej) > 8 else "") + ")")
    if calib.info.get("principal_point_source") == "image-center":
        add("the camera's principal point is a prior (the image centre), not measured from this pose")
    if check is not None:
        for note in check.notes:
            add(f"note: {note}")
        for _, r in evidence_reasons(check):
            add(r)
    return out


def rejection_message(rejected, norms, words: dict) -> str | None:
    """The warning that lists the rejected corners (indices ``rejected`` (n,), residual norms ``norms`` (n,) px) by
    the data of :func:`procam.single_pose._robust.rejection_report` (``words``: pose name, device, counts,
    threshold, rule); None when none was rejected. Worded here, with the verdict's other words, so that a solver
    and a renumbering of the board (:mod:`procam.board.labelling`) word it alike."""
    import numpy as np

    rej, norms = np.asarray(rejected, int), np.asarray(norms, float)
    if not len(rej):
        return None
    n, max_list = len(rej), words["max_list"]
    order = np.argsort(-np.nan_to_num(norms, nan=np.inf))
    listed = ", ".join(f"#{rej[i]} ({norms[i]:.1f} px)" for i in order[:max_list])
    more = f" and {n - max_list} more" if n > max_list else ""
    return (f"pose {words['name']!r}: {n} of {words['n_valid']} {words['what']} corners rejected as outliers "
            f"(residual > {words['threshold_px']:.2f} px = max({words['floor_px']:g} px, {words['k']:g} x robust "
            f"sigma)): {listed}{more}; the fit uses the other {words['n_used']} (reject_outliers=False keeps them)")
