"""What a report shows, read from an archive: the test at a glance, the modes with their flags, the FRF,
the results, the geometry and (for a scene archive) the scene's sections.

:func:`report_content` accepts the archives of ``python -m modal fit --archive`` (items ``frf`` and
``identify_<method>``, optionally ``geometry`` and ``source_files``) and of ``python -m balancer run``
(a scene: the ``frf`` and ``identify`` stages and the balancing stages). A result is any item with
``modes``, ``method`` and ``n_channels`` (identification results of every method, output-only ones
included). Anything else, a batch archive among them, is refused with one line saying why.
"""
from __future__ import annotations

import importlib
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ArchiveError, ModalError
from ..estimate.core import EstimatedFRF
from ..flags import FLAG_ACTION, FLAG_TEXT
from ..frf import FRF
from ..geometry import Geometry
from ..shapes import ModeShapes, mean_phase_deviation_deg, mode_shapes, mpc

__all__ = ["Section", "ReportContent", "report_content", "mode_rows", "SCENE_SECTIONS"]

#: the module (``module:function``) that turns a scene archive's balancing stages into report sections; looked
#: up by name, as the archive rebuilds balancer's classes, so that modal never imports balancer
SCENE_SECTIONS = "balancer.scene.report:report_sections"


@dataclass(frozen=True)
class Section:
    """A section of the report that the toolkit does not draw itself (the balancing stages of a scene).

    Attributes
    ----------
    title : str
    rows : tuple of (str, str)
        Name and value (with its unit) of each headline number.
    images : tuple of (str, bytes)
        Caption and PNG bytes of each figure.
    """

    title: str
    rows: tuple[tuple[str, str], ...] = ()
    images: tuple[tuple[str, bytes], ...] = ()


@dataclass(frozen=True)
class ReportContent:
    """Everything the HTML report shows (see :func:`report_content`)."""

    title: str
    glance: tuple[tuple[str, str], ...]
    frf: FRF | None
    results: tuple[Any, ...]
    shapes: tuple[ModeShapes, ...]
    geometry: Geometry | None
    geometry_note: str
    scene: tuple[Section, ...] = field(default_factory=tuple)


def _is_result(obj) -> bool:
    return all(hasattr(obj, name) for name in ("modes", "method", "n_channels"))


def _fmt(value, unit: str = "", digits: int = 5) -> str:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not np.isfinite(number):
        return "n/a"
    return f"{number:.{digits}g}" + (f" {unit}" if unit else "")


def _noise_text(frf: FRF | None, result) -> str:
    noise = np.asarray(getattr(result, "noise_std", np.zeros(0)), float).reshape(-1)
    noise = noise[np.isfinite(noise)]
    if noise.size == 0 or frf is None:
        return "not estimated"
    peak = float(np.max(np.abs(frf.channels)))
    median = float(np.median(noise))
    rel = f" ({20 * np.log10(median / peak):.0f} dB below the largest |H|)" if median > 0 and peak > 0 else ""
    return f"{median:.3g} {frf.units} (median over channels){rel}"


def _glance(path: str, archive, frf: FRF | None, results, geometry_note: str) -> tuple[tuple[str, str], ...]:
    rows: list[tuple[str, str]] = [("archive", os.fspath(path))]
    files = archive.items.get("source_files")
    if files:
        rows.append(("file(s)", ", ".join(str(f) for f in np.atleast_1d(files))))
    if archive.scene_text is not None:
        rows.append(("scene", "balancer run archive (scene text stored with the results)"))
    rows.append(("written", f"{archive.attrs.get('created', '?')} by modalbal {archive.attrs.get('software_version', '?')}"))
    if frf is not None:
        rows.append(("kind", f"{frf.kind} [{frf.units}]"))
        points = ""
        if frf.response_points is not None:
            refs = frf.reference_points or ("?",) * frf.n_channels
            shown = [f"{r}/{q}" for r, q in zip(frf.response_points, refs)]
            points = ": " + ", ".join(shown[:12]) + (f", … ({len(shown) - 12} more)" if len(shown) > 12 else "")
        rows.append(("channels", f"{frf.n_channels} (response/reference point{points})" if points
                     else f"{frf.n_channels} (no point ids)"))
        rows.append(("lines", f"{frf.n_freq}, {frf.frequency_hz[0]:g}–{frf.frequency_hz[-1]:g} Hz"))
        if isinstance(frf, EstimatedFRF):
            rows.append(("estimate", f"{frf.estimator} from time data, {frf.averages} average(s), window {frf.window}"))
    for result in results:
        settings = getattr(result, "settings", {}) or {}
        text = ", ".join(f"{k}={v}" for k, v in settings.items() if v not in (None, [], {}))
        rows.append((f"method {result.method}", f"{len(result.modes)} mode(s)" + (f"; {text}" if text else "")))
        rows.append((f"noise ({result.method})", _noise_text(frf, result)))
    rows.append(("geometry", geometry_note))
    # the warnings the results were given (each once, with the items that got it): what their numbers stand on
    said: dict[str, list[str]] = {}
    for name, texts in archive.warnings.items():
        for text in texts:
            said.setdefault(text, []).append(name)
    rows += [(f"warning ({', '.join(names)})", text) for text, names in said.items()]
    return tuple(rows)


