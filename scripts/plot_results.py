#!/usr/bin/env python3
"""Figures (PNG) of what the flatsos programs write, for any model.

Usage: plot_results.py [--report-scales] PATH [PATH ...]

Each PATH is one program's output folder, or a folder whose immediate subfolders are such
folders (e.g. the demo's results/ with open_loop/ and receding_horizon/). The kind of output is
told by the files present, and the figures are written into that output folder:
  arm_open_loop         plan.sto + simulation.sto
                        -> open_loop_activations.png, open_loop_joints_forces.png
  arm_receding_horizon  simulation.sto + predictions/
                        -> rh_joint_angles.png, rh_activations.png
  arm_forward           states.sto
                        -> forward_states.png
Controls files (plan_controls.sto, simulation_controls.sto, controls.sto) and summary.json are
drawn from when present. Joints and muscles are found from the column names. All
activation/excitation panels of a figure share one y-axis that starts at 0 (or below, if a
planned excitation is negative), so a nearly silent muscle looks nearly silent.

Options:
  -h, --help        print this text and exit
  --report-scales   after each figure's line, print a JSON line with the y-limits of its
                    activation/excitation panels (for tests)

Exit status: 0 figures written; 1 a missing path, a malformed file or nothing to plot (the
message names the file); 2 bad usage.
"""
import glob
import json
import math
import os
import sys
import tempfile

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.gridspec import GridSpec  # noqa: E402

DPI = 110
MAX_COLUMNS = 3  # muscle panels per row
# Drawing order: thick lines and references under, the thin line that could vanish on top.
ZORDER_UNDER, ZORDER_MIDDLE, ZORDER_OVER = 1, 2, 3
# Tops of the shared activation axis: the smallest that holds the data. The smallest top, 0.1,
# keeps an almost silent muscle (a ~ 0.002) near the bottom instead of filling its panel.
ACTIVATION_TOPS = (0.1, 0.2, 0.5, 1.0)


class PlotError(Exception):
    """A problem the user must fix (missing or malformed input); the message names the file."""


# ---------------------------------------------------------------- reading

class Table:
    """One .sto file: its path, its header's key=value pairs and its columns by label."""

    def __init__(self, path, header, labels, data):
        self.path, self.header, self.labels = path, header, labels
        self.columns = {label: data[:, i] for i, label in enumerate(labels)}

    @property
    def time(self):
        return self.columns["time"]

    def __getitem__(self, label):
        if label not in self.columns:
            raise PlotError("%s: no column '%s'" % (self.path, label))
        return self.columns[label]


def read_sto(path):
    """OpenSim storage: header lines up to 'endheader', then tab-separated labels and rows."""
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise PlotError("%s: cannot read: %s" % (path, e))
    if "endheader" not in lines:
        raise PlotError("%s: not an OpenSim storage file (no 'endheader' line)" % path)
    end = lines.index("endheader")
    header = dict(line.split("=", 1) for line in lines[:end] if "=" in line)
    if end + 1 >= len(lines) or not lines[end + 1].strip():
        raise PlotError("%s: no column labels after 'endheader'" % path)
    labels = lines[end + 1].split("\t")
    if labels[0] != "time":
        raise PlotError("%s: the first column is '%s', not 'time'" % (path, labels[0]))
    if len(set(labels)) != len(labels):
        raise PlotError("%s: repeated column labels" % path)
    rows = []
    for number, line in enumerate(lines[end + 2:], start=end + 3):
        if not line.strip():
            continue
        cells = line.split("\t")
        if len(cells) != len(labels):
            raise PlotError("%s: line %d has %d cells, the labels %d" % (path, number, len(cells), len(labels)))
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            raise PlotError("%s: line %d: a cell is not a number" % (path, number))
    if not rows:
        raise PlotError("%s: no data rows" % path)
    # The programs write nRows; fewer rows means a truncated file, which would plot as a lie.
    if header.get("nRows", "").isdigit() and int(header["nRows"]) != len(rows):
        raise PlotError("%s: header says nRows=%s, found %d rows" % (path, header["nRows"], len(rows)))
    return Table(path, header, labels, np.array(rows))


