"""Command line: ``python -m balancer run SCENE.toml [--out A.h5] [--plots DIR] [--archive EARLIER.h5] [--json]``
and ``python -m balancer influence READINGS.toml ...`` (see :mod:`balancer.influence.cli`).

Exit codes: 0 success, 1 bad scene or input (one line on stderr naming the
file, the key and what was expected) or a figure that could not be drawn or written
(the stage and the cause), 2 usage error. The summary (or JSON with
``--json``) goes to stdout; progress and warnings go to stderr.
"""
from __future__ import annotations

import argparse
import json
import sys
import warnings

from modal.errors import ModalError
from modal.report import jsonable

__all__ = ["main"]


def build_parser(influence: bool = True, prog: str = "python -m balancer") -> argparse.ArgumentParser:
    """The command-line parser; ``influence=False`` leaves out the ``influence`` command (not imported); ``prog`` is
    the name usage and help give the program."""
    parser = argparse.ArgumentParser(prog=prog, description="Balancing studies fed by modal identification.")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene end to end",
                         description="Run a scene (a TOML file naming an FRF or a time record, the identification "
                                     "and the balancing studies): only the stages its outputs need, reusing unchanged "
                                     "stages of an earlier archive; writes the archive and plots and prints a summary.")
    run.add_argument("scene", help="scene TOML file")
    run.add_argument("--out", metavar="ARCHIVE.h5", help="archive to write, in an existing folder (default out/<scene name>.h5)")
    run.add_argument("--plots", metavar="DIR", help="folder for the plots, made in an existing folder (for a scene whose [outputs] lists no "
                     "plots: the figures of every stage it runs)")
    run.add_argument("--archive", metavar="EARLIER.h5", help="earlier archive of the scene: reuse unchanged stages")
    run.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    if influence:
        from .influence.cli import add_parser as add_influence

        add_influence(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    from .scene.plotter import dismiss_early

    try:
        return _main(argv)
    finally:
        dismiss_early()  # a plotting process started for `run` (python -m balancer) that no run took over


def _main(argv: list[str] | None) -> int:
    from modal.cli_name import program_name

    prog = program_name("balancer", argv)
    argv = sys.argv[1:] if argv is None else list(argv)
    # a scene run does not need the influence command's modules
    args = build_parser(influence=not (argv and argv[0] == "run"), prog=prog).parse_args(argv)
    warnings.showwarning = lambda message, *a, **k: print(f"warning: {message}", file=sys.stderr)
    if args.command == "influence":
        from .influence.cli import run as run_influence

        return run_influence(args)
    from .scene import run_scene
    from .scene.summary import digest

    try:
        import os

        run = run_scene(args.scene, out=args.out, plots_dir=args.plots, archive=args.archive,
                        progress=lambda msg: print(msg, file=sys.stderr, flush=True),
                        plot_jobs=2 if (os.cpu_count() or 1) > 1 else 1)
    except ModalError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"error: {exc.filename or args.scene}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    if args.json:
        doc = {"scene": args.scene, "stages": run.stages, "archive": run.archive_path, "plots": list(run.plot_paths),
               "timings_s": run.timings_s, "warnings": {s: list(w) for s, w in run.warnings.items()},
               "results": {s: digest(s, r) for s, r in run.results.items()}}
        json.dump(jsonable(doc), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(run.summary)
    return 0
