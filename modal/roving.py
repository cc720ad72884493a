"""Roving-hammer time files: one file per hit point, each point's FRFs estimated, then joined as one FRF set.

A roving-hammer test keeps the accelerometers where they are and moves the hammer: each file holds the
force at its own point (the force channel's name says which, ``1+Z`` in one file, ``2+Z`` in the next)
and the same responses. Each point's FRFs are estimated from its own file (several files hit at one
point are takes of it, averaged as one), on one frequency axis, and joined channel by channel: by
reciprocity the FRFs of one response over the hit points are a row of the FRF matrix, the mode shapes
over the hit points (:mod:`modal.shapes`).

What each estimate knows of its errors is joined where it can be honestly (:func:`join_estimates`):
the noise per line of every channel, the fewest averages, the exponential window (one for all),
the lag window and the lines' correlation where the files' agree; a field that differs between the
files beyond its tolerance is dropped, and the note says which and why (identification then falls
back: no window-bias correction, lines taken as uncorrelated with the fit's own check of their
residual's correlation).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .errors import FormatError
from .estimate import EstimatedFRF
from .noise_model import NoiseModel
from .shared_error import CommonError, JoinedError

__all__ = ["RovingEstimate", "roving_points", "join_estimates", "LAG_WINDOW_TOLERANCE", "CORRELATION_TOLERANCE"]

#: the files' lag windows ρ(τ) that differ by at most this at every lag are one window (their mean is kept):
#: the window-bias correction then errs by at most 1 % of that bias, far below any mode's damping error
LAG_WINDOW_TOLERANCE = 0.01
#: the files' line correlations that differ by at most this (absolute, every lag and line) are one (their mean
#: is kept); a whitening from a correlation off by 0.05 changes a line's weight by a few per cent
CORRELATION_TOLERANCE = 0.05


@dataclass(frozen=True, eq=False)
class RovingEstimate(EstimatedFRF):
    """The FRFs of a roving-hammer test, joined from one estimate per hit point.

    Attributes
    ----------
    point_sources : tuple of (str, tuple of str)
        Each hit point (the force channel's name) and the files hit there, in the order of the channels.
    join_note : str
        What was joined and what was dropped, and why (a sentence for the results' ``settings``).
    """

    point_sources: tuple = ()
    join_note: str = ""


def roving_points(records, plans) -> list[tuple[str, list[int]]] | None:
    """The hit points of a roving-hammer test and the records hit at each, or None for takes of one test.

    Parameters
    ----------
    records : sequence of TimeRecord
        One per file, in the order given.
    plans : sequence of TimePlan
        Each record's channels (:func:`modal.time_frf.plan_time_frf`).

    Returns
    -------
    list of (str, list of int) or None
        Each hit point (the excitation channel's name) in order of first appearance, with the indices of
        the records hit there; None when every record's excitation has one name (takes of one test, or
        files that are not one test at all: :func:`modal.io.timejoin.join_takes` says which).

    Raises
    ------
    FormatError
        The excitation moves but the responses do not stay (other accelerometers, quantities or units), the
        sample rates differ, or a record has several excitation channels; the message names both files.
    """
    first, plan0 = records[0], plans[0]

    def force_name(record, plan):
        return "/".join(record.names[k] for k in plan.inputs)

    names = [force_name(r, p) for r, p in zip(records, plans)]
    if len(set(names)) == 1:
        return None
    for record, plan in zip(records, plans):
        src = record.source
        if len(plan.inputs) != 1:
            raise FormatError(f"{src}: {len(plan.inputs)} excitation channels; expected one force channel per file "
                              "of a roving-hammer test (the hammer's)")
        if abs(record.sample_rate_hz - first.sample_rate_hz) > 1e-6 * first.sample_rate_hz:
            raise FormatError(f"{src}: sample rate {record.sample_rate_hz:.9g} Hz where {first.source} has "
                              f"{first.sample_rate_hz:.9g} Hz; expected one rate in every file of a roving-hammer "
                              "test (resample first)")
        force, force0 = plan.inputs[0], plan0.inputs[0]
        for field in ("quantities", "units"):
            mine, theirs = getattr(record, field)[force], getattr(first, field)[force0]
            if mine != theirs:
                raise FormatError(f"{src}: excitation channel {force + 1} ({field}) is {mine!r} where "
                                  f"{first.source} has {theirs!r}; expected one hammer in every file of a "
                                  "roving-hammer test")
        if len(plan.outputs) != len(plan0.outputs):
            raise FormatError(f"{src}: {len(plan.outputs)} response channel(s) where {first.source} has "
                              f"{len(plan0.outputs)}; expected the same accelerometers in every file of a "
                              "roving-hammer test (the hammer moves, the sensors stay)")
        for k, k0 in zip(plan.outputs, plan0.outputs):
            for field in ("names", "quantities", "units"):
                mine, theirs = getattr(record, field)[k], getattr(first, field)[k0]
                if mine != theirs:
                    raise FormatError(f"{src}: response channel {k + 1} ({field}) is {mine!r} where {first.source} "
                                      f"has {theirs!r}; expected the same accelerometers in every file of a "
                                      "roving-hammer test (the hammer moves, the sensors stay; files that move "
                                      "the sensors: estimate each with python -m modal frf and fit the FRF files "
                                      "together)")
    points: dict[str, list[int]] = {}
    for k, name in enumerate(names):
        points.setdefault(name, []).append(k)
    return list(points.items())


def join_estimates(estimates: Sequence[EstimatedFRF], point_sources,
                   notes: Sequence[str] = ()) -> RovingEstimate:
    """One FRF set of the hit points' estimates, channel after channel, with what their errors can share.

    Parameters
    ----------
    estimates : sequence of EstimatedFRF
        One per hit point, on one frequency axis, of one kind, unit and window.
    point_sources : sequence of (str, sequence of str)
        Each estimate's hit point and its files.
    notes : sequence of str
        Sentences for the join note (how the estimates were made alike).

    Returns
    -------
    RovingEstimate

    Raises
    ------
    FormatError
        Estimates on other frequency axes, of another kind, unit or exponential window (the message names both
        points' files).
    """
    first = estimates[0]
    label = [", ".join(files) for _, files in point_sources]
    for est, where in zip(estimates[1:], label[1:]):
        if est.n_freq != first.n_freq or not np.array_equal(est.frequency_hz, first.frequency_hz):
            raise FormatError(f"{where}: {est.n_freq} lines up to {est.frequency_hz[-1]:g} Hz where {label[0]} has "
                              f"{first.n_freq} up to {first.frequency_hz[-1]:g} Hz; expected one frequency axis "
                              "(give --segment-length)")
        if (est.kind, est.units) != (first.kind, first.units):
            raise FormatError(f"{where}: {est.kind} in {est.units!r} where {label[0]} has {first.kind} in "
                              f"{first.units!r}; expected one kind and unit for the FRFs fitted together")
        if (est.exponential_decay_s or 0.0) != (first.exponential_decay_s or 0.0):
            raise FormatError(f"{where}: exponential window {est.exponential_decay_s} s where {label[0]} has "
                              f"{first.exponential_decay_s} s; expected one window for FRFs fitted together")

    def stacked(name):
        values = [getattr(e, name) for e in estimates]
        if any(v is None for v in values):
            return None
        return np.concatenate([np.atleast_2d(v) for v in values], axis=0)

    def ids(name):
        values = [getattr(e, name) for e in estimates]
        return None if any(v is None for v in values) else tuple(i for v in values for i in v)

    model, dropped = _joined_noise_model([e.noise_model for e in estimates],
                                         [np.atleast_2d(e.response) for e in estimates])
    rejected = [dict(item, take_name=item.get("take_name", e.source)) for e in estimates for item in e.rejected]
    overloads = [dict(item, channel=f"{e.source}: {item['channel']}") for e in estimates for item in e.overloads]
    unrelated = [dict(item, channel=f"{e.source}: {item['channel']}") for e in estimates for item in e.unrelated]
    points = ", ".join(f"{point} ({', '.join(files)})" for point, files in point_sources)
    averages = [e.averages for e in estimates]
    note = (f"roving hammer: {len(estimates)} hit points {points}, each estimated from its own file(s) "
            f"({min(averages)}–{max(averages)} averages) and joined channel by channel")
    note = "; ".join([note, *notes, *dropped])
    return RovingEstimate(
        frequency_hz=first.frequency_hz, response=stacked("response"), kind=first.kind,
        response_points=ids("response_points"), reference_points=ids("reference_points"), units=first.units,
        source=f"{estimates[0].source} (+{len(estimates) - 1} hit point{'s' if len(estimates) > 2 else ''})",
        noise_std=stacked("noise_std"), exponential_decay_s=first.exponential_decay_s, noise_model=model,
        coherence=stacked("coherence"), multiple_coherence=stacked("multiple_coherence"), averages=min(averages),
        rejected=rejected, estimator=first.estimator, window=first.window, sample_rate_hz=first.sample_rate_hz,
        segment_length=first.segment_length, overlap=first.overlap, n_inputs=1, hit_times_s=(), overloads=overloads,
        unrelated=unrelated,
        point_sources=tuple((p, tuple(f)) for p, f in point_sources), join_note=note)


def _joined_noise_model(models, responses) -> tuple[NoiseModel | None, list[str]]:
    """The noise model the estimates share, and a sentence for each part dropped (why).

    Where every estimate carries its excitation noise's error apart (``relative_error``, a hammer's), the points'
    response noise is what they share (one window, one kind of accelerometer noise): its line correlation and
    variance are joined as the outputs of one file share theirs, and each point's excitation noise is carried as
    its channels' own (:func:`_response_part`, :func:`_joined_relative_error`), independent of the other points'.
    """
    if any(m is None for m in models):
        return None, ["no noise model (not every point's estimate has one)"] if any(models) else []
    first, dropped = models[0], []
    lag = first.lag_window
    if any(m.lag_window is None for m in models):
        lag = None
        if any(m.lag_window is not None for m in models):
            dropped.append("no lag window (not every point's estimate has one): the window's bias is not taken out")
    else:
        lags = [m.lag_window for m in models]
        spread = _spread(lags)
        if spread is None or spread > LAG_WINDOW_TOLERANCE:
            lag = None
            dropped.append("the points' lag windows differ (" + _by(spread) + f", above {LAG_WINDOW_TOLERANCE:g}): "
                           "the window's bias is not taken out")
        else:
            lag = np.mean(lags, axis=0)
    relative = _joined_relative_error(models, responses)
    parts = [_response_part(m, h) for m, h in zip(models, responses)] if relative is not None else None
    correlation = None
    if all(m.line_correlation is not None for m in models):
        corrs = [m.line_correlation for m in models] if parts is None else [p[1] for p in parts]
        spread = _spread(corrs)
        if spread is not None and spread <= CORRELATION_TOLERANCE:
            correlation = np.mean(corrs, axis=0)
        else:
            dropped.append("the points' line correlations differ (" + _by(spread) + f", above {CORRELATION_TOLERANCE:g}"
                           "; each is its own channel's, mixed with its force noise): lines weighted as uncorrelated, "
                           "the fit checks its residual's correlation")
    variance = None
    if all(m.variance_model is not None for m in models):
        # the line weights use the channels' mean variance: the models' mean is its shape
        variance = np.mean([m.variance_model for m in models] if parts is None else [p[0] for p in parts], axis=0)
    if any(m.record_influence is not None for m in models):
        dropped.append("each point's records' influences describe its own channel only: the errors of the joint "
                       "fit come from the lines")
    joined = NoiseModel(averages=min(m.averages for m in models),
                        degrees_of_freedom=min(m.degrees_of_freedom for m in models), line_correlation=correlation,
                        lag_window=lag, sample_interval_s=first.sample_interval_s, variance_model=variance,
                        relative_error=relative)
    return joined, dropped


def _joined_relative_error(models, responses) -> JoinedError | None:
    """Each joined point's excitation-noise error, its channels' own over its own ξ (the points' records are
    independent; a fit forms their factors on its lines, :meth:`~modal.shared_error.JoinedError.factor`); None
    unless every point carries one (and a variance model and line correlation)."""
    if any(not isinstance(m.relative_error, CommonError) or m.variance_model is None
           or m.line_correlation is None for m in models):
        return None
    return JoinedError(tuple(m.relative_error for m in models), tuple(h.shape[0] for h in responses))


def _response_part(model, response) -> tuple[np.ndarray, np.ndarray]:
    """The response noise's share of a point's variance model and line correlation.

    Several outputs: the estimate carries only that already (its excitation noise is ``relative_error``). One
    output: its model mixes both, variance (a + b|H|²)/S_xx and covariance of lines k, k + m
    ρ_m,k σ_k σ_k+m, of which the excitation noise's is H_k conj(H_k+m) E[η_k η*_k+m]; what is left
    is the response noise's (on lines where the mixed model does not hold, NaN variance, the correlation is
    the response noise's already; a variance left not positive is NaN, which line weights take as unknown)."""
    if response.shape[0] > 1:
        return model.variance_model, model.line_correlation
    h, common, total = response[0], model.relative_error, model.variance_model
    with np.errstate(invalid="ignore", divide="ignore"):
        own = total - np.abs(h) ** 2 * common.lagged(0).real
        own = np.where(own > 0, own, np.nan)
        corr = np.array(model.line_correlation, complex)
        for m in range(1, corr.shape[0] + 1):
            mixed = corr[m - 1, :-m] * np.sqrt(total[:-m] * total[m:])
            excitation = h[:-m] * np.conj(h[m:]) * common.lagged(m)
            value = (mixed - excitation) / np.sqrt(own[:-m] * own[m:])
            held = np.isfinite(total[:-m]) & np.isfinite(total[m:])
            corr[m - 1, :-m] = np.where(held, np.where(np.isfinite(value), value, 0.0), corr[m - 1, :-m])
    magnitude = np.abs(corr)
    corr = np.where(magnitude > 1, corr / np.maximum(magnitude, 1e-300), corr)
    return own, corr


def _spread(arrays) -> float | None:
    """Largest absolute difference from the first array (None when the shapes differ)."""
    if len({a.shape for a in arrays}) != 1:
        return None
    return float(max(np.max(np.abs(a - arrays[0]), initial=0.0) for a in arrays))


def _by(spread: float | None) -> str:
    return "other lengths" if spread is None else f"by up to {spread:.2g}"

