"""The report page of a rig calibration (``procam report RIG.json``, ``procam calibrate RIGPOSE... --report``).

Top to bottom: the rig's verdict in words with every device's verdict and reasons; the rig drawn from above
(:func:`procam.rig.draw.rig_figure`, inline PNG); the devices with their intrinsics ± std
(:func:`procam.rig.tables.device_table`); every relative pose with its std, projector to projector included
(:func:`procam.rig.tables.relative_table`), under the statement of what the ± assumes; the pairs' 3-D agreement
(:func:`procam.rig.verify.verify_rig`, :func:`procam.rig.tables.agreement_table`); then each pair's parameters,
model and assumptions as the single-pair page shows them (:func:`procam.report.sections.parameters_section`).

The agreement is measured on the rig poses given, else on the poses each pair's calibration keeps (a rig file
written by procam keeps them: every pair has one view per rig pose, in the same order); without either the
section says so.  Self-contained and escaped like the single-pair page (:func:`procam.report.page.html_page`).
"""

from __future__ import annotations

from html import escape

from ..summary import short_name
from ..verdict import MEANING
from .elements import png, text_table
from .page import html_page
from .sections import parameters_section

__all__ = ["RIG_SECTIONS", "build_rig_report", "stored_rig_poses"]

#: The rig page's sections, in order (then one ``pair-<camera>-<projector>`` section per pair).
RIG_SECTIONS = {"verdict": "Verdict", "drawing": "The rig seen from above", "devices": "Devices",
                "relative": "Relative poses", "agreement": "Agreement of the pairs in 3-D"}


def _section(sid: str, heading: str, body: str, cls: str = "") -> str:
    c = f' class="{cls}"' if cls else ""
    return f'<section id="{escape(sid)}"{c}>\n<h2>{heading}</h2>\n{body}\n</section>'


def stored_rig_poses(rc) -> list:
    """The :class:`~procam.rig.calibrate.RigPoseViews` rebuilt from the views every pair's calibration keeps
    (pose ``k`` = every pair's ``k``-th view); empty when a pair keeps none or the pairs' counts differ."""
    from ..rig.calibrate import RigPoseViews

    counts = {len(cal.views) for cal in rc.pairs.values()}
    if len(counts) != 1 or 0 in counts:
        return []
    n = counts.pop()
    names = list(rc.pose_names) if len(rc.pose_names) == n else [f"pose {k + 1}" for k in range(n)]
    cams, projs = tuple(d.name for d in rc.cameras), tuple(d.name for d in rc.projectors)
    return [RigPoseViews(names[k], cams, projs,
                         {tuple(key.split("/", 1)): cal.views[k] for key, cal in rc.pairs.items()}) for k in range(n)]


def _verdict_section(rc) -> str:
    word = rc.verdict
    meaning = MEANING.get(word, "")
    parts = [(f"<p><strong>{escape(meaning[:1].upper() + meaning[1:])}.</strong> The rig's verdict is its worst "
              "device's.</p>")]
    rows = []
    for d in rc.devices:
        reasons = "".join(f"<li>{escape(r)}</li>" for r in d.verdict_reasons) or "<li>nothing flagged</li>"
        rows.append(f'<tr class="device-verdict {escape(d.verdict)}"><td class="l">{escape(d.name)}</td>'
                    f'<td class="l">{escape(d.kind)}</td><td class="l"><span class="word">{escape(d.verdict)}</span>'
                    f'</td><td class="l"><ul>{reasons}</ul></td></tr>')
    parts.append('<table id="device-verdicts"><thead><tr><th class="l">device</th><th class="l">kind</th>'
                 '<th class="l">verdict</th><th class="l">why</th></tr></thead><tbody>' + "".join(rows)
                 + "</tbody></table>")
    others = [w for w in rc.warnings if w not in rc.verdict_reasons]
    if others:
        parts.append('<p class="warn"><strong>Flagged:</strong></p><ul class="warn">'
                     + "".join(f"<li>{escape(w)}</li>" for w in others) + "</ul>")
    return (f'<section id="verdict" class="verdict {escape(word)}">\n<h2>Verdict: <span class="word">'
            f'{escape(word)}</span></h2>\n' + "\n".join(parts) + "\n</section>")


