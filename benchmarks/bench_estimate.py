"""FRFs from time data: estimate time per channel-second, a long record streamed from disk, and the
identification error on estimated FRFs against exact FRFs with the same noise.

Run ``python -m benchmarks.bench_estimate [--quick] [--minutes M]``.

1. Throughput: H1 with a Hann window, 50 % overlap, 4096-sample segments, 1 force + 8 responses at
   25.6 kHz, in memory: seconds of compute per channel-second of data.
2. Streaming: the same on a 10-minute 8-response record (``--minutes``; 1 with ``--quick``) held in a
   ``np.memmap`` on disk: wall time and the peak of Python-allocated memory (tracemalloc), against the
   record's size.
3. Identification: three modes excited by random force, 10 % output noise; ``identify`` on the H1
   estimate (which carries its noise per line) against ``identify`` on the exact FRF plus circular
   complex noise of the estimate's own ``noise_std`` — the same information, without the estimator.
"""
from __future__ import annotations

import argparse
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
from scipy import signal

import modal

FS = 25600.0


def resonators(fn_hz, zeta, gains, fs):
    """Digital resonators by impulse invariance (exact poles), one output per row of ``gains``."""
    sections = []
    T = 1.0 / fs
    for f, z in zip(fn_hz, zeta):
        w = 2 * np.pi * f
        p = -z * w + 1j * w * np.sqrt(1 - z**2)
        R = 1.0 / (2j * p.imag)
        zp = np.exp(p * T)
        sections.append((T * np.array([2 * R.real, -2 * (R * zp.conj()).real]),
                         np.array([1.0, -2 * zp.real, abs(zp) ** 2])))
    return sections, np.atleast_2d(gains)


def respond(system, force):
    sections, gains = system
    modes = np.array([signal.lfilter(b, a, force) for b, a in sections])
    return gains @ modes


def truth(system, frequency_hz, fs):
    sections, gains = system
    w = 2 * np.pi * np.asarray(frequency_hz) / fs
    return gains @ np.array([signal.freqz(b, a, worN=w)[1] for b, a in sections])


def throughput(seconds: float = 20.0) -> None:
    rng = np.random.default_rng(0)
    n = int(seconds * FS)
    force = rng.standard_normal(n)
    system = resonators([800.0, 2100.0, 5200.0], [0.02, 0.015, 0.01], rng.normal(size=(8, 3)), FS)
    resp = respond(system, force)
    start = time.perf_counter()
    modal.estimate_frf(force, resp, FS, segment_length=4096)
    elapsed = time.perf_counter() - start
    channel_seconds = 9 * seconds
    print(f"| in memory, {seconds:g} s x 9 channels | {elapsed:.3f} s | {elapsed / channel_seconds * 1e3:.2f} ms per "
          f"channel-second |")


def streaming(minutes: float) -> None:
    rng = np.random.default_rng(1)
    n = int(minutes * 60 * FS)
    system = resonators([800.0, 2100.0, 5200.0], [0.02, 0.015, 0.01], rng.normal(size=(8, 3)), FS)
    with tempfile.TemporaryDirectory() as folder:
        force_path, resp_path = Path(folder) / "force.dat", Path(folder) / "resp.dat"
        force = np.memmap(force_path, dtype=float, mode="w+", shape=(n,))
        resp = np.memmap(resp_path, dtype=float, mode="w+", shape=(8, n))
        chunk = int(30 * FS)
        zi = None
        for first in range(0, n, chunk):  # write the record a chunk at a time (filter state carried)
            f = rng.standard_normal(min(chunk, n - first))
            force[first:first + f.size] = f
            sections, gains = system
            if zi is None:
                zi = [np.zeros(2) for _ in sections]
            modes = []
            for k, (b, a) in enumerate(sections):
                y, zi[k] = signal.lfilter(b, a, f, zi=zi[k])
                modes.append(y)
            resp[:, first:first + f.size] = gains @ np.array(modes)
        force.flush()
        resp.flush()
        del force, resp
        size_mb = 9 * n * 8 / 2**20
        force = np.memmap(force_path, dtype=float, mode="r", shape=(n,))
        resp = np.memmap(resp_path, dtype=float, mode="r", shape=(8, n))
        tracemalloc.start()
        start = time.perf_counter()
        est = modal.estimate_frf(force, resp, FS, segment_length=4096)
        elapsed = time.perf_counter() - start
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    print(f"| memmap, {minutes:g} min x 9 channels ({size_mb:.0f} MB on disk) | {elapsed:.2f} s | peak Python memory "
          f"{peak / 2**20:.0f} MB; {est.averages} averages |")


def identification(seeds: int = 20) -> None:
    fs = 2048.0
    fn, zeta = np.array([90.0, 210.0, 380.0]), np.array([0.02, 0.015, 0.01])
    system = resonators(fn, zeta, np.array([[1.0, 0.6, 0.4]]), fs)
    errors = {"estimate": [], "exact + same noise": []}
    for seed in range(seeds):
        rng = np.random.default_rng(100 + seed)
        force = rng.standard_normal(2**18)
        clean = respond(system, force)
        noisy = clean + 0.1 * clean.std() * rng.standard_normal(clean.shape)
        est = modal.estimate_frf(force, noisy, fs, segment_length=8192)
        exact = truth(system, est.frequency_hz, fs)[0]
        noise = est.noise_std * (rng.standard_normal(exact.size) + 1j * rng.standard_normal(exact.size)) / np.sqrt(2)
        twin = modal.FRF(est.frequency_hz, exact + noise)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for name, frf in (("estimate", est), ("exact + same noise", twin)):
                result = modal.identify(frf, bands_hz=[(f * 0.85, f * 1.15) for f in fn])
                errors[name].append([[abs(m.natural_frequency_hz / f - 1), abs(m.damping_ratio / z - 1)]
                                     for m, f, z in zip(result, fn, zeta)])
    for name, e in errors.items():
        e = np.array(e)  # (seeds, modes, 2)
        print(f"| {name} | {np.median(e[..., 0]):.1e} | {e[..., 0].max():.1e} | {np.median(e[..., 1]):.1e} | "
              f"{e[..., 1].max():.1e} |")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--minutes", type=float, default=10.0)
    args = parser.parse_args(argv)
    print("| case | time | per unit |\n|---|---|---|")
    throughput(5.0 if args.quick else 20.0)
    streaming(1.0 if args.quick else args.minutes)
    print("\nIdentification (3 modes, random force, 10 % output noise, H1, 8192-sample Hann segments, bands "
          f"given), {5 if args.quick else 20} seeds; relative errors:\n")
    print("| FRF | median fn err | max fn err | median ζ err | max ζ err |\n|---|---|---|---|---|")
    identification(5 if args.quick else 20)


if __name__ == "__main__":
    main()
