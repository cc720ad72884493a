"""Command line: ``python -m modal fit PATH`` (console script ``modalbal``).

Exit codes: 0 success, 1 unreadable input or failed identification (one line
on stderr naming the file, the field and what was expected), 2 usage error.
Results go to stdout (a table, or one JSON document with ``--json``); logs and
warnings go to stderr.
"""
from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

from .cli_time import add_time_options, save_time_plots
from .time_frf import frf_from_time
from .errors import ModalError, kept_warnings
from .frf import FRF_KINDS
from .report import jsonable

__all__ = ["main", "build_parser"]


def add_fit_options(parser: argparse.ArgumentParser) -> None:
    """The options that say how a file is read and fitted (``modal fit`` and ``modal batch``;
    :class:`modal.fitting.FitOptions` holds them)."""
    parser.add_argument("--method", choices=["auto", "nls", "circle", "halfpower", "global", "all"], default="auto",
                        help="identification method (default: auto = global for poly-reference or many-mode data, "
                             "else nls, the band-wise least-squares refinement; the output says which ran; global: "
                             "poly-reference LSCF with a stabilisation diagram and a joint refinement of all modes, "
                             "for many modes, channels and references; all: the three band-wise methods)")
    parser.add_argument("--modes-hz", dest="modes_hz", type=float, nargs="+", metavar="HZ",
                        help="global: keep the modes nearest these frequencies (Hz) instead of the automatic choice")
    parser.add_argument("--order", type=int, help="global: use this model order's poles instead of the stabilisation")
    parser.add_argument("--max-order", dest="max_order", type=int, help="global: highest order of the sweep")
    parser.add_argument("--max-evaluations", dest="max_evaluations", type=int, metavar="N",
                        help="model evaluations the least-squares refinement may take (circle, halfpower: the one that "
                             "checks them; default: scaled "
                             "to the problem, never reached by ordinary files; where it binds the modes are "
                             "flagged work_capped)")
    parser.add_argument("--band", nargs=2, type=float, action="append", metavar=("FMIN", "FMAX"),
                        help="fitting band of one mode in Hz (repeat for several modes); default: automatic")
    parser.add_argument("--kind", choices=FRF_KINDS, help="FRF kind when the file does not say")
    parser.add_argument("--driving-point", dest="driving_point", nargs="+", metavar="CHANNEL",
                        help="the channel(s) measured at the excitation point: number counted from 1 (as the table "
                             "numbers them; from a time file, its responses in order) or response point id. k, c, m "
                             "are given for driving points only; default: the file's point ids say (response point "
                             "= reference point), and without them no channel gets k, c, m (flag "
                             "driving_point_unknown)")
    parser.add_argument("--frequency-axis", dest="frequency_axis", choices=["hz", "khz", "rad/s", "cpm", "rpm"],
                        help="unit of the file's frequency column when it does not say")
    parser.add_argument("--frequency-step", dest="frequency_step", type=float, metavar="HZ",
                        help="line spacing (Hz) for files without a frequency column")
    parser.add_argument("--frequency-start", dest="frequency_start", type=float, metavar="HZ",
                        help="first line (Hz) for files without a frequency column (default 0)")
    parser.add_argument("--layout", help="CSV layout when the header does not say (re_im, mag_phase_deg, db_phase_deg, ...)")
    parser.add_argument("--delimiter", help="CSV delimiter")
    parser.add_argument("--decimal", help="CSV decimal mark, e.g. ','")
    parser.add_argument("--dataset", type=int, help="UFF dataset number (1-based) when the file holds several axes")
    add_time_options(parser)


