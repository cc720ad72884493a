"""Several setups merged into one set of shapes: roving sensors with shared references.

Each setup is identified on its own (:func:`modal.oma`); a mode of the first setup is found in each
further setup as the mode nearest in frequency (within :data:`FREQ_TOL` or three combined standard
errors) whose shape at the reference channels has a MAC of at least :data:`REF_MAC` with the first
setup's. Each further setup's shape is rescaled by the least-squares factor that maps its reference
entries onto the first setup's, ``a = φ_refᴴ φ₁,ref / φ_refᴴ φ_ref`` (post-identification rescaling,
PoSER-style), and its other channels appended. Frequencies and damping ratios are the
inverse-variance weighted means over the setups that hold the mode.
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import ParameterError, QualityWarning
from ..results import IdentificationResult
from .result import merged_result
from .selection import shape_mac

__all__ = ["merge_setups", "FREQ_TOL", "REF_MAC"]

#: a mode of another setup lies within this relative frequency difference (or 3 combined standard errors)
FREQ_TOL = 0.01
#: ... and its reference entries have at least this MAC with the first setup's
REF_MAC = 0.8


def _references(reference_channels, results) -> list[np.ndarray]:
    try:
        refs = [np.asarray(r, int) for r in reference_channels]
        if all(r.ndim == 0 for r in refs):
            refs = [np.asarray(reference_channels, int)] * len(results)
    except (TypeError, ValueError):
        raise ParameterError(f"'reference_channels' is {reference_channels!r}; expected 0-based channel indices "
                             "(one list for every setup, or one list per setup)") from None
    if len(refs) != len(results):
        raise ParameterError(f"'reference_channels' gives {len(refs)} lists for {len(results)} setups; expected one "
                             "per setup (or one list for all)")
    sizes = {r.size for r in refs}
    for k, (r, res) in enumerate(zip(refs, results)):
        if r.ndim != 1 or r.size == 0 or np.any(r < 0) or np.any(r >= res.n_channels) or np.unique(r).size != r.size:
            raise ParameterError(f"'reference_channels' of setup {k + 1} is {r.tolist()}; expected distinct indices in "
                                 f"[0, {res.n_channels})")
    if len(sizes) != 1:
        raise ParameterError("'reference_channels' lists differ in length; expected the same references, in the same "
                             "order, in every setup")
    return refs


def _near(mode, other) -> bool:
    """Whether ``other`` lies near ``mode`` in frequency (see the module docstring)."""
    gap = abs(other.natural_frequency_hz - mode.natural_frequency_hz)
    return gap <= max(FREQ_TOL * mode.natural_frequency_hz,
                      3 * np.nan_to_num(np.hypot(mode.std.natural_frequency_hz, other.std.natural_frequency_hz)))


def _check_references(results, refs) -> None:
    """Refuse a setup whose reference entries disagree with the first setup's in most of the modes both hold.

    A mode found at the same frequency in both setups whose reference entries have a MAC below
    :data:`REF_MAC` is left out of the merge (``missing_in_setup``), with a warning that it was found (the
    flag alone reads as a mode the setup lacks); when that is so for half the modes or more (two at least),
    the references are not the same channels (another order, another sensor, a dead reference, a reference
    in another unit) and the modes that pass do so by chance: the merged shapes would be wrong.

    Calibration (``python -m benchmarks.calib_merge_references``: anchor-case setup pairs, references right,
    swapped, or the second moved to each other channel): right setups have no disagreeing mode (their
    smallest reference MAC 0.94, the weakly excited mode); a moved reference makes 2 to 5 of 6 disagree, and
    those passing have MACs 0.84-1.0, as right ones may: a mode cannot be told apart, the count can. Exactly
    half (a reference moved to a channel that moves with it in three modes) was merged before, the passing
    modes at MAC 0.86-0.94.
    """
    if refs[0].size < 2:
        return  # one reference: its entries cannot disagree in shape
    for k, (result, ref) in enumerate(zip(results[1:], refs[1:]), start=2):
        matched, disagree = 0, []
        for mode in results[0]:
            near = [other for other in result if _near(mode, other)]
            if not near:
                continue
            matched += 1
            best = max(shape_mac(mode.mode_shape[refs[0]], other.mode_shape[ref]) for other in near)
            if best < REF_MAC:
                disagree.append(f"{mode.natural_frequency_hz:.4g} Hz (MAC {best:.2f})")
        src = result.settings.get("source", "<array>")
        refused = len(disagree) >= 2 and 2 * len(disagree) >= matched
        if disagree and not refused:
            warnings.warn(f"setup {k} ({src}) holds modes at the frequencies of setup 1's {', '.join(disagree)} whose "
                          f"reference entries {_named(result, ref)} disagree with setup 1's {_named(results[0], refs[0])} "
                          f"(MAC below {REF_MAC:g}): left out of the merge and flagged missing_in_setup, though found; "
                          "a reference moved between setups, or near a node of these modes?", QualityWarning,
                          stacklevel=3)
        if refused:
            raise ParameterError(f"setup {k} ({src}): the reference channels {_named(result, ref)} disagree with setup "
                                 f"1's {_named(results[0], refs[0])} in {len(disagree)} of the {matched} modes both hold: "
                                 f"{', '.join(disagree)}; expected the same reference sensors, in the same order and "
                                 f"unit, in every setup (MAC >= {REF_MAC:g}): check their order, a moved or dead "
                                 "reference, or a reference in another unit")


def _named(result, channels) -> str:
    """Channels by name (as the setup's file names them; for an array, the 0-based index)."""
    names = list(result.settings.get("channel_names") or [])
    return "[" + ", ".join(str(names[c]) if c < len(names) else str(c) for c in channels) + "]"


def _find(mode, ref0, result, ref):
    """The mode of ``result`` that is ``mode`` (see the module docstring), or None."""
    best, best_key = None, np.inf
    for other in result:
        gap = abs(other.natural_frequency_hz - mode.natural_frequency_hz)
        if not _near(mode, other):
            continue
        if ref.size > 1 and shape_mac(mode.mode_shape[ref0], other.mode_shape[ref]) < REF_MAC:
            continue
        if gap < best_key:
            best, best_key = other, gap
    return best


def _scale(mode, ref0, other, ref) -> tuple[complex, float]:
    """The factor ``a`` that maps ``other``'s reference entries onto ``mode``'s (least squares), and its standard
    error to first order from both setups' reference entries' errors (NaN where a setup gives none):
    ``σ_a² = Σ_r |φ_r|² (σ₁,r² + |a|² σ_r²) / (Σ_r |φ_r|²)²``. A reference entry within its errors of zero (a
    reference at a node of the mode) leaves ``a`` undetermined: ``|a|`` comparable to ``σ_a``."""
    phi, phi1 = np.asarray(other.mode_shape, complex)[ref], np.asarray(mode.mode_shape, complex)[ref0]
    power = float(np.vdot(phi, phi).real)
    a = np.vdot(phi, phi1) / power
    std1 = np.asarray(mode.std.mode_shape, float)[ref0] if mode.std.mode_shape is not None else np.nan
    std2 = np.asarray(other.std.mode_shape, float)[ref] if other.std.mode_shape is not None else np.nan
    std_a = float(np.sqrt(np.sum(np.abs(phi) ** 2 * (std1**2 + abs(a) ** 2 * std2**2))) / power)
    return complex(a), std_a


def merge_setups(results, reference_channels) -> IdentificationResult:
    """Merge operational results of several setups into shapes over all their channels.

    Parameters
    ----------
    results : sequence of IdentificationResult
        One per setup (:func:`modal.oma`), the first defining the modes.
    reference_channels : sequence of int, or sequence of sequences of int
        Each setup's reference channels (0-based), in the same order for every setup; one list serves
        all setups when their references sit at the same indices.

    Returns
    -------
    IdentificationResult
        The first setup's modes; each shape holds the first setup's channels, then each further setup's
        non-reference channels in order. A mode missing from a setup has NaN there and the flag
        ``missing_in_setup``. The merged entries' standard errors include the scale factor's (:func:`_scale`):
        references near a node of a mode leave that setup's entries of it as uncertain as the factor.

    Notes
    -----
    With one reference per setup a reference moved between setups cannot be seen: its entries cannot
    disagree in shape, frequencies do not move with a sensor, and each mode's setup-2 entries are merged at
    the wrong scale (the ratio of the two points' entries). What the records would show is the reference's
    share of each mode: with the anchor case's stationary excitation its band power per mode changed by
    0.66-1.28× between right setups and by 4-25× in most modes when moved, but by 0.86-1.69× when moved to
    the mirror point (symmetric and antisymmetric modes keep their power), and ambient excitation that
    changes between setups (wind, traffic, the machine's load) changes the shares as much. Use two references
    or more (their entries are checked against each other) where a moved reference is possible.

    Raises
    ------
    ParameterError
        Bad reference lists, or a setup whose reference entries disagree (MAC below :data:`REF_MAC`) with
        the first setup's in half the modes both hold or more (two at least): references in another order,
        moved, dead or in another unit.
    """
    results = list(results)
    if len(results) < 2:
        raise ParameterError(f"merge_setups needs at least 2 setups, got {len(results)}")
    refs = _references(reference_channels, results)
    _check_references(results, refs)
    others = [np.setdiff1d(np.arange(r.n_channels), ref) for r, ref in zip(results, refs)]
    merged = []
    for mode in results[0]:
        shape = [np.asarray(mode.mode_shape, complex)]
        shape_std = [np.asarray(mode.std.mode_shape if mode.std.mode_shape is not None
                                else np.full(mode.mode_shape.size, np.nan), float)]
        f, sf, z, sz = [mode.natural_frequency_hz], [mode.std.natural_frequency_hz], [mode.damping_ratio], \
            [mode.std.damping_ratio]
        flags = set()
        for result, ref, rest in zip(results[1:], refs[1:], others[1:]):
            other = _find(mode, refs[0], result, ref)
            if other is None:
                flags.add("missing_in_setup")
                shape.append(np.full(rest.size, np.nan + 0j))
                shape_std.append(np.full(rest.size, np.nan))
                continue
            a, std_a = _scale(mode, refs[0], other, ref)
            phi = np.asarray(other.mode_shape, complex)
            shape.append(a * phi[rest])
            s = other.std.mode_shape
            s = np.asarray(s, float)[rest] if s is not None else np.full(rest.size, np.nan)
            shape_std.append(np.hypot(abs(a) * s, np.abs(phi[rest]) * std_a))
            f.append(other.natural_frequency_hz), sf.append(other.std.natural_frequency_hz)
            z.append(other.damping_ratio), sz.append(other.std.damping_ratio)
        merged.append((mode, np.concatenate(shape), np.concatenate(shape_std), _mean(f, sf), _mean(z, sz), flags))
    names = []
    for k, (result, rest) in enumerate(zip(results, others)):
        own = list(result.settings.get("channel_names") or range(result.n_channels))
        picked = range(result.n_channels) if k == 0 else rest
        names += [f"setup{k + 1}:{own[i]}" for i in picked]
    settings = {**results[0].settings, "setups": len(results), "reference_channels": [r.tolist() for r in refs],
                "channel_names": names, "n_channels": len(names)}
    harmonics = sorted({round(h, 6) for r in results for h in r.harmonics_hz})
    return merged_result(results[0], merged, settings, harmonics)


def _mean(values, stds):
    """Inverse-variance weighted mean and its standard error (plain mean when an error is missing)."""
    v, s = np.asarray(values, float), np.asarray(stds, float)
    if np.all(np.isfinite(s) & (s > 0)):
        w = 1.0 / s**2
        return float(np.sum(w * v) / np.sum(w)), float(1.0 / np.sqrt(np.sum(w)))
    return float(np.mean(v)), float("nan")
