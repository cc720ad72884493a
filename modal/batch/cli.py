"""``python -m modal batch DIR_OR_GLOB... --out RESULTS.h5``: the command line of :mod:`modal.batch`.

Exit codes: 0 every file fitted, 1 some failed (the archive holds the others) or the output is in use by
another run, 2 bad usage.
stdout: one summary line, or one JSON document with ``--json``; stderr: each file's warnings and
the failures, one line each, a note per group of files that hold the same bytes and per group that
look like takes of one test, and a progress bar when stderr is a terminal.
"""
from __future__ import annotations

import argparse
import json
import math
import sys

from .fitproc import DEFAULT_FILE_TIMEOUT_S

__all__ = ["add_batch_parser", "run_batch", "failure_line"]


def add_batch_parser(sub, add_fit_options) -> argparse.ArgumentParser:
    """The ``batch`` subcommand (with every fit option of ``modal fit``)."""
    batch = sub.add_parser(
        "batch", help="fit many FRF files (locally or on a Dask cluster) into one archive and one table",
        description="Fit every FRF file found (folders are searched recursively for UFF, CSV, MAT and HDF5 files) "
                    "with the options of 'modal fit', on an embedded Dask cluster or an existing one; write one "
                    "archive (a group per file) and one CSV table (a row per file, mode and channel). A rerun "
                    "with the same options reuses the results of unchanged files (by their content's SHA-256). "
                    "One run per output: a second run on the same --out refuses at once, naming the running one. "
                    "Symbolic links are followed only where they stay inside the folders given. Exit 0: every "
                    "file fitted; 1: some failed (listed), or the output is in use; 2: bad usage.")
    batch.add_argument("inputs", nargs="+", metavar="DIR_OR_GLOB", help="folders, glob patterns or files")
    batch.add_argument("--out", required=True, metavar="RESULTS.h5",
                       help="the archive (replaced whole at the end; results go to RESULTS.h5.parts/ "
                            "meanwhile, so an interrupted run resumes; RESULTS.h5.lock says which run holds it)")
    batch.add_argument("--table", metavar="RESULTS.csv", help="the CSV table (default: the archive's name with .csv)")
    batch.add_argument("--json", action="store_true",
                       help="print one JSON document: files, fitted, reused, failed, warnings (per file, with its "
                            "flagged modes), takes, duplicates, archive, table, wall_time_s")
    batch.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                       help="address of a running Dask scheduler (workers need this package installed and the "
                            "files at the same paths); default: a local cluster")
    batch.add_argument("--workers", type=int, metavar="N", help="local cluster: worker processes (default: the cores)")
    batch.add_argument("--dashboard", nargs="?", const="127.0.0.1:8787", metavar="HOST:PORT",
                       help="local cluster: serve Dask's dashboard (default 127.0.0.1:8787; needs bokeh); without "
                            "it the local cluster opens no web port")
    batch.add_argument("--follow-symlinks", dest="follow_symlinks", action="store_true",
                       help="follow every symbolic link in the folders (default: only links that lead inside the "
                            "folders given)")
    batch.add_argument("--file-timeout", dest="file_timeout", type=float, default=DEFAULT_FILE_TIMEOUT_S,
                       metavar="SECONDS",
                       help=f"time limit of one file's fit (default {DEFAULT_FILE_TIMEOUT_S:g} s; 0: none): a file "
                            "still fitting then is listed as failed ('timed out after N s') and the batch goes on")
    add_fit_options(batch)
    batch.add_argument("--oma", action="store_true",
                       help="records of responses only (ambient, no force): each file's modes by operational "
                            "analysis (modal oma, method ssi) with --band (once) and --max-order, not a fit of FRFs")
    batch.add_argument("--rotor-speed-hz", dest="rotor_speed_hz", type=float, metavar="F",
                       help="--oma: the running speed (poles on its harmonics are tones or flagged 'harmonic')")
    batch.add_argument("--reference-channels", dest="reference_channels", nargs="+", metavar="CH",
                       help="--oma: reference channels, numbered from 1 or names (default: chosen from the data)")
    return batch


def failure_line(path: str, error: str) -> str:
    """A failed file's line: the error, which names the file, as it is; otherwise the file first."""
    return error if error.startswith(f"{path}:") else f"{path}: {error}"


def run_batch(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Run ``modal batch``; returns the exit code."""
    from ..errors import ModalError, ParameterError
    from ..fitting import FitOptions
    from ..report import jsonable
    from .run import fit_files, takes_command

    if args.scheduler and args.workers is not None:
        parser.error("--workers applies to the local cluster; the cluster at --scheduler has its own workers")
    if args.scheduler and args.dashboard:
        parser.error("--dashboard applies to the local cluster; the scheduler at --scheduler serves its own")
    if args.workers is not None and args.workers < 1:
        parser.error(f"--workers {args.workers}: expected 1 or more")
    if not (args.file_timeout >= 0 and math.isfinite(args.file_timeout)):
        parser.error(f"--file-timeout {args.file_timeout:g}: expected seconds > 0, or 0 for no limit")
    if not args.oma and (args.rotor_speed_hz is not None or args.reference_channels):
        parser.error("--rotor-speed-hz and --reference-channels apply to --oma")
    if args.dashboard:
        print(f"dashboard: http://{args.dashboard}/status (Dask's, while files are fitted)", file=sys.stderr)
    try:
        options = FitOptions.from_args(args)
        result = fit_files(args.inputs, client=args.scheduler, out=args.out, table=args.table, workers=args.workers,
                           progress=sys.stderr.isatty(), file_timeout_s=args.file_timeout or None,
                           dashboard=args.dashboard or False, follow_symlinks=args.follow_symlinks,
                           **{k: v for k, v in vars(options).items()})
    except ParameterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except ModalError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:  # the archive, the table or the parts folder cannot be written
        print(f"error: {exc.filename or args.out}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"interrupted: the files fitted so far are kept in {args.out}.parts; run the same command again "
              "to finish", file=sys.stderr)
        return 130
    for outcome in result.outcomes:  # what modal fit would have printed of each file, kept in the archive too
        for text in outcome.warnings:
            print(f"warning: {failure_line(outcome.file, text)}", file=sys.stderr)
    for item in result.failed:
        print(f"failed: {failure_line(item['file'], item['error'])}", file=sys.stderr)
    for files in result.duplicates:
        print(f"note: {len(files)} files hold the same bytes (copies?): {', '.join(files)}; the table holds their "
              "results once for each", file=sys.stderr)
    for files in result.takes:  # said once per group, never acted on: the folder may hold repeats on purpose
        print(f"note: {len(files)} files look like takes of one test (one hammer hit each, the same channels at "
              f"the same sample rate): {', '.join(files)}; each was fitted alone, from one hit; to average the "
              f"hits, fit them together: {takes_command(files)}", file=sys.stderr)
    if args.json:
        json.dump(jsonable(result.summary()), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        warned = len(result.warned)
        print(f"{len(result.outcomes)} files: {result.fitted} fitted, {result.reused} reused, "
              f"{len(result.failed)} failed in {result.wall_time_s:.1f} s"
              + (f", {warned} with warnings or flagged modes (table columns warnings, flagged_modes)" if warned else "")
              + f"; archive {result.archive}, table {result.table}")
    return 1 if result.failed else 0