def build_parser(prog: str = "python -m modal") -> argparse.ArgumentParser:
    """The command-line parser; ``prog`` is the name usage and help give the program."""
    parser = argparse.ArgumentParser(prog=prog, description="Experimental modal analysis.")
    sub = parser.add_subparsers(dest="command", required=True)
    fit = sub.add_parser("fit", help="identify the modes of an FRF file",
                         description="Identify natural frequency, damping, modal constant and k, c, m of every mode.")
    fit.add_argument("path", nargs="+", help="FRF file(s) (UFF 58/58b, CSV, MAT, HDF5); several files on one "
                     "frequency axis become one multi-channel FRF; several time files are takes of one test "
                     "(the same channels, e.g. one file per hammer hit), averaged as one; time files of a roving "
                     "hammer (the force channel names the hit point, the responses stay) are estimated point by "
                     "point and fitted together")
    add_fit_options(fit)
    fit.add_argument("--stabilisation-plot", dest="stabilisation_plot", metavar="OUT.png",
                     help="global: write the stabilisation diagram over the summed FRF")
    fit.add_argument("--export-uff", dest="export_uff", metavar="OUT.uff",
                     help="write the mode shapes (UFF 55) and the synthesised FRFs (UFF 58) of the first method")
    fit.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    fit.add_argument("--plot", metavar="OUT.png", help="write a figure of the fit (every method's model over the data)")
    fit.add_argument("--channel", type=int, metavar="N",
                     help="--plot: draw only channel N (counted from 1, as the table numbers them); default every "
                          "channel (the RMS over channels above 8)")
    fit.add_argument("--archive", metavar="OUT.h5", help="write the FRF and results to an HDF5 archive")
    fit.add_argument("--geometry", metavar="GEOM", help="the test geometry (UFF 15/2411 and 82, CSV or TOML): kept "
                     "with the results by --archive, written before the shapes by --export-uff")
    frf = sub.add_parser("frf", help="estimate FRFs from a time record (force and responses)",
                         description="Estimate FRFs with coherence and noise per line from a time file "
                                     "(UFF 58/58b function type 1, CSV with a time column, MAT, HDF5).")
    frf.add_argument("path", nargs="+", help="time file(s); several are takes of one test (the same channels, "
                     "e.g. one file per hammer hit), averaged as one; files of a roving hammer (the force channel "
                     "names the hit point) give one FRF per point")
    frf.add_argument("--out", required=True, metavar="FRF.h5",
                     help="output: .h5 keeps coherence, noise and settings; .uff/.csv/.mat the FRF only")
    frf.add_argument("--kind", choices=FRF_KINDS, help="FRF kind (default: from what the responses measured)")
    frf.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    frf.add_argument("--plot", metavar="OUT.png", help="write the FRFs with coherence and error band "
                     "(and OUT_hits.png with the hits for --impact)")
    add_time_options(frf)
    report = sub.add_parser("report", help="write a self-contained HTML report of an archive",
                            description="One HTML file that opens offline: the test at a glance, the modes and "
                                        "their flags, FRFs with the fitted models, the stabilisation diagram, MAC, "
                                        "and the mode shapes animated on the test geometry (and a scene's results).")
    report.add_argument("archive", metavar="ARCHIVE.h5", help="archive of python -m modal fit --archive or "
                        "python -m balancer run")
    report.add_argument("--out", required=True, metavar="REPORT.html", help="the HTML file to write")
    report.add_argument("--geometry", metavar="GEOM", help="test geometry (UFF 15/2411 and 82, CSV or TOML); "
                        "default the archive's own, else the channels on a line in file order")
    report.add_argument("--gif", metavar="OUT.gif", help="also write one mode's animation as a GIF")
    report.add_argument("--mode", type=int, default=1, metavar="N",
                        help="--gif: the mode to animate, numbered as in the report (default 1)")
    report.add_argument("--method", metavar="METHOD",
                        help="--gif: the result whose mode is animated (default the archive's first)")
    from .batch.cli import add_batch_parser
    from .cli_oma import add_oma_parser

    add_batch_parser(sub, add_fit_options)
    add_oma_parser(sub)
    return parser


def _showwarning(message, category, filename, lineno, file=None, line=None):
    print(f"warning: {message}", file=sys.stderr)


