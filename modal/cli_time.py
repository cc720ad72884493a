"""Command-line glue for time data: the options of ``modal fit TIME_FILE`` and ``modal frf``.

Kept apart from :mod:`modal.cli` so that the FRF path stays short to read; both
subcommands share :func:`add_time_options` and :func:`save_time_plots`, and read the file with
:func:`modal.time_frf.frf_from_time`.
"""
from __future__ import annotations

import argparse

from .estimate import ESTIMATORS, WINDOWS, EstimatedFRF

__all__ = ["add_time_options", "save_time_plots"]


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


def save_time_plots(target, estimate: EstimatedFRF, record, inputs, outputs, hits_target=None) -> list[str]:
    """Write the estimate's figure to ``target`` and, for impact records, the hits' figure; returns the paths.

    The hits' figure goes to ``hits_target`` (default ``<target stem>_hits<suffix>``).
    """
    from pathlib import Path

    from .estimate.plots import plot_estimate, plot_hits
    from .io._atomic import atomic_path

    target = Path(target)
    figures = [(target, plot_estimate(estimate))]
    if record is not None and (estimate.hit_times_s or estimate.rejected):
        hits_path = Path(hits_target) if hits_target else target.with_name(f"{target.stem}_hits{target.suffix}")
        figures.append((hits_path,
                        plot_hits(record.signals[inputs[0]], record.signals[outputs], record.sample_rate_hz, estimate)))
    written = []
    for path, fig in figures:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format=path.suffix.lstrip(".") or "png")
        written.append(str(path))
    return written