def _driving(mode, name: str):
    """The value and standard error of k, c or m at the first channel where it is defined."""
    values = np.atleast_1d(np.asarray(getattr(mode, name, np.nan), float))
    std = np.atleast_1d(np.asarray(getattr(mode.std, name, np.nan), float)) if hasattr(mode, "std") else values * np.nan
    finite = np.flatnonzero(np.isfinite(values))
    if finite.size == 0:
        return np.nan, np.nan, None
    k = int(finite[0])
    return float(values[k]), float(std[k] if k < std.size else np.nan), k


def _pm(value: float, std: float, digits: int = 5) -> str:
    if not np.isfinite(value):
        return "—"
    return f"{value:.{digits}g}" + (f" ± {std:.2g}" if np.isfinite(std) else "")


def mode_rows(result, shapes: ModeShapes | None) -> list[dict]:
    """One row of text per mode: frequency, damping and their standard errors, MPC, MPD, k, c, m where
    defined (the first driving-point channel) and the flags.

    MPC is the result's own where it has one, else computed from the shape's entries.
    """
    own = np.array([float(getattr(m, "mpc", np.nan)) for m in result.modes])
    computed = mpc(shapes.shapes) if shapes is not None else np.full(len(own), np.nan)
    mpd = mean_phase_deviation_deg(shapes.shapes) if shapes is not None else np.full(len(own), np.nan)
    rows = []
    for number, mode in enumerate(result.modes, start=1):
        std = getattr(mode, "std", None)
        k, sk, ch = _driving(mode, "stiffness_n_per_m")
        c, sc, _ = _driving(mode, "damping_n_s_per_m")
        m, sm, _ = _driving(mode, "mass_kg")
        value = own[number - 1] if np.isfinite(own[number - 1]) else computed[number - 1]
        rows.append({
            "number": number, "method": result.method,
            "frequency": _pm(mode.natural_frequency_hz, getattr(std, "natural_frequency_hz", np.nan), 6),
            "damping": _pm(100 * mode.damping_ratio, 100 * getattr(std, "damping_ratio", np.nan), 4),
            "mpc": _fmt(value, digits=3), "mpd": _fmt(mpd[number - 1], "°", 3),
            "k": _pm(k, sk), "c": _pm(c, sc, 4), "m": _pm(m, sm),
            "kcm_channel": "—" if ch is None else str(ch + 1),  # counted from 1, as the command line counts
            "flags": tuple(getattr(mode, "flags", ())),
        })
    return rows


def flag_legend(results) -> list[tuple[str, str, str]]:
    """(flag, meaning, what to do) for every flag raised in ``results``, in order of first appearance."""
    seen: dict[str, None] = {}
    for result in results:
        for mode in result.modes:
            for flag in getattr(mode, "flags", ()):
                seen.setdefault(flag, None)
    return [(f, FLAG_TEXT.get(f, "(no description)"), FLAG_ACTION.get(f, "")) for f in seen]


def _scene_sections(archive) -> tuple[Section, ...]:
    module_name, _, function = SCENE_SECTIONS.partition(":")
    try:
        make = getattr(importlib.import_module(module_name), function)
    except ImportError:
        raise ArchiveError("a scene archive's report needs the balancer package, which is not installed") from None
    return tuple(make(archive))


def report_content(path: str | os.PathLike, geometry: Geometry | None = None) -> ReportContent:
    """Read an archive and gather what its report shows.

    Parameters
    ----------
    path : path-like
        An archive of ``python -m modal fit --archive`` or ``python -m balancer run``.
    geometry : Geometry, optional
        Test geometry; default the archive's own (item ``geometry``), else the channels on a line.

    Raises
    ------
    ModalError
        The file is not an archive, is a batch archive, or holds neither an FRF, a result nor a scene.
    """
    from ..archive import read_archive

    src = os.fspath(path)
    archive = read_archive(path)
    if "batch" in archive.items:
        raise ArchiveError(f"{src}: is a batch archive (many files); expected the archive of one fit: report one "
                           f"file with python -m modal fit FILE --archive OUT.h5")
    frf = next((v for v in archive.items.values() if isinstance(v, FRF)), None)
    results = tuple(v for v in archive.items.values() if _is_result(v))
    if frf is None and not results and archive.scene_text is None:
        have = ", ".join(archive.items) or "nothing"
        raise ArchiveError(f"{src}: holds no FRF, identification result or scene (it holds {have}); expected an "
                           f"archive of python -m modal fit --archive or python -m balancer run")
    if frf is not None:
        results = tuple(r for r in results if int(r.n_channels) == frf.n_channels)
    if geometry is None and isinstance(archive.items.get("geometry"), Geometry):
        geometry, note = archive.items["geometry"], f"from the archive ({archive.items['geometry'].source})"
    elif geometry is not None:
        note = f"{geometry.source}"
    else:
        note = "none: the channels stand on a line in file order"
    responses = frf.response_points if frf is not None else None
    references = frf.reference_points if frf is not None else None
    shapes = []
    for result in results:
        try:
            shapes.append(mode_shapes(result, responses, references))
        except ModalError:
            shapes.append(None)  # a result without shapes: its table is still shown
    if geometry is not None:
        for s in shapes:
            if s is not None:
                s.placed_on(geometry)  # a geometry that cannot place the shape's entries fails here, in one line
    scene = _scene_sections(archive) if archive.scene_text is not None else ()
    title = f"Modal report: {os.path.basename(src)}"
    return ReportContent(title=title, glance=_glance(src, archive, frf, results, note), frf=frf, results=results,
                         shapes=tuple(shapes), geometry=geometry, geometry_note=note, scene=scene)
