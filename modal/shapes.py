"""Mode shapes of any result that carries them: normalisation, MAC, MPC, complexity, animation frames.

:func:`mode_shapes` is the one accessor the figures and the report read. It takes every mode's
shape from the result, whatever the method:

* FRF-based results (``nls``, ``circle``, ``halfpower``, ``global``): the receptance modal constants
  of the channels, ``ModeResult.modal_constant``. With one reference (a roving response) the shape
  stands on the response points; with one response and many references (a roving hammer) on the
  reference points, by reciprocity; with several references on the first reference's channels.
* results without modal constants (output-only analysis): ``ModeResult.mode_shape`` over the
  channels, standing on the response points.

Shapes are complex. :func:`normalise` scales each to its largest entry (that entry becomes 1) or
to unit modal mass from a driving point. MAC (Allemang) compares two sets of shapes, MPC (Pappa)
and the mean phase deviation (MPD) say how far a shape is from a real (normal) mode.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .geometry import Geometry

__all__ = ["ModeShapes", "mode_shapes", "normalise", "mac", "auto_mac", "cross_mac", "mpc",
           "mean_phase_deviation_deg", "node_displacements", "animation_frames"]


@dataclass(frozen=True, eq=False)
class ModeShapes:
    """The complex shapes of a result's modes over the entries (channels) that carry them.

    Attributes
    ----------
    natural_frequency_hz, damping_ratio : ndarray, shape (n_modes,)
        Hz and dimensionless.
    shapes : ndarray of complex, shape (n_modes, n_entries)
        As the result gives them (receptance modal constants, 1/kg, or output-only shapes in the
        response's unit); NaN entries read as 0.
    channels : ndarray of int, shape (n_entries,)
        The FRF channel of each entry (0-based).
    points : tuple of str or None
        The point id each entry stands on (``"3+Z"``), None when the data carry no ids.
    method : str
        The identification method.
    flags : tuple of tuple of str
        Each mode's quality flags.
    """

    natural_frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    channels: np.ndarray
    points: tuple[str, ...] | None
    method: str
    flags: tuple[tuple[str, ...], ...] = ()

    @property
    def n_modes(self) -> int:
        return int(self.shapes.shape[0])

    @property
    def n_entries(self) -> int:
        return int(self.shapes.shape[1])

    def placed_on(self, geometry: Geometry | None) -> Geometry:
        """The geometry with one placed channel per entry (channels on a line without a geometry)."""
        from .geometry import line_geometry

        if geometry is None:
            return line_geometry(self.n_entries)
        return geometry.placed_for(self.n_entries, self.points)


def _entries(n_channels: int, responses, references) -> tuple[np.ndarray, tuple[str, ...] | None]:
    """Channels that carry the shape and the point each stands on (see the module's text)."""
    channels = np.arange(n_channels)
    if references is None or len(set(references)) == 1:
        return channels, None if responses is None else tuple(responses)
    if responses is not None and len(set(responses)) == 1:
        return channels, tuple(references)  # roving hammer: the shape stands on the references
    chosen = np.flatnonzero(np.array(references) == references[0])
    return chosen, None if responses is None else tuple(responses[c] for c in chosen)


def mode_shapes(result, response_points: Sequence[str] | None = None,
                reference_points: Sequence[str] | None = None) -> ModeShapes:
    """Every mode's complex shape from any identification result that carries shapes.

    Parameters
    ----------
    result : IdentificationResult (or any result with ``modes``, ``method`` and ``n_channels``)
        Each mode has ``modal_constant`` (FRF-based methods) or ``mode_shape`` (output-only).
    response_points, reference_points : sequence of str, optional
        The fitted FRF's point ids (``FRF.response_points``, ``FRF.reference_points``): they say which
        channels form the shape and where each stands.

    Returns
    -------
    ModeShapes

    Raises
    ------
    ParameterError
        The result has no modes, or a mode has neither modal constants nor a shape over the channels.
    """
    modes = tuple(result.modes)
    if not modes:
        raise ParameterError(f"result of method {result.method!r} has no modes; no shapes to show")
    n_ch = int(result.n_channels)
    rows = []
    for number, mode in enumerate(modes, start=1):
        const = getattr(mode, "modal_constant", None)
        values = None if const is None else np.atleast_1d(np.asarray(const, complex))
        if values is None or values.size != n_ch or not np.any(np.isfinite(values) & (values != 0)):
            shape = getattr(mode, "mode_shape", None)
            values = None if shape is None else np.atleast_1d(np.asarray(shape, complex)).reshape(-1)
        if values is None or values.size != n_ch:
            raise ParameterError(f"mode {number} ({mode.natural_frequency_hz:.6g} Hz, method {result.method!r}) has "
                                 f"no shape over the {n_ch} channel(s)")
        rows.append(np.where(np.isfinite(values), values, 0))
    channels, points = _entries(n_ch, response_points, reference_points)
    return ModeShapes(
        natural_frequency_hz=np.array([m.natural_frequency_hz for m in modes], float),
        damping_ratio=np.array([m.damping_ratio for m in modes], float),
        shapes=np.array(rows)[:, channels], channels=channels, points=points, method=str(result.method),
        flags=tuple(tuple(m.flags) for m in modes))


def normalise(shapes: np.ndarray, how: str = "max", driving_entry: int | None = None) -> np.ndarray:
    """Scaled copies of complex shapes (one per row).

    Parameters
    ----------
    shapes : array_like of complex, shape (n_modes, n_entries) or (n_entries,)
    how : {"max", "unit_modal_mass"}
        ``"max"``: each shape divided by its largest-magnitude entry (that entry becomes 1, the phase of the
        others is relative to it; a zero shape stays zero). ``"unit_modal_mass"``: receptance modal constants
        A_j = φ_j φ_d turned into mass-normalised shapes φ_j = A_j / √A_d (1/√kg) with the driving point's
        constant A_d (the root with a positive real part).
    driving_entry : int, optional
        Index of the driving point among the entries (for ``"unit_modal_mass"``).
    """
    arr = np.asarray(shapes, complex)
    rows = np.atleast_2d(arr)
    if how == "max":
        top = rows[np.arange(rows.shape[0]), np.argmax(np.abs(rows), axis=1)]
        out = rows / np.where(top == 0, 1, top)[:, None]
    elif how == "unit_modal_mass":
        if driving_entry is None or not 0 <= driving_entry < rows.shape[1]:
            raise ParameterError(f"unit_modal_mass needs the driving point's entry (0..{rows.shape[1] - 1}), "
                                 f"got {driving_entry!r}")
        root = np.sqrt(rows[:, driving_entry])
        root = np.where(root.real < 0, -root, root)
        if np.any(root == 0):
            raise ParameterError("unit_modal_mass: a mode's driving-point modal constant is zero")
        out = rows / root[:, None]
    else:
        raise ParameterError(f"normalise: how must be 'max' or 'unit_modal_mass', got {how!r}")
    return out if arr.ndim == 2 else out[0]


def mac(a, b) -> np.ndarray:
    """Modal assurance criterion of every shape of ``a`` with every shape of ``b``.

    MAC = |aᴴb|² / ((aᴴa)(bᴴb)), between 0 (orthogonal) and 1 (the same shape, any scale and phase).

    Parameters
    ----------
    a, b : array_like of complex, shape (n_a, n_entries) and (n_b, n_entries)

    Returns
    -------
    ndarray, shape (n_a, n_b)
        0 where a shape is zero.
    """
    a = np.atleast_2d(np.asarray(a, complex))
    b = np.atleast_2d(np.asarray(b, complex))
    if a.shape[1] != b.shape[1]:
        raise ParameterError(f"mac: the shapes have {a.shape[1]} and {b.shape[1]} entries; expected the same")
    num = np.abs(a.conj() @ b.T) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, axis=1), np.sum(np.abs(b) ** 2, axis=1))
    return num / np.where(den > 0, den, np.inf)


