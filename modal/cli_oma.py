"""Command-line glue of ``python -m modal oma TIME_FILE...``: operational modal analysis of ambient records.

One file: one record, identified. Several files: one setup each (roving sensors with shared
references), identified apart and merged over ``--reference-channels``.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["add_oma_parser", "run_oma"]


def add_oma_parser(sub) -> argparse.ArgumentParser:
    from .operational import OMA_METHODS

    oma = sub.add_parser("oma", help="operational modal analysis of ambient response records (no force channel)",
                         description="Identify natural frequency, damping ratio and shape of every mode from "
                                     "response records alone, with standard errors; machine tones listed apart.")
    oma.add_argument("path", nargs="+", help="time file(s) (UFF 58/58b function type 1, CSV with a time column, "
                     "MAT, HDF5); several files are setups sharing --reference-channels, merged")
    oma.add_argument("--band", nargs=2, type=float, metavar=("FMIN", "FMAX"),
                     help="band of interest in Hz (default: 0 Hz to 80 %% of the Nyquist frequency)")
    oma.add_argument("--method", choices=OMA_METHODS, default="ssi",
                     help="ssi: covariance-driven stochastic subspace identification (default); plscf: "
                          "poly-reference LSCF on half-spectra (a cross-check); fdd, efdd: quick looks")
    oma.add_argument("--reference-channels", dest="reference_channels", type=int, nargs="+", metavar="CH",
                     help="reference (projection) channels, 0-based; with several files, the references every "
                          "setup shares, at these indices in each (default: chosen from the data)")
    oma.add_argument("--rotor-speed-hz", dest="rotor_speed_hz", type=float, metavar="F",
                     help="running speed: poles on its harmonics are tones or flagged 'harmonic'")
    oma.add_argument("--max-order", dest="max_order", type=int, metavar="N", help="highest model order (default 80)")
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
    tones = ", ".join(f"{f:.4f}" for f in result.harmonics_hz) or "none"
    lines.append(f"machine tones [Hz]: {tones}")
    return "\n".join(lines)


def _doc(result, paths) -> dict:
    modes = []
    for k, mode in enumerate(result, start=1):
        modes.append({"mode": k, "natural_frequency_hz": mode.natural_frequency_hz,
                      "damping_ratio": mode.damping_ratio,
                      "std": {"natural_frequency_hz": mode.std.natural_frequency_hz,
                              "damping_ratio": mode.std.damping_ratio,
                              "mode_shape": [float(v) for v in (mode.std.mode_shape if mode.std.mode_shape is not None
                                                                else [])]},
                      "mode_shape": [complex(v) for v in mode.mode_shape], "mpc": mode.mpc,
                      "flags": list(mode.flags)})
    settings = {k: v for k, v in result.settings.items()}
    return {"file": paths[0] if len(paths) == 1 else list(paths), "method": result.method, "kind": result.kind,
            "n_channels": result.n_channels, "modes": modes, "harmonics_hz": list(result.harmonics_hz),
            "settings": settings}


def run_oma(args) -> int:
    """Run ``modal oma`` (errors propagate to :func:`modal.cli.main`, which prints them)."""
    from .errors import ParameterError
    from .io.timedata import read_time
    from .operational import merge_setups, oma
    from .report import jsonable

    paths = list(args.path)
    if len(paths) > 1 and not args.reference_channels:
        raise ParameterError(f"{len(paths)} files are setups to merge; give the references they share with "
                             "--reference-channels CH ...")
    records = [read_time(p) for p in paths]
    band = tuple(args.band) if args.band else None
    results = [oma(r, band_hz=band, method=args.method, reference_channels=args.reference_channels,
                   rotor_speed_hz=args.rotor_speed_hz, max_order=args.max_order) for r in records]
    result = results[0] if len(results) == 1 else merge_setups(results, args.reference_channels)
    if args.json:
        json.dump(jsonable(_doc(result, paths)), sys.stdout, indent=1, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(_table(result, paths[0] if len(paths) == 1 else f"{paths[0]} (+{len(paths) - 1} setups)"))
    if args.plot:
        _plot(results[0], records[0], args)
    if args.archive:
        from .archive import write_archive

        items = {f"oma_{result.method}": result}
        if len(results) > 1:
            items.update({f"setup{k + 1}": r for k, r in enumerate(results)})
        write_archive(args.archive, items)
        print(f"archive: {args.archive}", file=sys.stderr)
    return 0


def _plot(result, record, args) -> None:
    from .io._atomic import atomic_path
    from .operational.fdd import singular_values
    from .operational.inputs import prepare
    from .operational.plots import plot_stabilisation

    prepared = prepare(record, band_hz=tuple(result.settings["band_hz"]))
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
