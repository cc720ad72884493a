"""A time-data file → its FRFs, with the time options of ``modal fit``, ``modal frf`` and ``modal batch``.

The fit service (:mod:`modal.fitting`) and the command line (:mod:`modal.cli`,
whose options :mod:`modal.cli_time` declares) both call :func:`frf_from_time`, so a
time file gives the same FRFs either way; a scene's ``[frf]`` table takes the same options
under the same names and calls :func:`plan_time_frf` (when the scene is checked) and
:func:`estimate_time_frf` (when its stage runs), or :func:`estimate_roving` for a roving hammer's files.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from typing import Callable

from .errors import FormatError, ParameterError
from .estimate import estimate_frf
from .frf import DEFAULT_UNITS, FRF_KINDS

__all__ = ["TIME_OPTIONS", "wants_time", "frf_from_time", "TimePlan", "plan_time_frf", "estimate_time_frf",
           "estimate_roving", "point_ids"]

#: the attribute names the time options set (None when not given)
TIME_OPTIONS = ("excitation", "response", "impact", "estimator", "window", "exponential_decay_s", "segment_length",
                "overlap")
#: the numbering of repeated channel names in a time record (``1+Z#4``)
_NUMBERED = re.compile(r"#\d+$")
_KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


def wants_time(args, path) -> bool:
    """Whether ``path`` is to be read as time data (a time option given, or the file holds time data)."""
    from .io.timedata import is_time_file

    given = any(getattr(args, name, None) not in (None, False) for name in TIME_OPTIONS if name != "overlap")
    return given or is_time_file(path)


def frf_from_time(path, args, report: Callable[[str], None] | None = None):
    """Read a time file and estimate its FRFs with the command line's options.

    Parameters
    ----------
    path : path-like or sequence of path-likes
        One file, or several takes of one test (the same channels at one rate, such as one file
        per hammer hit): estimated as one, no segment or hit record straddling two files; or the
        files of a roving-hammer test (the force channel's name changes, the responses stay):
        each hit point estimated from its own file(s), joined (:mod:`modal.roving`).
    args : object
        The time options as attributes (:data:`TIME_OPTIONS`, and ``kind``): an ``argparse``
        namespace or :meth:`modal.fitting.FitOptions.namespace`.
    report : callable, optional
        Called with a one-line note (the excitation channel taken when none was named).

    Returns
    -------
    (EstimatedFRF, TimeRecord, list of int, list of int)
        The estimate, the record, and the excitation and response channel indices (of the first file);
        for a roving-hammer test a :class:`~modal.roving.RovingEstimate` and no record (None).
    """
    from .io._common import refuse_copies
    from .io.timedata import read_time
    from .io.timejoin import join_takes

    paths = [path] if isinstance(path, (str, os.PathLike)) else list(path)
    refuse_copies(paths, "takes", "a take given twice is averaged with itself: its noise looks smaller than it is")
    records = [read_time(p) for p in paths]
    if len(records) > 1 and len({r.names for r in records}) > 1:  # a roving hammer, or files that are not one test
        from .roving import roving_points

        plans = [plan_time_frf(r, args) for r in records]
        points = roving_points(records, plans)
        if points is not None:
            estimate = estimate_roving(records, plans, points, args, report)
            return estimate, None, list(plans[0].inputs), list(plans[0].outputs)
    record = join_takes(records)
    plan = plan_time_frf(record, args, report)
    return estimate_time_frf(record, plan, args), record, list(plan.inputs), list(plan.outputs)


@dataclass(frozen=True)
class TimePlan:
    """Which channels of a time record give which FRF: what can be checked before any estimation.

    Attributes
    ----------
    inputs, outputs : tuple of int
        0-based indices of the excitation and response channels.
    kind : str
        The FRF kind to estimate.
    quantity : str or None
        What the responses measured (None when the file does not say).
    """

    inputs: tuple[int, ...]
    outputs: tuple[int, ...]
    kind: str
    quantity: str | None


def _command_line_option(name: str) -> str:
    return "--" + name.replace("_", "-")


def plan_time_frf(record, args, report: Callable[[str], None] | None = None,
                  option: Callable[[str], str] = _command_line_option) -> TimePlan:
    """The excitation and response channels and the FRF kind, from the options and the record.

    Parameters
    ----------
    record : TimeRecord
    args : object
        The time options as attributes (:data:`TIME_OPTIONS`, and ``kind``).
    report : callable, optional
        Called with a one-line note (the excitation channel taken when none was named).
    option : callable
        An option's name as the user writes it, in messages (default: the command line's
        ``--exponential-decay-s``; a scene names its key).

    Raises
    ------
    FormatError
        A channel that does not exist (the message lists the valid ones), no or several
        force channels and none named, a channel in the wrong role, or a kind the file does
        not tell and the options do not give.
    """
    src = record.source
    if not getattr(args, "impact", False):  # checked before any estimate: a scene refuses it in its check
        window, decay = getattr(args, "window", None), getattr(args, "exponential_decay_s", None)
        if window in ("force", "exponential") or decay is not None:
            given = f"{option('window')} {window!r}" if window in ("force", "exponential") else \
                option("exponential_decay_s")
            raise ParameterError(f"{src}: {given} is for impact records (one record per hit); expected "
                                 f"{option('impact')} as well, or a continuous record's window ('rect' or 'hann')")
    if args.excitation is not None:
        inputs = [record.channel_index(args.excitation)]
    else:
        inputs = record.force_channels()
        if len(inputs) != 1:
            listing = ", ".join(f"{k + 1}={n} ({q or 'unknown'})"
                                for k, (n, q) in enumerate(zip(record.names, record.quantities)))
            what = "no channel" if not inputs else f"{len(inputs)} channels"
            responses_only = not inputs and all(q not in (None, "force") for q in record.quantities)
            if responses_only:  # the advice before the listing, which may be long (a batch keeps 500 characters)
                raise FormatError(f"{src}: no channel marked as force: the record holds responses only; for "
                                  f"operational (output-only) modal analysis use python -m modal oma {src} (a folder "
                                  f"of such records: modal batch --oma), or name the force channel with "
                                  f"{option('excitation')} (an FRF needs an excitation); channels {listing}")
            raise FormatError(f"{src}: {what} marked as force ({listing}); expected one: name the force channel "
                              f"with {option('excitation')} (an FRF needs an excitation)")
    if args.response:
        outputs = [record.channel_index(r) for r in args.response]
    else:
        outputs = [k for k in range(record.n_channels) if k not in inputs]
    if not outputs:
        listing = ", ".join(record.describe(k) for k in range(record.n_channels))
        raise FormatError(f"{src}: holds {record.n_channels} channel(s) ({listing}) and no response besides the "
                          "excitation; expected at least one response channel (is the file cut short?)")
    quantity = record.check_roles(inputs, outputs)
    if args.excitation is None and report is not None:
        report(f"{src}: excitation channel {inputs[0] + 1} ({record.names[inputs[0]]})")
    kind = getattr(args, "kind", None) or _KIND_OF_QUANTITY.get(quantity or "")
    if kind is None:
        listing = ", ".join(record.describe(k) for k in outputs)
        raise FormatError(f"{src}: the file does not say what the responses measured ({listing}); give "
                          f"{option('kind')} ({', '.join(FRF_KINDS)})")
    return TimePlan(tuple(inputs), tuple(outputs), kind, quantity)


def estimate_time_frf(record, plan: TimePlan, args):
    """The FRFs of ``record`` as ``plan`` says, with the estimation options of ``args`` (an EstimatedFRF)."""
    inputs, outputs = list(plan.inputs), list(plan.outputs)
    window = args.window or ("force" if args.impact else "hann")
    points = point_ids([record.names[k] for k in inputs + outputs])
    estimate = estimate_frf(
        record.signals[inputs], record.signals[outputs], record.sample_rate_hz,
        estimator=args.estimator or "H1", kind=plan.kind, segment_length=args.segment_length,
        overlap=0.5 if args.overlap is None else args.overlap, window=window,
        exponential_decay_s=args.exponential_decay_s, impact=args.impact,
        response_quantity=plan.quantity, excitation_points=[record.names[k] for k in inputs],
        response_points=[record.names[k] for k in outputs], source=record.source,
        take_lengths=record.take_lengths, take_names=record.take_sources,
        full_scale=None if record.full_scale is None else [record.full_scale[k] for k in inputs + outputs])
    if points is None:  # names, not point ids: they do not say where the force and the responses stood
        estimate = replace(estimate, reference_points=None)
    else:
        forces, responses = points[:len(inputs)], points[len(inputs):]  # channels as estimate_frf orders them
        estimate = replace(estimate, reference_points=[f for _ in responses for f in forces],
                           response_points=[r for r in responses for _ in forces])
    units = _ratio_units(record, plan)
    return estimate if units is None else replace(estimate, units=units)


def point_ids(names) -> list[str] | None:
    """The channels' names as point ids (``"101+Z"``), or None when one is not a point id with a direction.

    A time file's channel names are point ids only when they say a node and a direction (UFF 58 records
    do; a CSV column or a MAT/HDF5 ``names`` entry may): only then does an excitation and a response
    of the same id make a driving point. The numbering ``#k`` that tells repeated ids apart in a record
    (:func:`modal.io.timedata.read_time`) is dropped, so that a force and a response at one point match.
    """
    from .io.uff import format_point, parse_point

    ids = []
    for name in names:
        try:
            node, direction = parse_point(_NUMBERED.sub("", str(name)))
        except ValueError:
            return None
        if direction == 0:
            return None
        ids.append(format_point(node, direction))
    return ids


def _ratio_units(record, plan: TimePlan) -> str | None:
    """The FRF's unit where the channels do not give the kind's own (``m/s^2/N``): what the responses were
    recorded in over what the excitation was (a channel of unknown quantity is taken as it was stored); None
    when a force in N and a response of known quantity give the kind's unit."""
    force = all(record.quantities[k] == "force" for k in plan.inputs)
    if force and plan.quantity is not None:
        return None
    top = DEFAULT_UNITS[plan.kind][:-2] if plan.quantity is not None else (
        record.units[plan.outputs[0]] or "unit not given")
    bottom = "N" if force else (record.units[plan.inputs[0]] or "unit not given")
    return f"{top}/{bottom}" if "/" not in bottom and " " not in bottom else f"{top}/({bottom})"