def auto_mac(shapes: ModeShapes) -> np.ndarray:
    """MAC of a result's modes with each other, shape (n_modes, n_modes)."""
    return mac(shapes.shapes, shapes.shapes)


def cross_mac(first: ModeShapes, second: ModeShapes) -> np.ndarray:
    """MAC between the modes of two results (two tests, or two methods on one test).

    Entries are matched by point id where both carry ids (only the points both have count), else by
    position (then both must have the same number of entries).

    Returns
    -------
    ndarray, shape (first.n_modes, second.n_modes)
    """
    if first.points is not None and second.points is not None:
        common = [p for p in first.points if p in set(second.points)]
        if not common:
            raise ParameterError("cross_mac: the two results share no point id; nothing to compare")
        ia = [first.points.index(p) for p in common]
        ib = [second.points.index(p) for p in common]
        return mac(first.shapes[:, ia], second.shapes[:, ib])
    if first.n_entries != second.n_entries:
        raise ParameterError(f"cross_mac: {first.n_entries} and {second.n_entries} entries without point ids to "
                             f"match them; expected the same channels")
    return mac(first.shapes, second.shapes)


def mpc(shapes) -> np.ndarray:
    """Modal phase collinearity (Pappa et al. 1993) of each shape: 1 for a real (normal) mode, 0 for a
    circular one; NaN for a zero shape.

    Parameters
    ----------
    shapes : array_like of complex, shape (n_modes, n_entries) or (n_entries,)

    Returns
    -------
    ndarray of shape (n_modes,), or float for one shape
    """
    rows = np.atleast_2d(np.asarray(shapes, complex))
    re, im = rows.real, rows.imag
    sxx, syy, sxy = np.sum(re * re, 1), np.sum(im * im, 1), np.sum(re * im, 1)
    total = sxx + syy
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(total > 0, ((sxx - syy) ** 2 + 4 * sxy**2) / np.where(total > 0, total, 1) ** 2, np.nan)
    return out if np.ndim(shapes) == 2 else float(out[0])