def _agreement_body(agreement, measured_on: str) -> str:
    from ..rig.tables import agreement_table

    if agreement is None:
        return ("<p>Not measured: no rig poses were given and the pairs keep none (give the rig pose folders: "
                "<code>procam report RIG.json RIGPOSE... --board COLSxROWS --square S</code>).</p>")
    if not agreement:
        return "<p>Nothing to compare: no two pairs share a camera at any pose.</p>"
    ok = [a for a in agreement if a.n]
    worst = max(ok, key=lambda a: a.rms_pct) if ok else None
    head = (f"<p>The board corners two pairs both decoded, triangulated by each pair's calibration and compared in "
            f"the reference camera's frame ({escape(measured_on)}); the distance holds the corner noise of two "
            "captures as well as any error of the devices' poses and intrinsics.")
    if worst is not None:
        head += (f" Worst: {escape(worst.a)} vs {escape(worst.b)} at {escape(short_name(worst.pose))}, "
                 f"{worst.rms_mm:.3f} mm rms ({worst.rms_pct:.3f} % of the depth).")
    return head + "</p>\n" + text_table(agreement_table(agreement))


def _pair_section(key: str, cal) -> str:
    slug = "pair-" + key.replace("/", "-")
    reasons = "".join(f"<li>{escape(r)}</li>" for r in cal.verdict_reasons)
    body = (f'<p>Verdict of the pair: <span class="word">{escape(str(cal.verdict))}</span>; camera RMS '
            f"{cal.cam_rms:.3f} px, projector RMS {cal.proj_rms:.3f} px; in the pair's camera frame "
            f"(x_p = R x_c + T), as <code>procam export --pair {escape(key)}</code> writes it.</p>"
            + (f"<ul>{reasons}</ul>" if reasons else "")
            + parameters_section(cal).replace('id="datasheet"', f'id="{escape(slug)}-datasheet"'))
    return _section(slug, f"Pair {escape(key)}", body)


def build_rig_report(rc, poses=None, *, agreement=None, name: str = "rig", notes=(), pairs: bool = True) -> str:
    """The HTML page of a rig calibration (module docstring).

    Parameters
    ----------
    rc : :class:`procam.rig.RigCalibration`.
    poses : :class:`~procam.rig.calibrate.RigPoseViews` to verify on (default: the pairs' own,
        :func:`stored_rig_poses`).
    agreement : the :func:`~procam.rig.verify.verify_rig` figures when already computed (then ``poses`` is
        not used).
    name : the calibration's name in the title; ``notes`` : extra lines for the top of the page.
    pairs : add each pair's parameter section.

    Returns
    -------
    str : the whole page (UTF-8 text).
    """
    from .. import __version__
    from ..rig.draw import rig_figure
    from ..rig.tables import device_table, relative_table
    from ..rig.verify import verify_rig

    measured_on = "the rig poses given"
    if agreement is None:
        if poses is None:
            poses = stored_rig_poses(rc)
            measured_on = "the poses the calibration was fitted to: in-sample"
        agreement = verify_rig(rc, poses) if poses else None
    fig = rig_figure(rc, agreement or (), title=name)
    drawing = (png(fig, f"the rig {name} seen from above", dpi=90)
               + '<p class="note">Top view in the reference camera\'s frame (x right, z forward): each device\'s '
                 "horizontal field of view coloured by its verdict; + marks the board poses.</p>")
    n_proj = len(rc.projectors)
    pp = [k for k, r in rc.relative.items() if rc.device(r.a).kind == rc.device(r.b).kind == "projector"]
    rel_note = (f'<p class="note">x_b = R x_a + T, board units (mm for a board in mm), intrinsic XYZ Euler angles '
                f"in degrees; {escape(rc.uncertainty)}.</p>")
    if pp:
        r = rc.relative[pp[0]]
        rel_note += (f"<p>Projector to projector ({escape(pp[0])}): baseline {r.baseline:.2f} ± "
                     f"{r.std_baseline:.2f} ({100 * r.std_baseline / max(r.baseline, 1e-12):.3f} % of it).</p>")
    sections = [_verdict_section(rc),
                _section("drawing", RIG_SECTIONS["drawing"], drawing),
                _section("devices", RIG_SECTIONS["devices"],
                         f'<p class="note">± 1 sigma; reference camera {escape(rc.reference)}.</p>'
                         + text_table(device_table(rc))),
                _section("relative", RIG_SECTIONS["relative"], rel_note + text_table(relative_table(rc))),
                _section("agreement", RIG_SECTIONS["agreement"], _agreement_body(agreement, measured_on))]
    if pairs:
        sections += [_pair_section(k, cal) for k, cal in rc.pairs.items()]
    n_cam = len(rc.cameras)
    head = (f'<p class="meta">{escape(rc.method)} rig calibration of {n_cam} camera{"s" if n_cam != 1 else ""} '
            f'and {n_proj} projector{"s" if n_proj != 1 else ""}, {len(rc.pose_names)} rig pose'
            f'{"s" if len(rc.pose_names) != 1 else ""}; procam {escape(__version__)}.</p>')
    extra = "".join(f'<p class="note">{escape(n)}</p>' for n in notes)
    return html_page(f"procam rig report: {name}", f"procam rig calibration report: {name}", [head, extra, *sections])
