"""The test geometry: nodes, trace lines, and where each channel stands and points.

A :class:`Geometry` holds the nodes of a test structure (id and x, y, z in metres), the
trace lines drawn between them, and, once placed, each channel's node and direction
(a unit vector). Mode shapes are drawn on it (:mod:`modal.shapes`, :mod:`modal.shape_plots`,
the HTML report).

Channels map onto nodes by their point ids, as the FRF files carry them: ``"3+Z"`` is
node 3 in +Z, ``"12-X"`` node 12 in −X (UFF 58 response/reference node and direction
fields give the same ids). A bare node number (``"3"``) measures along +Z. Rotations
(``"3+RX"``) stand on their node with no translation to draw (direction zero).
Without a geometry, :func:`line_geometry` stands the channels on a line in file order.

Read a geometry with :func:`modal.io.geometry.read_geometry` (UFF 15/2411 and 82, or a
small CSV or TOML file a person can type).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .errors import ParameterError, QualityWarning, warn

__all__ = ["Geometry", "line_geometry", "direction_vector", "DIRECTIONS"]

#: Unit vector of each translation direction of a point id; rotations draw nothing.
DIRECTIONS = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0),
              "RX": (0.0, 0.0, 0.0), "RY": (0.0, 0.0, 0.0), "RZ": (0.0, 0.0, 0.0)}


def direction_vector(point: str) -> tuple[int, np.ndarray]:
    """Node and unit direction vector of a point id: ``"3+Z"`` → ``(3, [0, 0, 1])``.

    A bare node number measures along +Z; a rotation (``RX``, ``RY``, ``RZ``) gives the zero
    vector (nothing to draw as a translation).

    Raises
    ------
    ValueError
        The id is not ``<node>[+|-]<X|Y|Z|RX|RY|RZ>`` or a node number.
    """
    from .io.uff import parse_point  # the one parser of point ids (also used for UFF 58 fields)

    node, code = parse_point(point)
    if code == 0:
        return node, np.array(DIRECTIONS["Z"])
    axis = ("X", "Y", "Z", "RX", "RY", "RZ")[abs(code) - 1]
    return node, np.sign(code) * np.array(DIRECTIONS[axis])


@dataclass(frozen=True, eq=False)
class Geometry:
    """Nodes, trace lines and (once placed) each channel's node and direction.

    Parameters
    ----------
    node_id : array_like of int, shape (n_nodes,)
        Node numbers, distinct.
    coordinates_m : array_like of float, shape (n_nodes, 3)
        x, y, z of each node, m (global Cartesian axes).
    lines : array_like of int, shape (n_lines, 2)
        Trace line segments as pairs of node numbers (each must be a node).
    channel_node : array_like of int, shape (n_channels,), optional
        Node number of each channel (or mode-shape entry).
    channel_direction : array_like of float, shape (n_channels, 3), optional
        Unit vector of each channel's measuring direction (zero for a rotation).
    source : str
        Where the geometry came from (file name), for error messages.
    """

    node_id: np.ndarray
    coordinates_m: np.ndarray
    lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    channel_node: np.ndarray | None = None
    channel_direction: np.ndarray | None = None
    source: str = "<geometry>"

    def archive_units(self) -> dict[str, str]:
        """Units of the fields whose names do not say them (for :mod:`modal.archive`)."""
        return {"node_id": "1", "lines": "1", "channel_node": "1", "channel_direction": "1"}

    def __post_init__(self) -> None:
        src = self.source
        ids = np.asarray(self.node_id)
        if ids.ndim != 1 or ids.size == 0 or ids.dtype.kind not in "iu":
            raise ParameterError(f"{src}: field 'node_id' must be a non-empty 1-D array of integers")
        if np.unique(ids).size != ids.size:
            dup = ids[np.flatnonzero(np.diff(np.sort(ids)) == 0)[0]]
            raise ParameterError(f"{src}: field 'node_id' repeats node {int(dup)}; expected distinct node numbers")
        xyz = np.asarray(self.coordinates_m, dtype=float)
        if xyz.shape != (ids.size, 3) or not np.all(np.isfinite(xyz)):
            raise ParameterError(f"{src}: field 'coordinates_m' must be finite x, y, z for each of the {ids.size} nodes "
                                 f"(shape ({ids.size}, 3)), got shape {xyz.shape}")
        lines = np.asarray(self.lines).reshape(-1, 2) if np.size(self.lines) else np.zeros((0, 2), int)
        if lines.dtype.kind not in "iu":
            raise ParameterError(f"{src}: field 'lines' must be pairs of node numbers (integers)")
        unknown = np.setdiff1d(lines, ids)
        if unknown.size:
            raise ParameterError(f"{src}: trace line names node {int(unknown[0])}, which is not among the nodes")
        object.__setattr__(self, "node_id", ids.astype(np.int64))
        object.__setattr__(self, "coordinates_m", xyz)
        object.__setattr__(self, "lines", lines.astype(np.int64))
        if (self.channel_node is None) != (self.channel_direction is None):
            raise ParameterError(f"{src}: give both 'channel_node' and 'channel_direction', or neither")
        if self.channel_node is not None:
            nodes = np.asarray(self.channel_node).astype(np.int64).reshape(-1)
            directions = np.asarray(self.channel_direction, float).reshape(-1, 3)
            if directions.shape[0] != nodes.size:
                raise ParameterError(f"{src}: 'channel_direction' has {directions.shape[0]} rows, expected one per "
                                     f"channel ({nodes.size})")
            missing = np.setdiff1d(nodes, ids)
            if missing.size:
                raise ParameterError(f"{src}: a channel stands on node {int(missing[0])}, which is not among the nodes")
            object.__setattr__(self, "channel_node", nodes)
            object.__setattr__(self, "channel_direction", directions)

    @property
    def n_nodes(self) -> int:
        return int(self.node_id.size)

    @property
    def n_channels(self) -> int:
        """Number of placed channels (0 before :meth:`with_channels`)."""
        return 0 if self.channel_node is None else int(self.channel_node.size)

    def node_index(self, nodes) -> np.ndarray:
        """Row of each node number in :attr:`node_id` / :attr:`coordinates_m`."""
        nodes = np.asarray(nodes, dtype=np.int64)
        order = np.argsort(self.node_id)
        pos = np.searchsorted(self.node_id[order], nodes)
        pos = np.clip(pos, 0, self.node_id.size - 1)
        found = self.node_id[order][pos] == nodes
        if not np.all(found):
            raise ParameterError(f"{self.source}: node {int(nodes[~found][0])} is not among the nodes")
        return order[pos]

    def with_channels(self, points: Sequence[str]) -> "Geometry":
        """The same geometry with channels placed by their point ids (``"3+Z"``: node 3, +Z).

        Parameters
        ----------
        points : sequence of str
            One point id per channel (or per mode-shape entry).

        Raises
        ------
        ParameterError
            A point id is malformed or names a node the geometry does not have.
        """
        nodes, directions = [], []
        known = set(self.node_id.tolist())
        for k, point in enumerate(points, start=1):  # channels counted from 1, as everywhere users see them
            try:
                node, direction = direction_vector(point)
            except ValueError as exc:
                raise ParameterError(f"{self.source}: channel {k}: {exc}") from None
            if node not in known:
                raise ParameterError(f"{self.source}: channel {k} (point {point!r}) stands on node {node}, which the "
                                     f"geometry does not have (nodes {_id_range(self.node_id)})")
            nodes.append(node)
            directions.append(direction)
        return replace(self, channel_node=np.array(nodes, np.int64),
                       channel_direction=np.array(directions, float).reshape(-1, 3))

    def placed_for(self, n_channels: int, points: Sequence[str] | None) -> "Geometry":
        """This geometry with ``n_channels`` channels placed: by the geometry's own channel map when it has
        one, else by ``points`` (the channels' point ids).

        Raises
        ------
        ParameterError
            The geometry's channel map has another number of channels, or neither a map nor point ids say
            where the channels stand.
        """
        if self.channel_node is not None:
            if self.n_channels != n_channels:
                raise ParameterError(f"{self.source}: the geometry places {self.n_channels} channel(s), the data have "
                                     f"{n_channels}")
            if points is not None:
                self._warn_map_disagrees(points)
            return self
        if points is None:
            raise ParameterError(f"{self.source}: the data carry no point ids and the geometry no channel map; "
                                 f"expected point ids such as '3+Z' in the FRF file or a [channels] table")
        return self.with_channels(points)

    def _warn_map_disagrees(self, points: Sequence[str]) -> None:
        """Warn when the data's point ids would place the channels on this geometry's nodes, but elsewhere than
        its channel map does (a map written for another channel order, or a sensor's sign): the map is used.
        Point ids that do not stand on the geometry's nodes are a deliberate renaming, not warned."""
        try:
            placed = [direction_vector(str(point)) for point in points]
        except ValueError:
            return
        known = set(self.node_id.tolist())
        if len(placed) != self.n_channels or any(node not in known for node, _ in placed):
            return
        for k, ((node, direction), point) in enumerate(zip(placed, points)):
            if node != self.channel_node[k] or not np.allclose(direction, self.channel_direction[k]):
                mapped = _point_text(int(self.channel_node[k]), self.channel_direction[k])
                others = sum(node != self.channel_node[j] or not np.allclose(direction, self.channel_direction[j])
                             for j, (node, direction) in enumerate(placed))
                warn(f"{self.source}: the geometry's channel map places channel {k + 1} at {mapped}, the data's point "
                     f"id says {point!r} ({others} of {len(placed)} channels disagree): the shapes are drawn where the "
                     "map says; if the data's ids are right, remove the map's channel entries", QualityWarning)
                return

    def extent_m(self) -> float:
        """Largest distance between two nodes along any axis, m (1 for a single point)."""
        span = float(np.max(np.ptp(self.coordinates_m, axis=0)))
        return span if span > 0 else 1.0


def _point_text(node: int, direction: np.ndarray) -> str:
    """A placed channel as a point id (``"3-X"``; a rotation, which draws nothing, as its node alone)."""
    for axis, unit in DIRECTIONS.items():
        for sign in (1.0, -1.0):
            if np.any(unit) and np.allclose(direction, sign * np.array(unit)):
                return f"{node}{'+' if sign > 0 else '-'}{axis}"
    return str(node)


def _id_range(ids: np.ndarray) -> str:
    return f"{int(ids.min())}..{int(ids.max())}" if ids.size > 1 else str(int(ids[0]))


def line_geometry(n_channels: int, spacing_m: float = 1.0) -> Geometry:
    """Channels on a straight line in file order: node k + 1 at x = k·spacing, measuring +Z, joined in order.

    Parameters
    ----------
    n_channels : int
        Number of channels (>= 1).
    spacing_m : float
        Distance between neighbouring channels, m.
    """
    if int(n_channels) < 1:
        raise ParameterError(f"line_geometry needs at least one channel, got {n_channels}")
    n = int(n_channels)
    ids = np.arange(1, n + 1)
    xyz = np.zeros((n, 3))
    xyz[:, 0] = np.arange(n) * float(spacing_m)
    lines = np.column_stack([ids[:-1], ids[1:]])
    direction = np.tile([0.0, 0.0, 1.0], (n, 1))
    return Geometry(ids, xyz, lines, ids.copy(), direction, source="channels on a line in file order")