def mean_phase_deviation_deg(shapes) -> np.ndarray:
    """Mean phase deviation (MPD) of each shape, degrees: the magnitude-weighted mean angle between its
    entries and their best straight line through the origin in the complex plane (0 for a real mode).

    Parameters
    ----------
    shapes : array_like of complex, shape (n_modes, n_entries) or (n_entries,)

    Returns
    -------
    ndarray of shape (n_modes,), or float for one shape
    """
    rows = np.atleast_2d(np.asarray(shapes, complex))
    out = np.full(rows.shape[0], np.nan)
    for k, row in enumerate(rows):
        weight = np.abs(row)
        if not np.any(weight > 0):
            continue
        # principal direction of the points (Re, Im): the right singular vector of the largest value
        _, _, vt = np.linalg.svd(np.column_stack([row.real, row.imag]), full_matrices=False)
        line = complex(vt[0, 0], vt[0, 1])
        cos = np.abs((row * np.conj(line)).real) / np.where(weight > 0, weight, 1)
        angle = np.degrees(np.arccos(np.clip(cos, 0, 1)))
        out[k] = float(np.sum(weight * angle) / np.sum(weight))
    return out if np.ndim(shapes) == 2 else float(out[0])


def node_displacements(geometry: Geometry, shape) -> np.ndarray:
    """Complex displacement of every node, shape (n_nodes, 3): each placed channel's entry along its
    direction, summed per node; nodes without a channel stand still (zero).

    Parameters
    ----------
    geometry : Geometry
        With one placed channel per entry of ``shape`` (:meth:`ModeShapes.placed_on`).
    shape : array_like of complex, shape (n_entries,)
    """
    shape = np.asarray(shape, complex).reshape(-1)
    if geometry.n_channels != shape.size:
        raise ParameterError(f"{geometry.source}: {geometry.n_channels} placed channel(s) for a shape of "
                             f"{shape.size} entries")
    out = np.zeros((geometry.n_nodes, 3), complex)
    rows = geometry.node_index(geometry.channel_node)
    np.add.at(out, rows, shape[:, None] * geometry.channel_direction)
    return out


def animation_frames(geometry: Geometry, shape, n_frames: int = 24, amplitude: float = 0.1) -> np.ndarray:
    """Node positions over one cycle of a mode: x + Re(u e^{iθ}) for θ = 2π k / n_frames.

    Parameters
    ----------
    geometry : Geometry
        Placed for the shape's entries.
    shape : array_like of complex, shape (n_entries,)
    n_frames : int
        Frames per cycle.
    amplitude : float
        Largest displacement as a fraction of the geometry's extent (:meth:`Geometry.extent_m`).

    Returns
    -------
    ndarray, shape (n_frames, n_nodes, 3)
        Positions, m.
    """
    disp = node_displacements(geometry, shape)
    peak = float(np.max(np.linalg.norm(np.abs(disp), axis=1))) if disp.size else 0.0
    scale = amplitude * geometry.extent_m() / peak if peak > 0 else 0.0
    theta = 2 * np.pi * np.arange(int(n_frames)) / int(n_frames)
    moving = (disp[None, :, :] * np.exp(1j * theta)[:, None, None]).real * scale
    return geometry.coordinates_m[None, :, :] + moving