def read_optional_sto(path):
    return read_sto(path) if os.path.exists(path) else None


def read_summary(folder):
    """summary.json as a dict, or {} if the folder has none."""
    path = os.path.join(folder, "summary.json")
    if not os.path.exists(path):
        return {}
    try:
        with open(path) as f:
            summary = json.load(f)
    except (OSError, ValueError) as e:
        raise PlotError("%s: cannot read JSON: %s" % (path, e))
    if not isinstance(summary, dict):
        raise PlotError("%s: not a JSON object" % path)
    return summary


def summary_input(summary, key, count):
    """summary['inputs'][key] if it is a list of `count` numbers (one per joint/muscle), else None."""
    inputs = summary.get("inputs")
    value = inputs.get(key) if isinstance(inputs, dict) else None
    if isinstance(value, list) and len(value) == count and all(isinstance(v, (int, float)) for v in value):
        return value
    return None


# ---------------------------------------------------------------- model discovery

def joints_of(table):
    """Coordinate column prefixes '/jointset/<joint>/<coordinate>' in column order."""
    found = [label[:-len("/value")] for label in table.labels
             if label.startswith("/jointset/") and label.endswith("/value")]
    if not found:
        raise PlotError("%s: no joint columns (/jointset/<joint>/<coordinate>/value)" % table.path)
    return found


def muscles_of(table):
    """Muscle names from '/forceset/<muscle>/activation' in column order."""
    found = [label[len("/forceset/"):-len("/activation")] for label in table.labels
             if label.startswith("/forceset/") and label.endswith("/activation")]
    if not found:
        raise PlotError("%s: no muscle columns (/forceset/<muscle>/activation)" % table.path)
    return found


def joint_name(prefix):
    return prefix.rsplit("/", 1)[-1].replace("_", " ")


def muscle_name(muscle):
    return muscle.replace("_", " ")


def require_same(reference, other, found, what):
    """The second file must describe the model of the first (e.g. plan vs simulation)."""
    if other is not None and found(other) != found(reference):
        raise PlotError("%s: its %s differ from those of %s" % (other.path, what, reference.path))


def excitation(controls, muscle):
    return controls["/forceset/" + muscle] if controls is not None else None


# ---------------------------------------------------------------- drawing helpers

def shared_activation_limits(series):
    """One (bottom, top) for every activation/excitation panel of a figure: from 0 (or from a
    negative planned excitation, shown honestly) to the smallest ACTIVATION_TOPS entry holding
    the data, or just above the data if it exceeds 1."""
    values = np.concatenate([np.asarray(s, dtype=float).ravel() for s in series])
    values = values[np.isfinite(values)]
    low, high = (values.min(), values.max()) if values.size else (0.0, 0.0)
    top = next((t for t in ACTIVATION_TOPS if high * 1.02 <= t), high * 1.05)
    bottom = 0.0 if low >= 0 else low - 0.03 * (top - low)
    return bottom, top


