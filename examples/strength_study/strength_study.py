#!/usr/bin/env python3
"""The paper's open-loop plan (the arm, [0, 10] -> [90, 0] deg in 3 s, the quartic flat outputs,
reserves 10 N, excitations kept in [0, 1]) for 1000 subjects whose muscles are each up to 20 %
weaker or stronger, in two studies: from the paper's initial activations (paper_start.json) and
from each subject's own minimum-effort rest (own_rest.json). Runs both on Dask, writes
OUT/<study>/table.csv and summary.json, and draws OUT/strength_study.png: how often the plan
stays feasible, which muscles decide it, and how cost and peak activation spread.
"""
import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import flatsos.study  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
STUDIES = {"paper_start": "from the paper's initial activations", "own_rest": "from each subject's own rest"}
STATUS_COLORS = {"solved": "tab:green", "infeasible": "tab:orange", "failed": "tab:red"}


def draw(results, nominal_cost, path):
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for k, (name, result) in enumerate(results.items()):
        counts = result.summary["statuses"]
        left = 0.0
        for status, color in STATUS_COLORS.items():
            share = counts.get(status, 0) / result.summary["samples"]
            ax[0, 0].barh(k, share, left=left, color=color, label=status if k == 0 else None)
            if share > 0.04:
                ax[0, 0].text(left + share / 2, k, f"{100 * share:.0f} %", ha="center", va="center")
            left += share
    ax[0, 0].set_yticks(range(len(results)), [STUDIES[n] for n in results])
    ax[0, 0].set_xlabel("share of the plans")
    ax[0, 0].set_title("outcome: each maximum force x U(0.8, 1.2)")
    ax[0, 0].legend(loc="lower right", fontsize=8)

    paper = results["paper_start"]
    t = paper.table()
    solved = t["status"] == "solved"
    bins = np.linspace(0.8, 1.2, 9)
    centers = 0.5 * (bins[1:] + bins[:-1])
    for muscle in paper.study.muscles:
        f = t[f"strength_{muscle}"]
        share = [solved[(f >= lo) & (f < hi)].mean() if ((f >= lo) & (f < hi)).any() else np.nan
                 for lo, hi in zip(bins[:-1], bins[1:])]
        ax[0, 1].plot(centers, share, "o-", label=muscle)
    ax[0, 1].set_xlabel("the muscle's strength factor")
    ax[0, 1].set_ylabel("share solved")
    ax[0, 1].set_title("from the paper's activations: who decides")
    ax[0, 1].legend(fontsize=7)

    for k, (name, result) in enumerate(results.items()):
        t = result.table()
        ok = t["status"] == "solved"
        if not ok.any():
            continue
        ax[1, 0].hist(t["peak_activation"][ok], bins=40, alpha=0.6, label=STUDIES[name])
        change = 100.0 * (t["cost_Ns"][ok] / nominal_cost[name] - 1.0)
        ax[1, 1].hist(change, bins=40, alpha=0.6, label=f"{STUDIES[name]}: {nominal_cost[name]:.2f} N s nominal")
        ax[1, 1].text(0.98, 0.6 - 0.1 * k, f"{STUDIES[name]}: {change.min():+.2g} to {change.max():+.2g} %",
                      transform=ax[1, 1].transAxes, ha="right", fontsize=8)
    ax[1, 0].set_xlabel("peak activation over the plan")
    ax[1, 0].set_ylabel("plans")
    ax[1, 0].set_title("what strength changes: the activations")
    ax[1, 0].legend(fontsize=8)
    ax[1, 1].set_xlabel("cost change from the nominal arm's plan, %")
    ax[1, 1].set_ylabel("plans")
    ax[1, 1].set_title("the effort (tendon force): set by the start")
    ax[1, 1].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default=str(HERE.parents[1] / "models" / "arm_richter_warner.json"),
                        help="model file (default: the paper's arm)")
    parser.add_argument("--samples", type=int, default=1000, help="subjects per study (default 1000)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes (default 2; 0: serial)")
    parser.add_argument("--out", default="results/strength_study", help="output folder")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    results, nominal_cost = {}, {}
    try:
        for name in STUDIES:
            description = json.loads((HERE / f"{name}.json").read_text())
            results[name] = flatsos.study.run(args.model, description, args.samples, scheduler=args.scheduler,
                                              workers=args.workers, progress=True)
            results[name].write(out / name)
            nominal = flatsos.study.run(args.model, dict(description, strength={"low": 1.0, "high": 1.0}), 1,
                                        workers=0)
            nominal_cost[name] = nominal.rows[0]["cost_Ns"]
            s = results[name].summary
            print(f"{name}: {s['statuses']} in {s['wall_seconds']:.1f} s ({s['plans_per_second']:.0f} plans/s)")
    except ValueError as e:
        print(f"strength_study: error: {e}", file=sys.stderr)
        return 2
    draw(results, nominal_cost, out / "strength_study.png")
    print(f"strength_study: wrote {out}/{{paper_start,own_rest}}/table.csv, summary.json and strength_study.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
