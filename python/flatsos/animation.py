"""Motion you can watch: a planar model's bodies as a stick figure with a line per muscle, beside
a bar per muscle, each coloured by its activation, from any state table the programs write, as GIF (and MP4 where
ffmpeg is installed).

    import flatsos, flatsos.animation
    flatsos.animation.animate(model, time, q, activation, "motion.gif")

or from a shell: python3 -m flatsos.animation --model M.json --states simulation.sto --out motion.gif
"""
import argparse
import json
import os
import pathlib
import sys
import tempfile

import numpy as np

_PLANAR_COS = np.cos(np.radians(45.0))  # a joint axis this near the view's normal moves in its plane
_PARALLEL = 1e-6  # |sin| of the angle between two directions that still counts as parallel
_MUSCLE_OFFSET = 0.08  # a muscle line's largest distance from the bones, in body lengths
_ATTACHMENT = 0.4  # where a muscle line starts and ends along its proximal and distal bodies


class _Skeleton:
    """What the stick figure needs from a model: its joints' tree, each body's tip where no
    joint continues it, and the plane the motion happens in."""

    def __init__(self, model):
        description = json.loads(model.to_json())
        self.model = model
        bodies = {b["name"]: b for b in description["bodies"]}
        joints = description["joints"]
        child_of = {j["child"]: i for i, j in enumerate(joints)}
        self.parent = [child_of.get(j["parent"], -1) for j in joints]  # -1: ground
        # A body's tip, in its own frame: none where a joint continues it; else its length
        # along the direction of its mass centre (or the mass centre itself).
        self.tips = []
        for j in joints:
            body = bodies[j["child"]]
            if any(k["parent"] == j["child"] for k in joints):
                self.tips.append(None)
                continue
            centre = np.array(body.get("mass_center_m", [0.0, 0.0, 0.0]), dtype=float)
            length = body.get("length_m", 0.0)
            norm = np.linalg.norm(centre)
            self.tips.append(centre / norm * length if length > 0 and norm > 0 else centre)
        self.base = [np.array(j["location_in_parent_m"], dtype=float) if self.parent[i] < 0 else None
                     for i, j in enumerate(joints)]
        self.axes = [np.array(j.get("axis", [0.0, 0.0, 1.0]), dtype=float) for j in joints]
        self.types = [j.get("type", "pin") for j in joints]
        gravity = np.array(description.get("gravity_m_per_s2", [0.0, -9.81, 0.0]), dtype=float)
        self.up = -gravity / np.linalg.norm(gravity) if np.linalg.norm(gravity) > 0 else np.array([0.0, 1.0, 0.0])
        self.plane = self._plane()

    def _plane(self):
        """Two unit vectors spanning the plane the motion is drawn in: the ground plane (OpenSim's
        views) whose normal is nearest the first pin's axis (in ground, at the zero posture; with
        sliders only, the one that best holds the first slider's direction and 'up'); the motion
        is projected on it. A pin whose axis is more than 45 deg from that normal, or a slider
        whose direction is more than 45 deg out of the plane, does not move in it (the model is
        not planar). The second vector is 'up' (against gravity) in the plane."""
        _, rotations = self.model.body_frames(np.zeros(len(self.model.joints)))
        directions = []
        for i, axis in enumerate(self.axes):
            r = np.eye(3) if self.parent[i] < 0 else rotations[self.parent[i]]
            directions.append(r @ axis / np.linalg.norm(axis))
        pins = [d for d, kind in zip(directions, self.types) if kind != "slider"]
        n = np.zeros(3)
        if pins:
            n[np.argmax(np.abs(pins[0]))] = 1.0
        else:
            n[np.argmin(np.abs(directions[0]) + np.abs(self.up))] = 1.0
        for name, kind, other in zip(self.model.joints, self.types, directions):
            if kind != "slider" and abs(n @ other) < _PLANAR_COS:
                raise ValueError(f"animation: model '{self.model.name}' is not planar: joint '{name}' turns about "
                                 f"{np.round(other, 3).tolist()}, more than 45 deg from the drawing plane's normal "
                                 f"{n.tolist()}")
            if kind == "slider" and abs(n @ other) > _PLANAR_COS:
                raise ValueError(f"animation: model '{self.model.name}' is not planar: slider '{name}' moves along "
                                 f"{np.round(other, 3).tolist()}, more than 45 deg out of the drawing plane (normal "
                                 f"{n.tolist()})")
        up = self.up - (self.up @ n) * n
        if np.linalg.norm(up) < _PARALLEL:  # gravity along the axis: any in-plane 'up'
            up = np.cross(n, [1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.cross(n, [0.0, 1.0, 0.0])
        up /= np.linalg.norm(up)
        return np.cross(up, n), up

    def segments(self, q):
        """[(start, end)] in plane coordinates (m): ground to each base joint, each body from
        its joint to the next joint or its tip."""
        origins, rotations = self.model.body_frames(q)
        e1, e2 = self.plane
        flat = lambda p: np.array([p @ e1, p @ e2])  # noqa: E731
        out = []
        for i in range(len(self.parent)):
            if self.parent[i] >= 0:
                out.append((flat(origins[self.parent[i]]), flat(origins[i])))
            if self.tips[i] is not None:
                out.append((flat(origins[i]), flat(origins[i] + rotations[i] @ self.tips[i])))
        return out

    def muscle_paths(self, q, moment_arms):
        """Per muscle, a schematic line in plane coordinates (m): from its proximal body past each
        joint it crosses, on the side where it pulls (a positive moment arm turns the joint the
        way the coordinate grows, so the muscle passes on that side of the child body), to a
        point on its distal body; None for a muscle that crosses no joint. Its offset from the
        bones grows with its moment arm."""
        origins, rotations = self.model.body_frames(q)
        e1, e2 = self.plane
        normal = np.cross(e1, e2)
        flat = lambda p: np.array([p @ e1, p @ e2])  # noqa: E731
        centres = [flat(o) for o in origins]
        ends = self._child_ends(origins, rotations, flat)
        lengths = [max(np.linalg.norm(end - c), 1e-3) for c, end in zip(centres, ends)]
        offset = _MUSCLE_OFFSET * np.median(lengths)
        largest = max(np.abs(moment_arms).max(), 1e-12)
        paths = []
        for arms in np.asarray(moment_arms):
            crossed = [i for i in range(len(centres)) if abs(arms[i]) > _PARALLEL * largest]
            if not crossed:
                paths.append(None)
                continue
            points = []
            for k, i in enumerate(crossed):
                along = (ends[i] - centres[i]) / lengths[i]
                side = np.array([-along[1], along[0]])  # the child's counter-clockwise side in the view
                turns = 1.0 if self._axis_in_ground(i, rotations) @ normal >= 0 else -1.0
                shift = np.sign(arms[i]) * turns * offset * (0.5 + 0.5 * abs(arms[i]) / largest) * side
                if k == 0:  # from the proximal body, or from above the joint on the ground
                    parent = self.parent[i]
                    back = centres[parent] - centres[i] if parent >= 0 else np.array([0.0, lengths[i]])
                    points.append(centres[i] + _ATTACHMENT * back + shift)
                points.append(centres[i] + shift)
                if k == len(crossed) - 1:
                    points.append(centres[i] + _ATTACHMENT * (ends[i] - centres[i]) + shift)
            paths.append(np.array(points))
        return paths

    def _child_ends(self, origins, rotations, flat):
        """Each joint's child body's far end in plane coordinates: its next joint or its tip."""
        ends = []
        for i in range(len(self.parent)):
            children = [k for k in range(len(self.parent)) if self.parent[k] == i]
            if children:
                ends.append(flat(origins[children[0]]))
            else:
                tip = self.tips[i] if self.tips[i] is not None else np.zeros(3)
                ends.append(flat(origins[i] + rotations[i] @ tip))
        return ends

    def _axis_in_ground(self, i, rotations):
        r = np.eye(3) if self.parent[i] < 0 else rotations[self.parent[i]]
        return r @ self.axes[i] / np.linalg.norm(self.axes[i])

    def bases(self):
        e1, e2 = self.plane
        return [np.array([b @ e1, b @ e2]) for b in self.base if b is not None]


def _resampled(time, values, frame_times):
    return np.column_stack([np.interp(frame_times, time, values[:, k]) for k in range(values.shape[1])])


def animate(model, time, q, activation, path, *, fps=25, speed=1.0, title=None, dpi=80):
    """Writes the motion (time: s, q: rows x joints, rad; activation: rows x muscles) to `path`,
    a .gif, or a .mp4 where ffmpeg is installed, played at `speed` times real time. Bad input,
    a model that is not planar or an MP4 without ffmpeg raise ValueError; the file is written
    whole or not at all. Returns the number of frames."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import animation

    path = pathlib.Path(path)
    time = np.asarray(time, dtype=float)
    q = np.asarray(q, dtype=float)
    activation = np.asarray(activation, dtype=float)
    if time.ndim != 1 or time.size < 2 or (np.diff(time) <= 0).any() or not np.isfinite(time).all():
        raise ValueError("time: expected at least two strictly increasing finite times")
    if q.shape != (time.size, len(model.joints)) or not np.isfinite(q).all():
        raise ValueError(f"q: expected {time.size} rows of {len(model.joints)} finite angles, got shape {q.shape}")
    if activation.shape != (time.size, len(model.muscles)) or not np.isfinite(activation).all():
        raise ValueError(f"activation: expected {time.size} rows of {len(model.muscles)} finite values, got shape "
                         f"{activation.shape}")
    if not (fps > 0 and speed > 0):
        raise ValueError("fps, speed: must be positive")
    suffix = path.suffix.lower()
    if suffix == ".gif":
        writer = animation.PillowWriter(fps=fps)
    elif suffix == ".mp4":
        if not animation.FFMpegWriter.isAvailable():
            raise ValueError(f"{path}: an MP4 needs ffmpeg, which is not installed (write a .gif)")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        raise ValueError(f"{path}: the file must end in .gif or .mp4")
    skeleton = _Skeleton(model)

    frames = max(2, int(round((time[-1] - time[0]) / speed * fps)) + 1)
    frame_times = np.linspace(time[0], time[-1], frames)
    q_frames = _resampled(time, q, frame_times)
    a_frames = np.clip(_resampled(time, activation, frame_times), 0.0, 1.0)
    drawn = [skeleton.segments(row) for row in q_frames]
    muscle_paths = [skeleton.muscle_paths(row, model.moment_arms(row)) for row in q_frames]
    points = np.array([p for segments in drawn for segment in segments for p in segment] + skeleton.bases() +
                      [p for paths in muscle_paths for path in paths if path is not None for p in path])
    low, high = points.min(axis=0), points.max(axis=0)
    pad = 0.1 * max(high - low) + 0.02

    muscles = len(model.muscles)
    fig, (body_ax, bar_ax) = plt.subplots(1, 2, figsize=(9, max(4.0, 0.16 * muscles + 1.5)),
                                          gridspec_kw={"width_ratios": [3, 2]})
    body_ax.set_xlim(low[0] - pad, high[0] + pad)
    body_ax.set_ylim(low[1] - pad, high[1] + pad)
    body_ax.set_aspect("equal")
    body_ax.set_xlabel("m")
    for base in skeleton.bases():
        body_ax.plot(*base, "k^", markersize=12)
    lines = [body_ax.plot([], [], "o-", color="tab:blue", lw=4, markersize=7, zorder=3)[0] for _ in drawn[0]]
    colours = matplotlib.colormaps["Reds"]
    muscle_lines = [body_ax.plot([], [], "-", lw=2.5, solid_capstyle="round", zorder=2)[0] for _ in model.muscles]
    clock = body_ax.text(0.02, 0.96, "", transform=body_ax.transAxes, va="top")
    body_ax.set_title(title or model.name)
    bars = bar_ax.barh(range(muscles), a_frames[0], color=colours(a_frames[0]))
    bar_ax.set_xlim(0.0, 1.0)
    bar_ax.set_yticks(range(muscles), model.muscles, fontsize=7 if muscles > 12 else 9)
    bar_ax.invert_yaxis()
    bar_ax.set_xlabel("activation")
    fig.tight_layout()

    def update(k):
        for line, (start, end) in zip(lines, drawn[k]):
            line.set_data([start[0], end[0]], [start[1], end[1]])
        for line, path, a in zip(muscle_lines, muscle_paths[k], a_frames[k]):
            if path is not None:
                line.set_data(path[:, 0], path[:, 1])
                line.set_color(colours(0.3 + 0.7 * a))  # a silent muscle stays visible
        for bar, a in zip(bars, a_frames[k]):
            bar.set_width(a)
            bar.set_color(colours(0.15 + 0.85 * a))
        clock.set_text(f"t = {frame_times[k]:.2f} s")
        return lines + muscle_lines + list(bars) + [clock]

    movie = animation.FuncAnimation(fig, update, frames=frames, blit=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, suffix=".tmp" + suffix)
    os.close(handle)
    try:
        movie.save(temporary, writer=writer, dpi=dpi)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)  # mkstemp's 0600 is for the temporary, not the result
        os.replace(temporary, path)
    finally:
        plt.close(fig)
        if os.path.exists(temporary):
            os.remove(temporary)
    return frames


def main(argv=None):
    from ._flatsos import Model
    from .sto import joint_angles, muscle_activations, read_sto
    parser = argparse.ArgumentParser(
        prog="python3 -m flatsos.animation",
        description="Animates a state table a flatsos program wrote (simulation.sto, plan.sto) for a planar model: "
                    "the bodies as a stick figure, a bar per muscle coloured by its activation. Writes a GIF, or an "
                    "MP4 where ffmpeg is installed.")
    parser.add_argument("--model", required=True, help="the model file (JSON) the table was made with")
    parser.add_argument("--states", required=True, help="a state table (.sto)")
    parser.add_argument("--out", required=True, help="the animation to write (.gif or .mp4)")
    parser.add_argument("--fps", type=float, default=25.0, help="frames per second (default 25)")
    parser.add_argument("--speed", type=float, default=1.0, help="times real time (default 1)")
    parser.add_argument("--title", help="title (default: the model's name)")
    args = parser.parse_args(argv)
    try:
        model = Model(args.model)
        table = read_sto(args.states)
        time, q = joint_angles(model, table, args.states)
        frames = animate(model, time, q, muscle_activations(model, table, args.states), args.out, fps=args.fps,
                         speed=args.speed, title=args.title)
    except (ValueError, OSError) as e:
        print(f"flatsos.animation: error: {e}", file=sys.stderr)
        return 2
    print(f"flatsos.animation: wrote {args.out} ({frames} frames)")
    return 0


if __name__ == "__main__":
    from flatsos.animation import main as package_main
    sys.exit(package_main())
