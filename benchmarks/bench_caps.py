"""The caps on identify's work: pathological FRFs with the default budget against no budget.

Run ``python -m benchmarks.bench_caps [--cases 40:10000:random:auto ...] [--timeout S] [--runs N] [--default-only]``.
Each case is ``MODES:LINES:VARIANT:METHOD[:OPTION=VALUE]`` (:func:`support.manymodes.many_modes_frf`; an option
of ``identify`` such as ``max_order=644``); each run is ``identify`` in a fresh single-threaded process
(``OPENBLAS_NUM_THREADS=1``, as the batch's workers run), once with the default budget (``max_evaluations``
scaled to the size of one evaluation) and once without one (``max_evaluations=10**9``, the work identify did
before the cap; not with ``--default-only``), interleaved. Rows: wall time (median of the runs), the peak memory
``identify`` allocated (traced: numpy's arrays; the synthesised FRF before it is not counted) and the process's
peak resident memory, the evaluations used against the budget, the method run, the modes found and those
flagged ``work_capped``, the order the peaks call for, and the global sweep's lines; a run past ``--timeout``
is listed as such. The machine's load is printed: timings on a loaded machine are noisy.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: the issue's cases: 40 modes on 10 000 lines that the global method refits again and again, the batch tests'
#: slow file, and the 400-mode 200 000-line FRF, by the global method (auto) and band-wise (nls)
CASES = ("40:10000:random:auto", "150:60000:even:auto", "100:50000:even:nls", "400:200000:even:auto",
         "400:200000:even:nls", "400:200000:even:global", "400:200000:even:global:max_order=644",
         "100:50000:even:halfpower", "100:50000:even:circle")
UNCAPPED = 10**9

_CHILD = """
import json, resource, sys, time, tracemalloc, warnings
sys.path.insert(0, {tests!r})
from support.manymodes import many_modes_frf
from modal import identify
n, lines, variant, method, *options = {case!r}.split(":")
options = {{k: int(v) for k, v in (o.split("=") for o in options)}}
frf = many_modes_frf(int(n), int(lines), variant)
tracemalloc.start()
start = time.perf_counter()
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    try:
        result = identify(frf, method, max_evaluations={budget!r}, **options)
    except Exception as error:  # a library error (no stable pole ...): its line, with the time it took
        print(json.dumps({{"failed": str(error).split(";")[0][-70:], "time_s": time.perf_counter() - start,
                          "identify_mb": tracemalloc.get_traced_memory()[1] / 2**20}}))
        raise SystemExit(0)
elapsed = time.perf_counter() - start
print(json.dumps({{"time_s": elapsed, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "identify_mb": tracemalloc.get_traced_memory()[1] / 2**20,
                  "method": result.method, "modes": len(result.modes),
                  "capped": sum("work_capped" in m.flags for m in result.modes),
                  "evaluations": result.settings.get("evaluations"), "max": result.settings.get("max_evaluations"),
                  "order_wanted": result.settings.get("order_wanted"),
                  "sweep_lines": result.settings.get("sweep_lines")}}))
"""


def run_case(case: str, budget: int | None, timeout: float) -> dict:
    """One ``identify`` of ``case`` in a fresh process: its figures, or ``{"timed_out": True}``."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    code = _CHILD.format(tests=str(ROOT / "tests"), case=case, budget=budget)
    start = time.perf_counter()
    try:
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout,
                              env=env, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return {"timed_out": True, "time_s": time.perf_counter() - start}
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit {done.returncode}"}
    return json.loads(done.stdout.strip().splitlines()[-1])


def table(cases, runs: int, timeout: float, default_only: bool = False) -> list[str]:
    rows = ["| case (modes:lines:variant:method) | budget | time s (median) | identify MB | process MB | "
            "evaluations / budget | method | modes | work_capped | order wanted | sweep lines |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for case in cases:
        results = {"default": []} if default_only else {"default": [], "none": []}
        for _ in range(runs):  # interleaved: the load shifts between them alike
            for label, found in results.items():
                found.append(run_case(case, None if label == "default" else UNCAPPED, timeout))
        for label, found in results.items():
            last = found[-1]
            median = statistics.median(r.get("time_s", float("nan")) for r in found)
            if "error" in last:
                rows.append(f"| {case} | {label} | error: {last['error']} | | | | | | | | |")
            elif any(r.get("timed_out") for r in found):
                rows.append(f"| {case} | {label} | > {timeout:.0f} (timed out) | | | | | | | | |")
            elif "failed" in last:
                rows.append(f"| {case} | {label} | {median:.1f} | {last['identify_mb']:.0f} | | | failed: "
                            f"{last['failed']} | | | | |")
            else:
                rows.append(f"| {case} | {label} | {median:.1f} | {last['identify_mb']:.0f} | {last['peak_mb']:.0f} | "
                            f"{last['evaluations']} / {last['max']} | {last['method']} | {last['modes']} | "
                            f"{last['capped']} | {last['order_wanted']} | {last['sweep_lines']} |")
        print(*rows[-len(results):], sep="\n", flush=True)
    return rows


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=list(CASES))
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds a run may take (default 600)")
    parser.add_argument("--default-only", action="store_true", help="only the default budget (no uncapped runs)")
    args = parser.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    table(args.cases, args.runs, args.timeout, args.default_only)
    print(f"load average {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