def muscle_grid(fig, gridspec, count, first_row=0):
    """Axes for `count` muscle panels, up to MAX_COLUMNS per row, x shared; the x label only
    under the panels with no panel below."""
    columns = min(MAX_COLUMNS, count)
    axes = []
    for i in range(count):
        ax = fig.add_subplot(gridspec[first_row + i // columns, i % columns],
                             sharex=axes[0] if axes else None)
        if i + columns >= count:
            ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        axes.append(ax)
    return axes


def grid_shape(count):
    columns = min(MAX_COLUMNS, count)
    return math.ceil(count / columns), columns


def plot_activations(axes, muscles, states, controls, excitation_style, excitation_label):
    """Per muscle panel: the activation, thick, and the excitation (when the controls have it) thin
    on top of it, so that neither hides the other; returns the plotted series for the shared scale."""
    series = []
    for ax, m in zip(axes, muscles):
        a = states["/forceset/%s/activation" % m]
        ax.plot(states.time, a, color="tab:blue", lw=2.5, alpha=0.6, zorder=ZORDER_UNDER, label="activation")
        series.append(a)
        n = excitation(controls, m)
        if n is not None:
            ax.plot(controls.time, n, label=excitation_label, zorder=ZORDER_OVER, **excitation_style)
            series.append(n)
    return series


def finish_muscle_panels(axes, muscles, series):
    """Titles, one shared y scale and the legend; returns {muscle: [bottom, top]} as drawn."""
    bottom, top = shared_activation_limits(series)
    for ax, muscle in zip(axes, muscles):
        ax.set_title(muscle_name(muscle), fontsize=10)
        ax.set_ylim(bottom, top)
    axes[0].legend(fontsize=7, loc="best")
    return {m: [float(v) for v in ax.get_ylim()] for m, ax in zip(muscles, axes)}


def save(fig, folder, name, scales, report):
    """Write the PNG under a temporary name in the same folder, then rename it, so that a
    failure never leaves a half-written figure under the real name."""
    path = os.path.join(folder, name)
    fd, temporary = tempfile.mkstemp(prefix="." + name + ".", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            fig.savefig(f, format="png", dpi=DPI)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
    finally:
        plt.close(fig)
    print("plot_results: wrote %s" % path)
    if report:
        print(json.dumps({"figure": path, "activation_ylims": scales}))


def joint_legend(ax):
    ax.set_xlabel("time (s)")
    ax.set_ylabel("joint angle (deg)")
    ax.grid(alpha=0.3)
    entries = len(ax.get_legend_handles_labels()[1])  # the thin predictions have no label
    ax.legend(fontsize=8, ncol=2 if entries > 8 else 1)


# ---------------------------------------------------------------- open loop

def open_loop(folder, report):
    plan = read_sto(os.path.join(folder, "plan.sto"))
    sim = read_sto(os.path.join(folder, "simulation.sto"))
    plan_controls = read_optional_sto(os.path.join(folder, "plan_controls.sto"))
    summary = read_summary(folder)
    joints, muscles = joints_of(plan), muscles_of(plan)
    require_same(plan, sim, joints_of, "joints")
    require_same(plan, sim, muscles_of, "muscles")
    # Simulated states as markers: every ~30th row keeps the planned line visible beneath.
    every = max(1, len(sim.time) // 30)

    rows, columns = grid_shape(len(muscles))
    fig = plt.figure(figsize=(4 * columns, 2.6 * rows + 0.8))
    axes = muscle_grid(fig, GridSpec(rows, columns, figure=fig), len(muscles))
    series = []
    for ax, m in zip(axes, muscles):
        a_plan, a_sim = plan["/forceset/%s/activation" % m], sim["/forceset/%s/activation" % m]
        n_plan = excitation(plan_controls, m)
        ax.plot(plan.time, a_plan, color="tab:blue", lw=2.5, alpha=0.6, zorder=ZORDER_UNDER, label="planned activation")
        ax.plot(sim.time[::every], a_sim[::every], "o", ms=3, color="tab:red", zorder=ZORDER_MIDDLE,
                label="simulated activation")
        if n_plan is not None:
            # Thin and on top: where the excitation equals the activation it must not vanish under it.
            ax.plot(plan_controls.time, n_plan, "--", color="black", lw=1, zorder=ZORDER_OVER, label="planned excitation")
            series.append(n_plan)
        series += [a_plan, a_sim]
    scales = finish_muscle_panels(axes, muscles, series)
    fig.suptitle("Open loop: planned vs simulated activations" +
                 (", with the planned excitations" if plan_controls is not None else ""))
    fig.tight_layout()
    save(fig, folder, "open_loop_activations.png", scales, report)

    fig, (ax_q, ax_f) = plt.subplots(1, 2, figsize=(11, 4.2))
    for i, j in enumerate(joints):
        color = "C%d" % (i % 10)
        ax_q.plot(plan.time, np.degrees(plan[j + "/value"]), color=color, label=joint_name(j) + " planned")
        ax_q.plot(sim.time[::every], np.degrees(sim[j + "/value"][::every]), "o", ms=3, color=color,
                  label=joint_name(j) + " simulated")
    joint_legend(ax_q)
    for i, m in enumerate(muscles):
        # Over the reserve lines: a muscle at its reserve must stay visible.
        ax_f.plot(plan.time, plan["/forceset/%s/tendon_force" % m], color="C%d" % (i % 10), zorder=ZORDER_OVER,
                  label=muscle_name(m))
    reserves = summary_input(summary, "reserves_N", len(muscles))
    title = "Open loop: joint angles and planned tendon forces"
    if reserves is not None:
        # One line if all muscles share the reserve, else one per muscle in its colour.
        if len(set(reserves)) == 1:
            ax_f.axhline(reserves[0], color="0.55", ls=":", lw=2, zorder=ZORDER_UNDER, label="reserve %g N" % reserves[0])
            title += " (reserve %g N)" % reserves[0]
        else:
            for i, r in enumerate(reserves):
                ax_f.axhline(r, color="C%d" % (i % 10), ls=":", lw=2, alpha=0.5, zorder=ZORDER_UNDER)
            title += " (reserves dotted)"
    ax_f.set_yscale("log")
    ax_f.set_xlabel("time (s)")
    ax_f.set_ylabel("planned tendon force (N)")
    ax_f.grid(alpha=0.3, which="both")
    ax_f.legend(fontsize=8, ncol=2 if len(muscles) > 6 else 1)
    fig.suptitle(title)
    fig.tight_layout()
    save(fig, folder, "open_loop_joints_forces.png", {}, report)


# ---------------------------------------------------------------- receding horizon

def read_predictions(folder, joints):
    paths = sorted(glob.glob(os.path.join(folder, "predictions", "step_*.sto")))
    predictions = [read_sto(p) for p in paths]
    for p in predictions:
        missing = [j for j in joints if j + "/value" not in p.columns]
        if missing:
            raise PlotError("%s: no column '%s/value'" % (p.path, missing[0]))
    return predictions


def receding_horizon(folder, report):
    sim = read_sto(os.path.join(folder, "simulation.sto"))
    controls = read_optional_sto(os.path.join(folder, "simulation_controls.sto"))
    summary = read_summary(folder)
    joints, muscles = joints_of(sim), muscles_of(sim)
    predictions = read_predictions(folder, joints)
    target = summary_input(summary, "target_deg", len(joints))

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for i, j in enumerate(joints):
        color = "C%d" % (i % 10)
        for p in predictions:
            ax.plot(p.time, np.degrees(p[j + "/value"]), color=color, lw=0.6, alpha=0.35)
        ax.plot(sim.time, np.degrees(sim[j + "/value"]), color=color, lw=2, label=joint_name(j) + " closed loop")
        if target is not None:
            ax.axhline(target[i], color=color, ls=":", lw=1.2, label=joint_name(j) + " target")
    joint_legend(ax)
    ax.set_title("Receding horizon: closed-loop joint angles" +
                 (" and each step's predicted path (thin)" if predictions else ""), fontsize=10)
    fig.tight_layout()
    save(fig, folder, "rh_joint_angles.png", {}, report)

    rows, columns = grid_shape(len(muscles))
    fig = plt.figure(figsize=(4 * columns, 2.6 * rows + 0.8))
    axes = muscle_grid(fig, GridSpec(rows, columns, figure=fig), len(muscles))
    series = plot_activations(axes, muscles, sim, controls, dict(color="black", lw=0.8), "applied excitation")
    scales = finish_muscle_panels(axes, muscles, series)
    fig.suptitle("Receding horizon: activations" + (" and applied excitations" if controls is not None else ""))
    fig.tight_layout()
    save(fig, folder, "rh_activations.png", scales, report)


# ---------------------------------------------------------------- forward simulation

def forward(folder, report):
    states = read_sto(os.path.join(folder, "states.sto"))
    controls = read_optional_sto(os.path.join(folder, "controls.sto"))
    joints, muscles = joints_of(states), muscles_of(states)

    rows, columns = grid_shape(len(muscles))
    fig = plt.figure(figsize=(max(8, 4 * columns), 2.6 * (rows + 1) + 0.8))
    # Top row: the joint angles across the width; below: one panel per muscle.
    grid = GridSpec(rows + 1, columns, figure=fig)
    ax_q = fig.add_subplot(grid[0, :])
    for i, j in enumerate(joints):
        ax_q.plot(states.time, np.degrees(states[j + "/value"]), color="C%d" % (i % 10), label=joint_name(j))
    joint_legend(ax_q)
    axes = muscle_grid(fig, grid, len(muscles), first_row=1)
    series = plot_activations(axes, muscles, states, controls, dict(ls="--", color="black", lw=1), "excitation")
    scales = finish_muscle_panels(axes, muscles, series)
    fig.suptitle("Forward simulation: joint angles, activations" + (" and excitations" if controls is not None else ""))
    fig.tight_layout()
    save(fig, folder, "forward_states.png", scales, report)


# ---------------------------------------------------------------- folders and main

def kind_of(folder):
    """The program whose output the folder holds, by the files present, or None."""
    has = lambda name: os.path.exists(os.path.join(folder, name))  # noqa: E731
    if has("plan.sto") and has("simulation.sto"):
        return open_loop
    if has("simulation.sto") and os.path.isdir(os.path.join(folder, "predictions")):
        return receding_horizon
    if has("states.sto"):
        return forward
    return None


def output_folders(path):
    """PATH itself if it is an output folder, else its immediate subfolders that are."""
    if not os.path.isdir(path):
        raise PlotError("%s: no such folder" % path)
    if kind_of(path):
        return [path]
    subfolders = sorted(os.path.join(path, d) for d in os.listdir(path) if os.path.isdir(os.path.join(path, d)))
    found = [d for d in subfolders if kind_of(d)]
    if not found:
        raise PlotError("%s: no program output here or in its subfolders (expected plan.sto + "
                        "simulation.sto, simulation.sto + predictions/, or states.sto)" % path)
    return found


def parse_arguments(argv):
    """(report_scales, paths); exits 0 for --help and 2 for bad usage."""
    report, paths, options_done = False, [], False
    for arg in argv:
        if options_done or not arg.startswith("-") or arg == "-":
            paths.append(arg)
        elif arg == "--":
            options_done = True
        elif arg in ("-h", "--help"):
            print(__doc__.strip())
            sys.exit(0)
        elif arg == "--report-scales":
            report = True
        else:
            usage_error("unknown option '%s'" % arg)
    if not paths:
        usage_error("expects at least one PATH")
    return report, paths


def usage_error(message):
    sys.stderr.write("plot_results: %s\nUsage: plot_results.py [--report-scales] PATH [PATH ...] "
                     "(--help for more)\n" % message)
    sys.exit(2)


def main(argv):
    report, paths = parse_arguments(argv)
    failed, made = False, 0
    for path in paths:
        try:
            folders = output_folders(path)
        except PlotError as e:
            folders, failed = [], report_error(e)
        for folder in folders:
            # One bad folder does not keep the others from being drawn.
            try:
                kind_of(folder)(folder, report)
                made += 1
            except PlotError as e:
                failed = report_error(e)
            except OSError as e:  # e.g. a folder we may not write into
                failed = report_error("%s: %s" % (e.filename or folder, e.strerror or e))
    return 1 if failed or not made else 0


def report_error(message):
    sys.stderr.write("plot_results: %s\n" % message)
    return True


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