def _fit(args) -> int:
    from .fitting import FitOptions, fit_path

    with kept_warnings() as said:  # shown as they come, and kept for the JSON document and the archive
        fitted = fit_path(args.path if len(args.path) > 1 else args.path[0], FitOptions.from_args(args),
                          report_estimate=_report_estimate, report=_note)
    frf, results = fitted.frf, list(fitted.results)
    time_data = None if fitted.time_data is None else (frf, *fitted.time_data)
    more = len(args.path) - 1
    label = args.path[0] if not more else f"{args.path[0]} (+{more} file{'s' if more > 1 else ''})"
    methods = [r.method for r in results]  # what ran ("auto" chooses)
    points = None
    if frf.response_points is not None:
        refs = frf.reference_points or ("?",) * frf.n_channels
        points = [f"{r} / {q}" for r, q in zip(frf.response_points, refs)]
    if args.channel is not None and not 1 <= args.channel <= frf.n_channels:
        raise ModalError(f"--channel {args.channel}: no such channel; expected 1..{frf.n_channels}")
    if args.json:
        from .frf_units import result_units

        rows = [dict(row, channel=row["channel"] + 1) for result in results for row in result.rows()]
        doc = {"file": args.path[0] if len(args.path) == 1 else list(args.path), "kind": frf.kind, "n_channels": frf.n_channels,
               "methods": methods, "driving_point": _driving_point_doc(results, args.driving_point),
               "modal_constant_units": result_units(frf.kind, results[0].settings)["modal_constant"],
               "warnings": said, "modes": rows}
        json.dump(jsonable(doc), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        from .report import format_table

        print(f"{label}: {frf.n_channels} channel(s), {frf.n_freq} lines, "
              f"{frf.frequency_hz[0]:g}–{frf.frequency_hz[-1]:g} Hz, {frf.kind}")
        for result in results:
            print()
            print(format_table(result, points))
    if args.plot:
        from .io._atomic import atomic_path
        from .plots import plot_fit

        fig = plot_fit(frf, results, channel=None if args.channel is None else args.channel - 1)
        with atomic_path(args.plot) as tmp:
            fig.savefig(tmp, dpi=110, format=Path(args.plot).suffix.lstrip(".") or "png")
        print(f"plot: {args.plot}", file=sys.stderr)
        if time_data is not None:
            stem = Path(args.plot)
            for path in save_time_plots(stem.with_name(f"{stem.stem}_estimate{stem.suffix}"), *time_data,
                                        hits_target=stem.with_name(f"{stem.stem}_hits{stem.suffix}")):
                print(f"plot: {path}", file=sys.stderr)
    geometry = None
    if args.geometry:
        if not (args.archive or args.export_uff):
            raise ModalError("--geometry goes with the results: give --archive OUT.h5 or --export-uff OUT.uff as well")
        from .io.geometry import read_geometry
        from .shapes import mode_shapes

        geometry = read_geometry(args.geometry)
        shapes = mode_shapes(results[0], frf.response_points, frf.reference_points)
        shapes.placed_on(geometry)  # every channel must stand on a node of the geometry: one line if not
    if getattr(args, "export_uff", None):
        from .global_.export import export_uff

        export_uff(results[0], frf, args.export_uff, geometry)
        print(f"uff: {args.export_uff}", file=sys.stderr)
    if getattr(args, "stabilisation_plot", None):
        if results[0].stabilisation is None:
            raise ModalError("--stabilisation-plot needs --method global")
        from .global_.plots import plot_stabilisation
        from .io._atomic import atomic_path

        fig = plot_stabilisation(frf, results[0])
        target = Path(args.stabilisation_plot)
        with atomic_path(target) as tmp:
            fig.savefig(tmp, dpi=110, format=target.suffix.lstrip(".") or "png")
        print(f"plot: {target}", file=sys.stderr)
    if args.archive:
        from .archive import write_archive

        items = {"frf": frf, **{f"identify_{r.method}": r for r in results}, "source_files": list(args.path)}
        if geometry is not None:
            items["geometry"] = geometry
        write_archive(args.archive, items, warnings={name: said for name in items if name.startswith("identify_")})
        print(f"archive: {args.archive}", file=sys.stderr)
    return 0


def _driving_point_doc(results, declared) -> dict:
    """What ``--json`` says of the driving point: where it is known from (``"point ids"``, ``"declared"``) or
    ``"unknown"`` with how to declare it, and the driving-point channels (counted from 1)."""
    from .flags import FLAG_ACTION

    modes = [mode for result in results for mode in result.modes]
    if any("driving_point_unknown" in mode.flags for mode in modes):
        return {"known_from": "unknown", "channels": [], "how_to_declare": FLAG_ACTION["driving_point_unknown"]}
    driving = np.atleast_1d(modes[0].driving_point) if modes else np.zeros(0, bool)
    return {"known_from": "declared" if declared else "point ids",
            "channels": [int(k) + 1 for k in np.flatnonzero(driving)]}


def _note(line: str) -> None:
    print(line, file=sys.stderr)


def _report_estimate(frf) -> None:
    """One line on stderr: what the estimate averaged and what it rejected."""
    print(f"{frf.source}: {frf.estimator} estimate, {frf.averages} average(s), window {frf.window}"
          + (f", exponential decay {frf.exponential_decay_s:g} s (its damping is removed)"
             if frf.exponential_decay_s else ""), file=sys.stderr)
    for item in frf.rejected:
        detail = f" ({item['detail']})" if item.get("detail") else ""
        where = item.get("take_name", frf.source)
        print(f"{where}: hit {item['hit']} at {item['time_s']:.4g} s rejected: {item['reason']}{detail}",
              file=sys.stderr)


def _frf(args) -> int:
    from .io import write_frf

    with kept_warnings() as said:
        frf, *record = frf_from_time(args.path[0] if len(args.path) == 1 else args.path, args, _note)
    _report_estimate(frf)
    write_frf(frf, args.out)
    if args.plot:
        for path in save_time_plots(args.plot, frf, *record):
            print(f"plot: {path}", file=sys.stderr)
    if args.json:
        doc = {"file": args.path[0] if len(args.path) == 1 else list(args.path), "out": args.out, "kind": frf.kind, "n_channels": frf.n_channels,
               "n_lines": frf.n_freq, "averages": frf.averages, "estimator": frf.estimator, "window": frf.window,
               "exponential_decay_s": frf.exponential_decay_s, "rejected": frf.rejected,
               "overloads": frf.overloads, "unrelated": frf.unrelated, "warnings": said,
               "response_points": list(frf.response_points or []),
               "reference_points": list(frf.reference_points or [])}
        json.dump(jsonable(doc), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(f"{args.out}: {frf.n_channels} FRF(s), {frf.n_freq} lines, {frf.kind}")
    return 0


def _report(args) -> int:
    with kept_warnings():  # the page and the GIF place the shapes on the geometry alike: each warning shown once
        return _write_report(args)


def _write_report(args) -> int:
    from .report import write_report

    geometry = None
    if args.geometry:
        from .io.geometry import read_geometry

        geometry = read_geometry(args.geometry)
    from .report.content import report_content

    content = report_content(args.archive, geometry)  # read once: the page and the GIF, its warnings given once
    out = write_report(args.archive, args.out, geometry, content=content)
    print(f"report: {out}", file=sys.stderr)
    if args.gif:
        from .shape_plots import write_gif

        available = [(r.method, s) for r, s in zip(content.results, content.shapes) if s is not None]
        if args.method is not None:
            available = [(m, s) for m, s in available if m == args.method]
        if not available:
            raise ModalError(f"{args.archive}: no result{' of method ' + args.method if args.method else ''} with mode "
                             f"shapes to animate")
        shapes = available[0][1]
        if not 1 <= args.mode <= shapes.n_modes:
            raise ModalError(f"--mode must be 1..{shapes.n_modes} (the modes of method {shapes.method}), got {args.mode}")
        write_gif(args.gif, shapes, args.mode - 1, content.geometry)
        print(f"gif: {args.gif}", file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    from .cli_name import program_name

    parser = build_parser(program_name("modal", argv))
    args = parser.parse_args(argv)  # exits with 2 on a usage error
    warnings.showwarning = _showwarning
    if args.command == "batch":
        from .batch.cli import run_batch

        return run_batch(args, parser)
    try:
        if args.command == "fit":
            return _fit(args)
        if args.command == "frf":
            return _frf(args)
        if args.command == "report":
            return _report(args)
        if args.command == "oma":
            from .cli_oma import run_oma

            return run_oma(args)
    except ModalError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        path = getattr(args, "path", None) or args.archive
        path = path if isinstance(path, str) else path[0]
        print(f"error: {exc.filename or path}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
