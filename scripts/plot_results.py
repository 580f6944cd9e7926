#!/usr/bin/env python3
"""Figures (PNG) of the paper's scenarios from the files the examples write.

Usage: plot_results.py RESULTS_DIR
Reads RESULTS_DIR/open_loop/{plan,simulation}.sto and RESULTS_DIR/receding_horizon/
{simulation,predictions}.sto; writes the PNG figures into the same folders.
"""
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_sto(path):
    """OpenSim storage: header up to 'endheader', then tab-separated labels and rows."""
    with open(path) as f:
        lines = f.read().splitlines()
    start = lines.index("endheader") + 1
    labels = lines[start].split("\t")
    columns = {label: [] for label in labels}
    for line in lines[start + 1:]:
        if not line:
            continue
        for label, cell in zip(labels, line.split("\t")):
            columns[label].append(float(cell))
    return columns


def names(table, prefix, suffix):
    return [c[len(prefix):-len(suffix)] for c in table if c.startswith(prefix) and c.endswith(suffix)]


def deg(values):
    return [v * 180.0 / math.pi for v in values]


def open_loop(folder):
    plan = read_sto(os.path.join(folder, "plan.sto"))
    sim = read_sto(os.path.join(folder, "simulation.sto"))
    muscles = names(plan, "/forceset/", "/activation")
    joints = names(plan, "/jointset/", "/q")

    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True)
    for ax, m in zip(axes.flat, muscles):
        base = "/forceset/" + m + "/"
        ax.plot(plan["time"], plan[base + "excitation"], "--", color="tab:gray", label="planned excitation n")
        ax.plot(plan["time"], plan[base + "activation"], color="tab:blue", label="planned activation a")
        ax.plot(sim["time"][::10], sim[base + "activation"][::10], "o", ms=3, color="tab:red",
                label="Simbody, open loop")
        ax.set_title(m.replace("_", " "))
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("Open loop: planned vs simulated activations, with the planned excitations")
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "open_loop_activations.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for j in joints:
        axes[0].plot(plan["time"], deg(plan["/jointset/" + j + "/q"]), label=j + " planned")
        axes[0].plot(sim["time"][::10], deg(sim["/jointset/" + j + "/q"][::10]), "o", ms=3, label=j + " simulated")
    axes[0].set_ylabel("joint angle (deg)")
    for m in muscles:
        axes[1].plot(plan["time"], plan["/forceset/" + m + "/tendon_force"], label=m.replace("_", " "))
    axes[1].set_ylabel("planned tendon force (N)")
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Open loop: joint angles and tendon forces (reserve 10 N)")
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "open_loop_joints_forces.png"), dpi=110)
    plt.close(fig)


def receding_horizon(folder):
    sim = read_sto(os.path.join(folder, "simulation.sto"))
    pred = read_sto(os.path.join(folder, "predictions.sto"))
    joints = names(sim, "/jointset/", "/q")
    muscles = names(sim, "/forceset/", "/activation")

    fig, ax = plt.subplots(figsize=(8, 4.5))
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    steps = pred["/controller/step"]
    for color, j in zip(colors, joints):
        key = "/jointset/" + j + "/q_predicted"
        for step in sorted(set(steps)):
            idx = [i for i, s in enumerate(steps) if s == step]
            ax.plot([pred["time"][i] for i in idx], deg([pred[key][i] for i in idx]), color=color, lw=0.6, alpha=0.35)
        ax.plot(sim["time"], deg(sim["/jointset/" + j + "/q"]), color=color, lw=2, label=j + " closed loop")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("joint angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title("Receding horizon: closed-loop joint angles and each step's predicted path (thin)")
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "rh_joint_angles.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharex=True)
    for ax, m in zip(axes.flat, muscles):
        base = "/forceset/" + m + "/"
        ax.plot(sim["time"], sim[base + "excitation"], color="tab:gray", lw=0.8, label="excitation n")
        ax.plot(sim["time"], sim[base + "activation"], color="tab:blue", label="activation a")
        ax.set_title(m.replace("_", " "))
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    axes[0][0].legend(fontsize=8)
    fig.suptitle("Receding horizon: activations and excitations")
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "rh_activations.png"), dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) == 2 else 2
    root = sys.argv[1]
    made = 0
    if os.path.exists(os.path.join(root, "open_loop", "simulation.sto")):
        open_loop(os.path.join(root, "open_loop"))
        made += 2
    if os.path.exists(os.path.join(root, "receding_horizon", "simulation.sto")):
        receding_horizon(os.path.join(root, "receding_horizon"))
        made += 2
    print("plot_results: %d figures in %s" % (made, root))
    return 0 if made else 1


if __name__ == "__main__":
    sys.exit(main())
