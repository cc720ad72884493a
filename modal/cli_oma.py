"""Command-line glue of ``python -m modal oma TIME_FILE...``: operational modal analysis of ambient records.

One file: one record, identified. Several files: one setup each (roving sensors with shared
references), identified apart and merged over ``--reference-channels``.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["add_oma_parser", "add_oma_options", "run_oma"]


def add_oma_options(parser: argparse.ArgumentParser) -> None:
    """The options of :class:`modal.operational.files.OMAOptions` (``modal oma`` and ``modal batch --oma``)."""
    from .operational.methods import OMA_METHODS

    parser.add_argument("--band", nargs=2, type=float, metavar=("FMIN", "FMAX"),
                        help="band of interest in Hz (default: 0 Hz to 80 %% of the Nyquist frequency)")
    parser.add_argument("--method", choices=OMA_METHODS, default=None,
                        help="ssi: covariance-driven stochastic subspace identification (default); plscf: "
                             "poly-reference LSCF on half-spectra (a cross-check); fdd, efdd: quick looks")
    parser.add_argument("--reference-channels", dest="reference_channels", nargs="+", metavar="CH",
                        help="reference (projection) channels, numbered from 1 in the file's order (or names); "
                             "with several files, the references every setup shares, in the same order "
                             "(default: chosen from the data)")
    parser.add_argument("--rotor-speed-hz", dest="rotor_speed_hz", type=float, metavar="F",
                        help="running speed: poles on its harmonics are tones or flagged 'harmonic'")
    parser.add_argument("--max-order", dest="max_order", type=int, metavar="N", help="highest model order (default 80)")


def add_oma_parser(sub) -> argparse.ArgumentParser:
    oma = sub.add_parser("oma", help="operational modal analysis of ambient response records (no force channel)",
                         description="Identify natural frequency, damping ratio and shape of every mode from "
                                     "response records alone, with standard errors; machine tones listed apart. "
                                     "With --mass-change, a second record with known masses added scales the "
                                     "shapes to unit modal mass: k, c, m per channel.")
    oma.add_argument("path", nargs="+", help="time file(s) (UFF 58/58b function type 1, CSV with a time column, "
                     "MAT, HDF5); several files are setups sharing --reference-channels, merged")
    add_oma_options(oma)
    oma.add_argument("--mass-change", dest="mass_change", metavar="AFTER",
                     help="time file of the same channels with known masses added (--added-mass-kg): the modes "
                          "of PATH scaled to unit modal mass, k, c, m at every channel")
    oma.add_argument("--added-mass-kg", dest="added_mass_kg", nargs=2, action="append", metavar=("CH", "KG"),
                     help="--mass-change: a mass added at channel CH (numbered from 1, or its name), kg; repeat "
                          "for several channels")
    oma.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    oma.add_argument("--plot", metavar="OUT.png", help="write the stabilisation diagram (first setup)")
    oma.add_argument("--archive", metavar="OUT.h5", help="write the results to an HDF5 archive")
    return oma


def _table(result, label: str) -> str:
    lines = [f"{label}: {result.n_channels} channels, method {result.method}, band "
             f"{result.settings['band_hz'][0]:g}-{result.settings['band_hz'][1]:g} Hz",
             f"{'mode':>4} {'f [Hz]':>10} {'± [Hz]':>9} {'zeta [%]':>9} {'± [%]':>7} {'MPC':>5}  flags"]
    for k, mode in enumerate(result, start=1):
        lines.append(f"{k:>4} {mode.natural_frequency_hz:>10.4f} {mode.std.natural_frequency_hz:>9.4f} "
                     f"{100 * mode.damping_ratio:>9.3f} {100 * mode.std.damping_ratio:>7.3f} {mode.mpc:>5.2f}  "
                     f"{','.join(mode.flags) or '-'}")
    if not len(result):  # only machine tones: say so rather than print an empty table
        lines[1] = "no structural mode in the band"
    tones = ", ".join(f"{f:.4f}" for f in result.harmonics_hz) or "none"
    lines.append(f"machine tones [Hz]: {tones}")
    return "\n".join(lines)


def _doc(result, paths) -> dict:
    import numpy as np

    scaled = any(np.any(mode.driving_point) for mode in result)
    modes = []
    for k, mode in enumerate(result, start=1):
        entry = {"mode": k, "natural_frequency_hz": mode.natural_frequency_hz, "damping_ratio": mode.damping_ratio,
                 "std": {"natural_frequency_hz": mode.std.natural_frequency_hz,
                         "damping_ratio": mode.std.damping_ratio,
                         "mode_shape": [float(v) for v in (mode.std.mode_shape if mode.std.mode_shape is not None
                                                           else [])]},
                 "mode_shape": [complex(v) for v in mode.mode_shape], "mpc": mode.mpc, "flags": list(mode.flags)}
        if scaled:  # per channel, each channel a driving point of the mass-normalised shape
            for name in ("mass_kg", "stiffness_n_per_m", "damping_n_s_per_m"):
                entry[name] = [float(v) for v in np.atleast_1d(getattr(mode, name))]
                entry["std"][name] = [float(v) for v in np.atleast_1d(getattr(mode.std, name))]
        modes.append(entry)
    return {"file": paths[0] if len(paths) == 1 else list(paths), "method": result.method, "kind": result.kind,
            "n_channels": result.n_channels, "modes": modes, "harmonics_hz": list(result.harmonics_hz),
            "settings": dict(result.settings)}


def _kcm_table(result) -> str:
    """k, c, m of every mode at every channel (a mass-normalised result), with their standard errors."""
    names = list(result.settings.get("channel_names") or range(1, result.n_channels + 1))
    lines = [f"{'mode':>4} {'channel':>12} {'m [kg]':>11} {'±':>9} {'k [N/m]':>11} {'±':>9} {'c [N s/m]':>11} "
             f"{'±':>9}"]
    for k, mode in enumerate(result, start=1):
        for j in range(result.n_channels):
            values = [mode.mass_kg, mode.std.mass_kg, mode.stiffness_n_per_m, mode.std.stiffness_n_per_m,
                      mode.damping_n_s_per_m, mode.std.damping_n_s_per_m]
            cells = " ".join(f"{float(v[j]):>{11 if i % 2 == 0 else 9}.4g}" for i, v in enumerate(values))
            lines.append(f"{k:>4} {f'{j + 1} ({names[j]})':>12} {cells}")
    return "\n".join(lines)


def run_oma(args) -> int:
    """Run ``modal oma`` (errors propagate to :func:`modal.cli.main`, which prints them)."""
    from .errors import ParameterError, kept_warnings
    from .operational.files import OMAOptions
    from .report import jsonable

    options = OMAOptions.from_args(args)
    paths = list(args.path)
    if args.added_mass_kg and not args.mass_change:
        raise ParameterError("--added-mass-kg needs --mass-change AFTER (the record with the masses added)")
    with kept_warnings() as said:  # shown as they come, and kept for the JSON document and the archive
        result, results, items = _identify(args, paths, options)
    if args.json:
        json.dump(jsonable({**_doc(result, paths), "warnings": said}), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(_table(result, paths[0] if len(paths) == 1 else f"{paths[0]} (+{len(paths) - 1} setups)"))
        if args.mass_change:
            print(_kcm_table(result))
    if args.plot:
        _plot(results[0], paths[0], args)
    if args.archive:
        from .archive import write_archive

        write_archive(args.archive, {f"oma_{result.method}": result, **items},
                      warnings={f"oma_{result.method}": said})
        print(f"archive: {args.archive}", file=sys.stderr)
    return 0


def _identify(args, paths, options):
    """The result to report, every result identified (one per setup) and what else the archive holds."""
    from .errors import ParameterError
    from .operational.files import oma_file, oma_files, scale_files

    items = {}
    if args.mass_change:
        if len(paths) > 1:
            raise ParameterError(f"--mass-change scales one record; got {len(paths)} files (merge setups apart)")
        masses = {}
        for channel, kg in args.added_mass_kg or []:
            try:
                masses[channel] = masses.get(channel, 0.0) + float(kg)
            except ValueError:
                raise ParameterError(f"--added-mass-kg {channel} {kg}: expected a mass in kg") from None
        result, after = scale_files(paths[0], args.mass_change, masses, options)
        items = {"mass_change": after}
        results = [result]
    elif len(paths) > 1:
        result, results = oma_files(paths, options)
        items = {f"setup{k + 1}": r for k, r in enumerate(results)}
    else:
        result = oma_file(paths[0], options)
        results = [result]
    return result, results, items


def _plot(result, path, args) -> None:
    from .io._atomic import atomic_path
    from .io.timedata import read_time
    from .operational.fdd import singular_values
    from .operational.inputs import prepare
    from .operational.plots import plot_stabilisation

    prepared = prepare(read_time(path), band_hz=tuple(result.settings["band_hz"]), screen=False)
    lines, s1, *_ = singular_values(prepared, result.settings["reference_channels"])
    fig = plot_stabilisation(result, spectrum=(lines, s1)) if result.stabilisation is not None else None
    if fig is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(11, 5), layout="constrained")
        ax = fig.add_subplot()
        ax.semilogy(lines, s1, color="k", lw=0.8)
        for mode in result:
            ax.axvline(mode.natural_frequency_hz, color="tab:green", lw=0.8)
        for f in result.harmonics_hz:
            ax.axvline(f, color="0.4", lw=0.8, ls="--")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("first singular value of the half-spectra")
    target = Path(args.plot)
    with atomic_path(target) as tmp:
        fig.savefig(tmp, dpi=110, format=target.suffix.lstrip(".") or "png")
    print(f"plot: {target}", file=sys.stderr)
