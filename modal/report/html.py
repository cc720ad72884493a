"""The self-contained HTML report of an archive (``python -m modal report``).

One file: the tables are HTML, the figures are drawn in the browser by the report's own small
script (``assets/report.js``, about 20 kB) from JSON inside the page, and the figures of a scene's
balancing stages are PNG images inside the page. A Content-Security-Policy forbids every request,
so the file opens offline and fetches nothing.

Sections (element ids): ``glance`` (the test at a glance), ``modes`` (table of modes and flags),
``frf`` (measured FRFs with the models, coherence), ``stabilisation``, ``mac`` (auto- and cross-MAC),
``shapes`` (animated mode shapes on the geometry) and, for a scene archive, ``scene``.
"""
from __future__ import annotations

import base64
import html
import os
from importlib import resources
from pathlib import Path

import numpy as np

from ..flags import INFORMATIONAL
from .content import ReportContent, flag_legend, mode_rows, report_content
from .payload import frf_payload, shapes_payload, stabilisation_payload, to_json

__all__ = ["build_report", "write_report", "SECTIONS"]

#: the report's sections, in order: (element id, heading)
SECTIONS = (("glance", "The test at a glance"), ("modes", "Modes"), ("frf", "FRFs and the fitted models"),
            ("stabilisation", "Stabilisation diagram"), ("mac", "MAC"), ("shapes", "Mode shapes"),
            ("scene", "Scene results"))
_CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'; script-src 'unsafe-inline'"