def estimate_roving(records, plans, points, args, report: Callable[[str], None] | None = None):
    """Each hit point's FRFs from its own file(s), joined (:func:`modal.roving.join_estimates`).

    Parameters
    ----------
    records, plans
        Each file's record and channels (:func:`modal.roving.roving_points`).
    points : list of (str, list of int)
        What :func:`modal.roving.roving_points` returned.
    args : object
        The time options (:data:`modal.time_frf.TIME_OPTIONS` and ``kind``), for every point alike; without a
        ``segment_length``, points whose hits give records of other lengths are estimated again with the
        shortest (one frequency axis).
    report : callable, optional
        Called with a one-line note (files averaged as takes of one point, a length imposed).

    Returns
    -------
    modal.roving.RovingEstimate
    """
    from types import SimpleNamespace

    from .io.timejoin import join_takes
    from .roving import join_estimates

    groups = []
    for point, members in points:
        sources = tuple(records[k].source for k in members)
        if len(members) > 1 and report is not None:
            report(f"{', '.join(sources)}: all hit at {point}: averaged as takes of that point")
        groups.append((join_takes([records[k] for k in members]), plans[members[0]], sources))
    estimates = [estimate_time_frf(record, plan, args) for record, plan, _ in groups]
    notes = []
    lengths = [e.segment_length for e in estimates]
    if args.segment_length is None and len(set(lengths)) > 1:
        shortest = min(lengths)
        alike = SimpleNamespace(**{**vars(args), "segment_length": shortest})
        estimates = [e if e.segment_length == shortest else estimate_time_frf(record, plan, alike)
                     for e, (record, plan, _) in zip(estimates, groups)]
        notes.append(f"every point's hit records cut to {shortest} samples (the shortest default of the points, "
                     "for one frequency axis)")
        if report is not None:
            report(f"roving hammer: hit records of {shortest} samples at every point (the points' defaults differ: "
                   f"{', '.join(str(n) for n in lengths)}); give --segment-length to choose")
    return join_estimates(estimates, [(point, sources) for (point, _), (_, _, sources) in zip(points, groups)],
                          notes)
