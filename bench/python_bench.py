#!/usr/bin/env python3
"""Benchmarks of the Python package in one run: open-loop plans per second from one and from
two Python threads (the GIL is released while planning), and a batch study's throughput as a
serial loop and on a 2-worker local Dask cluster. Prints each number beside the one in the
previous record (--previous) and writes the new record (--out).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py --out docs/benchmark_python.json
"""
import argparse
import json
import os
import pathlib
import platform
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import flatsos
import flatsos.study

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
OWN_REST = {"plan": {"a0": None, "qd0_deg_per_s": [0, 0]}, "strength": {"low": 0.8, "high": 1.2}}


def plans_per_second(model, scenario, plans, threads, repetitions):
    """The best of `repetitions` runs of `plans` plans shared by `threads` Python threads."""
    def one(_):
        return flatsos.plan_open_loop(model, *scenario).cost

    best = 0.0
    for _ in range(repetitions):
        start = time.perf_counter()
        with ThreadPoolExecutor(threads) as pool:
            costs = set(pool.map(one, range(plans)))
        best = max(best, plans / (time.perf_counter() - start))
        if len(costs) != 1:
            raise RuntimeError(f"{threads} threads planned different costs: {sorted(costs)}")
    return best


def threads_record(repetitions):
    record = {}
    cases = {
        "arm_open_loop": ("arm_richter_warner.json", (np.radians([0, 10]), [0, 0], None, np.radians([90, 0]), 3.0, 10.0), 200),
        "seated_knee_open_loop": ("seated_knee_r.json", (np.radians([90]), [0], None, np.radians([30]), 1.0, 10.0), 60),
    }
    for name, (file, scenario, plans) in cases.items():
        model = flatsos.Model(str(MODELS / file))
        one = plans_per_second(model, scenario, plans, 1, repetitions)
        two = plans_per_second(model, scenario, plans, 2, repetitions)
        record[name] = {"plans": plans, "one_thread_plans_per_s": one, "two_threads_plans_per_s": two,
                        "speedup": two / one}
    return record


def study_record(samples):
    from distributed import Client
    model = str(MODELS / "arm_richter_warner.json")
    serial = flatsos.study.run(model, OWN_REST, samples, workers=0)
    start = time.perf_counter()
    with flatsos.study.local_cluster(2) as cluster, Client(cluster) as client:
        started = time.perf_counter() - start
        on_cluster = flatsos.study.run(model, OWN_REST, samples, scheduler=client)
    same = all(np.array_equal(on_cluster.table()[c], serial.table()[c])
               for c in serial.study.columns() if c not in flatsos.study.TIMING_COLUMNS)
    if not same:
        raise RuntimeError("the cluster's table differs from the serial loop's")
    return {"samples": samples, "serial_plans_per_s": serial.summary["plans_per_second"],
            "cluster_2_workers_plans_per_s": on_cluster.summary["plans_per_second"],
            "speedup": on_cluster.summary["plans_per_second"] / serial.summary["plans_per_second"],
            "cluster_start_s": started}


def flatten(record, prefix=""):
    for key, value in record.items():
        if isinstance(value, dict):
            yield from flatten(value, f"{prefix}{key}.")
        elif isinstance(value, (int, float)):
            yield f"{prefix}{key}", value


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", help="write the record here (JSON)")
    parser.add_argument("--previous", default=str(ROOT / "docs" / "benchmark_python.json"),
                        help="the record to print beside (default docs/benchmark_python.json)")
    parser.add_argument("--samples", type=int, default=1000, help="plans of the study (default 1000)")
    parser.add_argument("--repetitions", type=int, default=3, help="runs per thread count, best kept (default 3)")
    args = parser.parse_args()
    if args.samples < 1 or args.repetitions < 1:
        parser.error("--samples and --repetitions must be >= 1")
    record = {"machine": {"cpu_count": os.cpu_count(), "python": platform.python_version()},
              "threads": threads_record(args.repetitions), "study": study_record(args.samples)}
    try:
        previous = dict(flatten(json.loads(pathlib.Path(args.previous).read_text())))
    except (OSError, json.JSONDecodeError):
        previous = {}
    for key, value in flatten(record):
        before = previous.get(key)
        print(f"{key:55s} {value:12.4g}" + (f"   (previous {before:.4g})" if before is not None else ""))
    if args.out:
        pathlib.Path(args.out).write_text(json.dumps(record, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