def _asset(name: str) -> str:
    return resources.files("modal.report").joinpath("assets", name).read_text(encoding="utf-8")


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _table(header, rows, classes=None) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = []
    for row in rows:
        cells = []
        for k, cell in enumerate(row):
            cls = f' class="{classes[k]}"' if classes and classes[k] else ""
            cells.append(f"<td{cls}>{cell}</td>")
        body.append("<tr>" + "".join(cells) + "</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"


def _flags_html(flags) -> str:
    if not flags:
        return "—"
    return "".join(f'<span class="flag{" info" if f in INFORMATIONAL else ""}" title="{_e(f)}">{_e(f)}</span>'
                   for f in flags)


def _glance(content: ReportContent) -> str:
    return _table(("", ""), [(f"<b>{_e(k)}</b>", _e(v)) for k, v in content.glance])


def _modes(content: ReportContent) -> str:
    if not content.results:
        return '<p class="note">The archive holds no identification result.</p>'
    parts = []
    header = ("#", "f_n [Hz]", "ζ [%]", "MPC", "MPD", "k [N/m]", "c [N s/m]", "m [kg]", "k, c, m at channel", "flags")
    num = ["num"] * 9 + [None]
    for result, shapes in zip(content.results, content.shapes):
        rows = [(str(r["number"]), _e(r["frequency"]), _e(r["damping"]), _e(r["mpc"]), _e(r["mpd"]), _e(r["k"]),
                 _e(r["c"]), _e(r["m"]), _e(r["kcm_channel"]), _flags_html(r["flags"]))
                for r in mode_rows(result, shapes)]
        parts.append(f"<h3>method {_e(result.method)}: {len(result.modes)} mode(s)</h3>" + _table(header, rows, num))
    parts.append('<p class="note">Values ± one standard error. k, c, m are defined at a driving point only (the '
                 'first such channel is shown; every channel is in the archive). MPC: modal phase collinearity '
                 '(1 for a real mode); MPD: mean phase deviation of the shape.</p>')
    legend = flag_legend(content.results)
    if legend:
        parts.append("<h3>Flags: what they mean and what to do</h3>"
                     + _table(("flag", "meaning", "what to do"),
                              [(_flags_html([f]), _e(text), _e(action)) for f, text, action in legend]))
    else:
        parts.append('<p class="note">No mode carries a flag.</p>')
    return "".join(parts)


def _frf(content: ReportContent, payload: dict) -> str:
    if content.frf is None:
        return '<p class="note">The archive holds no FRF.</p>'
    coherence = any(e["coherence"] is not None for e in payload["frf"]["entries"])
    return ('<div class="controls"><label>channel <select id="frf-channel"></select></label>'
            '<span class="note">drag across a plot to zoom, double-click to reset</span></div>'
            '<canvas class="plot" id="frf-mag"></canvas><canvas class="plot" id="frf-phase"></canvas>'
            '<p class="note" id="frf-phase-note" hidden>The RMS over channels has no phase: pick a channel.</p>'
            + ('<canvas class="plot" id="frf-coherence"></canvas>' if coherence else
               '<p class="note">No coherence: the FRF was not estimated from time data in this archive.</p>')
            + (f'<p class="note">{_e(payload["frf"]["note"])}</p>' if payload["frf"]["note"] else ""))


def _stabilisation(content: ReportContent, payload: dict) -> str:
    if not payload["stabilisation"]:
        methods = ", ".join(r.method for r in content.results) or "none"
        return (f'<p class="note">No stabilisation diagram: the methods here ({_e(methods)}) fit mode by mode; the '
                'global and output-only methods sweep model orders and draw one.</p>')
    parts = []
    for k, d in enumerate(payload["stabilisation"]):
        parts.append(f'<h3>method {_e(d["method"])}</h3><canvas class="plot" id="stab-{k}"></canvas>')
    parts.append('<p class="note">Poles of every model order by stability (grey new or unstable, orange frequency, '
                 'purple frequency and vector, blue frequency and damping, green all stable); the chosen modes as '
                 'vertical lines (green clean, red flagged); the RMS of |H| on the right axis.</p>')
    return "".join(parts)


def _mac_table(matrix: np.ndarray, rows, cols) -> str:
    head = "<tr><th></th>" + "".join(f"<th>{_e(c)}</th>" for c in cols) + "</tr>"
    body = []
    for label, values in zip(rows, matrix):
        cells = []
        for v in values:
            shade = int(round(255 - 180 * min(max(v, 0.0), 1.0)))
            colour = "#fff" if v > 0.6 else "#222"
            cells.append(f'<td style="background:rgb({shade},{shade + (255 - shade) // 3},255);color:{colour}">'
                         f"{v:.2f}</td>")
        body.append(f"<tr><th>{_e(label)}</th>{''.join(cells)}</tr>")
    return f'<table class="mac"><thead>{head}</thead><tbody>{"".join(body)}</tbody></table>'


def _mac(content: ReportContent) -> str:
    from ..shapes import auto_mac, cross_mac

    available = [s for s in content.shapes if s is not None]
    if not available:
        return '<p class="note">No mode shapes: no MAC.</p>'
    parts = []
    for s in available:
        labels = [f"{f:.4g}" for f in s.natural_frequency_hz]
        parts.append(f"<h3>auto-MAC, method {_e(s.method)} (modes in Hz)</h3>"
                     + _mac_table(auto_mac(s), labels, labels))
    for i, a in enumerate(available):
        for b in available[i + 1:]:
            parts.append(f"<h3>cross-MAC, {_e(a.method)} (rows) against {_e(b.method)} (columns)</h3>"
                         + _mac_table(cross_mac(a, b), [f"{f:.4g}" for f in a.natural_frequency_hz],
                                      [f"{f:.4g}" for f in b.natural_frequency_hz]))
    parts.append('<p class="note">MAC = |φ_aᴴφ_b|² / (|φ_a|²|φ_b|²): 1 for the same shape, 0 for orthogonal shapes. '
                 'Off-diagonal values near 1 mean two modes the channels cannot tell apart (too few or badly '
                 'placed points, or a spurious mode).</p>')
    return "".join(parts)


def _shapes(content: ReportContent) -> str:
    if not any(s is not None for s in content.shapes):
        return '<p class="note">No result in this archive carries mode shapes.</p>'
    return ('<div class="controls"><label>method <select id="shape-result"></select></label>'
            '<label>mode <select id="shape-mode"></select></label><button id="shape-play">pause</button>'
            '<label>amplitude <input id="shape-amplitude" type="range" min="0" max="40" value="12"></label>'
            '<span class="note">drag to rotate, wheel to zoom</span></div>'
            '<p id="shape-info"></p><div class="shape-row"><div><canvas id="shape-canvas"></canvas></div>'
            '<div><canvas id="shape-argand"></canvas><p class="note">Complexity (Argand diagram): the normalised '
            'entries in the complex plane; a real mode lies on one line.</p></div></div>'
            f'<p class="note">Geometry: {_e(content.geometry_note)}. Grey: at rest; blue: deflected. Nodes without '
            'a channel stand still.</p>')


def _scene(content: ReportContent) -> str:
    parts = []
    for section in content.scene:
        parts.append(f"<h3>{_e(section.title)}</h3>")
        if section.rows:
            parts.append(_table(("quantity", "value"), [(_e(k), _e(v)) for k, v in section.rows], [None, "num"]))
        if section.images:
            parts.append('<div class="scene-images">' + "".join(
                f'<figure><img alt="{_e(cap)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'
                f"<figcaption class=\"note\">{_e(cap)}</figcaption></figure>" for cap, png in section.images)
                + "</div>")
    return "".join(parts)


def build_report(content: ReportContent) -> str:
    """The HTML text of a report (see the module's text for its sections)."""
    from .. import __version__

    payload = {
        "frf": frf_payload(content.frf, content.results) if content.frf is not None else None,
        "stabilisation": [d for d in (stabilisation_payload(content.frf, r) for r in content.results) if d],
        "shapes": [shapes_payload(s, content.geometry) for s in content.shapes if s is not None],
    }
    bodies = {"glance": _glance(content), "modes": _modes(content), "frf": _frf(content, payload),
              "stabilisation": _stabilisation(content, payload), "mac": _mac(content), "shapes": _shapes(content),
              "scene": _scene(content)}
    shown = [(key, title) for key, title in SECTIONS if key != "scene" or content.scene]
    nav = "".join(f'<a href="#{key}">{_e(title)}</a>' for key, title in shown)
    sections = "".join(f'<section id="{key}"><h2>{_e(title)}</h2>{bodies[key]}</section>' for key, title in shown)
    return (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{_e(content.title)}</title><style>{_asset('report.css')}</style></head>"
            f"<body><header><h1>{_e(content.title)}</h1><nav>{nav}</nav></header><main>{sections}</main>"
            f"<footer>modalbal {_e(__version__)}: one self-contained file; figures drawn by the report's own "
            f"script, nothing fetched.</footer>"
            f'<script id="report-data" type="application/json">{to_json(payload)}</script>'
            f"<script>{_asset('report.js')}</script></body></html>")


def write_report(archive: str | os.PathLike, out: str | os.PathLike, geometry=None, content=None) -> Path:
    """Write the HTML report of an archive, crash-safely (temporary file beside ``out``, renamed).

    Parameters
    ----------
    archive : path-like
        An archive of ``python -m modal fit --archive`` or ``python -m balancer run``.
    out : path-like
        The ``.html`` file to write.
    geometry : Geometry or path-like, optional
        Test geometry (a :class:`~modal.geometry.Geometry` or a geometry file); default the archive's own.
    content : ReportContent, optional
        The archive's content as :func:`~modal.report.content.report_content` read it with this geometry, when
        the caller has it already (read once, its warnings given once).

    Returns
    -------
    Path
        ``out``.
    """
    from ..io._atomic import atomic_path

    if geometry is not None and not hasattr(geometry, "node_id"):
        from ..io.geometry import read_geometry

        geometry = read_geometry(geometry)
    text = build_report(content if content is not None else report_content(archive, geometry))
    with atomic_path(out) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return Path(out)
