"""FRF estimation side by side with pyFRF: run time against error, and what each does with lab mistakes.

Run ``python -m benchmarks.bench_pyfrf [--rounds N]`` (pyFRF is on the test extra).

1. Random excitation: 20 s of white force at 25.6 kHz, 8 accelerometers with 10 % noise, H1 with a Hann
   window, 4096-sample segments, half overlap, in both tools. CPU time per estimate (median of ``--rounds``
   rounds, the tools called in turn in each round) and the relative error of H1 against the exact FRF of the
   digital system, median and 95th percentile over the lines from 200 Hz to 10 kHz.
2. Impact: six hits of a hammer on a two-mode structure, 2 s apart, 0.2 % noise on force and response,
   rectangular windows. pyFRF takes one record per hit (cut here at the known hit times, as a user cuts them);
   modalbal takes the continuous record and finds the hits. Same timing and error (lines in the hammer's band).
3. Lab mistakes on the impact record, each tool as its user would call it (pyFRF: ``is_data_ok`` on the
   records, then the FRF; modalbal: ``estimate_frf(..., impact=True)``): a rebound (double hit) on one hit,
   the force clipped at the recorder's full scale on one hit, force and response swapped. The table gives what
   each tool says and the error of the FRF it returns; the clean record first, as a control of false alarms.
"""
from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import modal
from modal.errors import ModalError
from modal.synthetic_time import DigitalModes, impact_record

RANDOM_FS = 25600
IMPACT_FS = 4096


def _pyfrf(fs, force, response, **kwargs):
    """pyFRF's H1, shape (n_outputs, n_lines) (its 0 Hz line is NaN: it divides by ω there)."""
    import pyFRF

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        frf = pyFRF.FRF(int(fs), exc=force, resp=response, exc_type="f", resp_type="a", **kwargs)
        # get_H1 converts to receptance; the accelerance (what both tools measure here) is asked for by name
        return frf, np.squeeze(frf.get_FRF(frf_estimator="H1", frf_form="accelerance"), axis=1)


def _cpu(call):
    start = time.process_time()
    out = call()
    return time.process_time() - start, out


def _errors(estimate, exact, lines):
    estimate, exact = np.atleast_2d(estimate), np.atleast_2d(exact)
    rel = np.abs(estimate[:, lines] - exact[:, lines]) / np.abs(exact[:, lines])
    return float(np.median(rel)), float(np.percentile(rel, 95))


def random_case(rounds: int) -> list[str]:
    rng = np.random.default_rng(0)
    system = DigitalModes([800.0, 2100.0, 5200.0], [0.02, 0.015, 0.01], rng.normal(size=(8, 3)) * 1e-3,
                          RANDOM_FS)
    force = rng.standard_normal(20 * RANDOM_FS)
    clean = system.respond(force, "acceleration")
    response = clean + 0.1 * clean.std(axis=1, keepdims=True) * rng.standard_normal(clean.shape)
    times = {"modalbal": [], "pyFRF 1.5": []}
    for _ in range(rounds):
        t, ours = _cpu(lambda: modal.estimate_frf(force, response, RANDOM_FS, window="hann", segment_length=4096,
                                                  overlap=0.5, kind="accelerance"))
        times["modalbal"].append(t)
        t, (_, theirs) = _cpu(lambda: _pyfrf(RANDOM_FS, force[None, None, :], response[None, :, :], window="hann",
                                             nperseg=4096, noverlap=2048, fft_len=4096))
        times["pyFRF 1.5"].append(t)
    exact = system.frf(ours.frequency_hz, "accelerance")
    lines = np.flatnonzero((ours.frequency_hz >= 200) & (ours.frequency_hz <= 10000))
    rows = []
    for name, estimate, extra in (("modalbal", ours.response, "coherence, noise per line, averages"),
                                  ("pyFRF 1.5", theirs, "coherence")):
        med, p95 = _errors(estimate, exact, lines)
        rows.append(f"| random, 20 s × 9 channels | {name} | {np.median(times[name]):.3f} "
                    f"[{min(times[name]):.3f}–{max(times[name]):.3f}] | {med:.1e} | {p95:.1e} | {extra} |")
    return rows


def _impact(**kwargs):
    system = DigitalModes([45.0, 160.0], [0.01, 0.02], [[1.0, 0.5]], IMPACT_FS)
    hits = 0.5 + 2.0 * np.arange(6)
    settings = dict(pulse_width_s=0.002, amplitude_variation=0.2, force_noise=0.002, response_noise=0.002, seed=3)
    rec = impact_record(system, hits, 12.5, **{**settings, **kwargs})
    return rec, hits


def _cut(signal, hits, length):
    """One record per hit from 10 ms before it, as a user cuts a continuous record for pyFRF."""
    starts = np.round((hits - 0.01) * IMPACT_FS).astype(int)
    return np.stack([signal[s:s + length] for s in starts])


