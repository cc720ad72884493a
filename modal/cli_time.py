"""Command-line glue for time data: the options of ``modal fit TIME_FILE`` and ``modal frf``.

Kept apart from :mod:`modal.cli` so that the FRF path stays short to read; both
subcommands share :func:`add_time_options` and :func:`frf_from_time`.
"""
from __future__ import annotations

import argparse
import sys

from .errors import FormatError
from .estimate import ESTIMATORS, WINDOWS, EstimatedFRF, estimate_frf
from .frf import FRF_KINDS

__all__ = ["add_time_options", "frf_from_time", "save_time_plots", "wants_time", "TIME_OPTIONS"]

#: the attribute names the time options set (None when not given)
TIME_OPTIONS = ("excitation", "response", "impact", "estimator", "window", "exponential_decay_s", "segment_length",
                "overlap")
_KIND_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


def add_time_options(parser: argparse.ArgumentParser) -> None:
    """Options that turn a time record into FRFs (``modal fit`` and ``modal frf``)."""
    group = parser.add_argument_group("time data (force and response records; FRFs are estimated first)")
    group.add_argument("--excitation", metavar="CHANNEL",
                       help="force channel: number from 1 in file order, or its name/point id "
                            "(default: the one channel the file marks as force)")
    group.add_argument("--response", metavar="CHANNEL", action="append",
                       help="response channel (repeat for several; default: every channel but the excitation)")
    group.add_argument("--impact", action="store_true", help="impact-hammer record: cut one record per hit, "
                       "reject double hits, clipped and undecayed hits")
    group.add_argument("--estimator", choices=ESTIMATORS, help="FRF estimator (default H1)")
    group.add_argument("--window", choices=WINDOWS,
                       help="window (default: hann for continuous records, force for --impact)")
    group.add_argument("--exponential-decay-s", dest="exponential_decay_s", type=float, metavar="S",
                       help="time constant of the exponential window, s (its damping is removed from the modes)")
    group.add_argument("--segment-length", dest="segment_length", type=int, metavar="N",
                       help="samples per segment or hit record (default: automatic)")
    group.add_argument("--overlap", type=float, metavar="F", help="segment overlap fraction (default 0.5)")


def wants_time(args, path) -> bool:
    """Whether ``path`` is to be read as time data (a time option given, or the file holds time data)."""
    from .io.timedata import is_time_file

    given = any(getattr(args, name, None) not in (None, False) for name in TIME_OPTIONS if name != "overlap")
    return given or is_time_file(path)


def frf_from_time(path, args):
    """Read a time file and estimate its FRFs with the command line's options.

    Returns
    -------
    (EstimatedFRF, TimeRecord, list of int, list of int)
        The estimate, the record, and the excitation and response channel indices.
    """
    from .io.timedata import read_time

    record = read_time(path)
    src = record.source
    if args.excitation is not None:
        inputs = [record.channel_index(args.excitation)]
    else:
        inputs = record.force_channels()
        if len(inputs) != 1:
            listing = ", ".join(f"{k + 1}={n} ({q or 'unknown'})"
                                for k, (n, q) in enumerate(zip(record.names, record.quantities)))
            what = "no channel" if not inputs else f"{len(inputs)} channels"
            raise FormatError(f"{src}: {what} marked as force ({listing}); expected one: name the force channel "
                              "with --excitation CHANNEL (an FRF needs an excitation)")
        print(f"{src}: excitation channel {inputs[0] + 1} ({record.names[inputs[0]]})", file=sys.stderr)
    if args.response:
        outputs = [record.channel_index(r) for r in args.response]
    else:
        outputs = [k for k in range(record.n_channels) if k not in inputs]
    if not outputs:
        raise FormatError(f"{src}: no response channel besides the excitation; expected at least one")
    quantities = {record.quantities[k] for k in outputs}
    quantity = quantities.pop() if len(quantities) == 1 else None
    if len(quantities) > 0:
        raise FormatError(f"{src}: the response channels measured different quantities; expected one kind "
                          "(choose them with --response)")
    kind = getattr(args, "kind", None) or _KIND_OF_QUANTITY.get(quantity or "")
    if kind is None:
        raise FormatError(f"{src}: the file does not say what the response channels measured; give --kind "
                          f"({', '.join(FRF_KINDS)})")
    window = args.window or ("force" if args.impact else "hann")
    estimate = estimate_frf(
        record.signals[inputs], record.signals[outputs], record.sample_rate_hz,
        estimator=args.estimator or "H1", kind=kind, segment_length=args.segment_length,
        overlap=0.5 if args.overlap is None else args.overlap, window=window,
        exponential_decay_s=args.exponential_decay_s, impact=args.impact,
        response_quantity=quantity, excitation_points=[record.names[k] for k in inputs],
        response_points=[record.names[k] for k in outputs], source=src)
    return estimate, record, inputs, outputs


def save_time_plots(target, estimate: EstimatedFRF, record, inputs, outputs, hits_target=None) -> list[str]:
    """Write the estimate's figure to ``target`` and, for impact records, the hits' figure; returns the paths.

    The hits' figure goes to ``hits_target`` (default ``<target stem>_hits<suffix>``).
    """
    from pathlib import Path

    from .estimate.plots import plot_estimate, plot_hits
    from .io._atomic import atomic_path

    target = Path(target)
    figures = [(target, plot_estimate(estimate))]
    if estimate.hit_times_s or estimate.rejected:
        hits_path = Path(hits_target) if hits_target else target.with_name(f"{target.stem}_hits{target.suffix}")
        figures.append((hits_path,
                        plot_hits(record.signals[inputs[0]], record.signals[outputs], record.sample_rate_hz, estimate)))
    written = []
    for path, fig in figures:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format=path.suffix.lstrip(".") or "png")
        written.append(str(path))
    return written