def impact_case(rounds: int) -> list[str]:
    rec, hits = _impact()
    force, response = rec.record.signals[0], rec.record.signals[1]
    length = int(2.0 * IMPACT_FS) - 64
    times = {"modalbal": [], "pyFRF 1.5": []}
    for _ in range(rounds):
        t, ours = _cpu(lambda: modal.estimate_frf(force, response, IMPACT_FS, impact=True, window="rect",
                                                  segment_length=length, kind="accelerance"))
        times["modalbal"].append(t)
        t, (_, theirs) = _cpu(lambda: _pyfrf(IMPACT_FS, _cut(force, hits, length), _cut(response, hits, length),
                                             window="none"))
        times["pyFRF 1.5"].append(t)
    exact = rec.system.frf(ours.frequency_hz, "accelerance")
    lines = np.flatnonzero((ours.frequency_hz >= 5) & (ours.frequency_hz <= 300))
    rows = []
    for name, estimate, extra in (("modalbal", ours.response, "hits found, noise per line"),
                                  ("pyFRF 1.5", np.atleast_2d(theirs), "records cut by the user")):
        med, p95 = _errors(estimate, exact, lines)
        rows.append(f"| impact, 6 hits | {name} | {np.median(times[name]):.4f} "
                    f"[{min(times[name]):.4f}–{max(times[name]):.4f}] | {med:.1e} | {p95:.1e} | {extra} |")
    return rows


def _rebound():
    return _impact(rebound_delay_s=[None, None, 0.003, None, None, None])[0].record.signals


def _clipped():
    """A recorder's full scale set on softer hits: the hardest hit alone runs into it (a flat top)."""
    rec, hits = _impact()
    force = rec.record.signals[0]
    peaks = np.array([force[int(t * IMPACT_FS):int((t + 0.01) * IMPACT_FS)].max() for t in hits])
    rail = 0.5 * (np.sort(peaks)[-1] + np.sort(peaks)[-2])
    return np.vstack([np.clip(force, -rail, rail), rec.record.signals[1]])


def _swapped():
    return _impact()[0].record.signals[::-1]


MISTAKES = {"none (the clean record, as a control)": lambda: _impact()[0].record.signals,
            "rebound 3 ms after hit 3 (30 % of its peak)": _rebound,
            "force clipped on the hardest hit": _clipped,
            "force and response swapped": _swapped}


def mistakes() -> list[str]:
    length = int(2.0 * IMPACT_FS) - 64
    clean, hits = _impact()
    rows = []
    for name, make in MISTAKES.items():
        signals = make()
        force_records, response_records = _cut(signals[0], hits, length), _cut(signals[1], hits, length)
        frf, theirs = _pyfrf(IMPACT_FS, force_records, response_records, window="none")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ok = frf.is_data_ok(force_records, response_records)
            # the three checks is_data_ok combines, per record (its private helpers: it reports only one verdict)
            checks = {"force overflow": frf._is_overflow(force_records), "response overflow":
                      frf._is_overflow(response_records), "double impact": frf._is_double_impact(force_records)}
        fired = "; ".join(f"{check} in records {', '.join(str(k) for k in np.flatnonzero(hit) + 1)}" for check, hit in checks.items()
                          if np.any(hit))
        freq = frf.get_f_axis()
        lines = np.flatnonzero((freq >= 5) & (freq <= 300))
        their_error = _errors(theirs, clean.system.frf(freq, "accelerance"), lines)[0]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ours = modal.estimate_frf(signals[0], signals[1], IMPACT_FS, impact=True, window="rect",
                                          segment_length=length, kind="accelerance")
        except ModalError as error:
            said, our_error = f"refused: {str(error).split(' but ')[0]}", "—"
        else:
            lines = np.flatnonzero((ours.frequency_hz >= 5) & (ours.frequency_hz <= 300))
            reasons = "; ".join(f"hit at {r['time_s']:.2f} s rejected: {r['reason']}" for r in ours.rejected)
            said = f"{ours.averages} of 6 hits averaged" + (f" ({reasons})" if reasons else "")
            our_error = f"{_errors(ours.response, clean.system.frf(ours.frequency_hz, 'accelerance'), lines)[0]:.1e}"
        rows.append(f"| {name} | `is_data_ok` {ok} ({fired or 'no check fired'}); FRF of all 6 returned | "
                    f"{their_error:.1e} | {said} | {our_error} |")
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    print("| case | tool | CPU per estimate [s] | median rel. error | 95th pct rel. error | also returns |")
    print("|---|---|---|---|---|---|")
    for row in random_case(args.rounds) + impact_case(args.rounds):
        print(row)
    print("\n| lab mistake | pyFRF 1.5 | its FRF's median rel. error | modalbal | its FRF's median rel. error |")
    print("|---|---|---|---|---|")
    for row in mistakes():
        print(row)


if __name__ == "__main__":
    main()
