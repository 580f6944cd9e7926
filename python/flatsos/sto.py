"""OpenSim storage files: read the tables the flatsos programs write (.sto), read and write
controls tables (each muscle's excitation, as Moco writes them), and write a motion (.mot) in
OpenSim's coordinate names and degrees, which plays on the original .osim model.

    python3 -m flatsos.sto --model models/seated_knee_r.json \\
        --states results/seated_knee_r/open_loop/simulation.sto --out knee.mot
"""
import argparse
import math
import os
import pathlib
import sys
import tempfile

import numpy as np


def read_sto(path):
    """{column label: numpy array} of a tab-separated .sto file as the programs write it.
    Raises ValueError naming the file and what is wrong."""
    try:
        lines = pathlib.Path(path).read_text().splitlines()
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror}") from None
    if "endheader" not in lines:
        raise ValueError(f"{path}: not a storage file (no 'endheader' line)")
    start = lines.index("endheader") + 1
    if start >= len(lines):
        raise ValueError(f"{path}: no column labels after 'endheader'")
    labels = lines[start].split("\t")
    rows = []
    for number, line in enumerate(lines[start + 1:], start + 2):
        if not line.strip():
            continue
        fields = line.split("\t")
        if len(fields) != len(labels):
            raise ValueError(f"{path}:{number}: {len(fields)} values for {len(labels)} columns")
        try:
            rows.append([float(x) for x in fields])
        except ValueError:
            raise ValueError(f"{path}:{number}: a value is not a number") from None
    data = np.array(rows, dtype=float).reshape(len(rows), len(labels))
    return {label: data[:, k] for k, label in enumerate(labels)}


def joint_angles(model, table, source="table"):
    """(time, q: rows x joints, rad) from a state table of `model` (columns
    /jointset/<joint>/<coordinate>/value). ValueError naming a missing column."""
    q = []
    for joint, coordinate in zip(model.joints, model.coordinates):
        label = f"/jointset/{joint}/{coordinate}/value"
        if label not in table:
            raise ValueError(f"{source}: no column '{label}' (is it a state table of model '{model.name}'?)")
        q.append(table[label])
    if "time" not in table:
        raise ValueError(f"{source}: no column 'time'")
    return table["time"], np.column_stack(q)


def muscle_activations(model, table, source="table"):
    """rows x muscles of the columns /forceset/<muscle>/activation."""
    columns = []
    for muscle in model.muscles:
        label = f"/forceset/{muscle}/activation"
        if label not in table:
            raise ValueError(f"{source}: no column '{label}'")
        columns.append(table[label])
    return np.column_stack(columns)


def write_motion(model, time, q, path, name="flatsos"):
    """An OpenSim motion file: time, then each joint's coordinate and each coordinate the model
    held fixed (imported models), in degrees (inDegrees=yes: a slider's coordinate stays in metres, as
    OpenSim converts only rotational coordinates). Written whole or not at all."""
    time = np.asarray(time, dtype=float)
    q = np.asarray(q, dtype=float)
    if time.ndim != 1 or q.shape != (time.size, len(model.joints)):
        raise ValueError(f"q: expected {time.size} rows of {len(model.joints)} angles, got shape {q.shape}")
    if not (np.isfinite(time).all() and np.isfinite(q).all()):
        raise ValueError("time, q: values must be finite")
    if (np.diff(time) <= 0).any():
        raise ValueError("time: must increase strictly")
    held = model.held_coordinates
    labels = ["time"] + list(model.coordinates) + sorted(held)
    types = model.joint_types
    columns = [time] + [q[:, i] if types[i] == "slider" else np.degrees(q[:, i]) for i in range(q.shape[1])] + \
        [np.full(time.size, math.degrees(held[c])) for c in sorted(held)]
    _write_table(path, name, labels, np.column_stack(columns), in_degrees=True)


def write_controls(model, time, excitation, path, name="controls"):
    """A controls table as OpenSim Moco and the flatsos programs write it (time, then
    /forceset/<muscle>: each muscle's excitation), which `flatsos simulate --excitations` and
    flatsos.simulate read back. Written whole or not at all."""
    time = np.asarray(time, dtype=float)
    excitation = np.asarray(excitation, dtype=float)
    if time.ndim != 1 or excitation.shape != (time.size, len(model.muscles)):
        raise ValueError(f"excitation: expected {time.size} rows of {len(model.muscles)} excitations, got shape "
                         f"{excitation.shape}")
    if not (np.isfinite(time).all() and np.isfinite(excitation).all()):
        raise ValueError("time, excitation: values must be finite")
    if (np.diff(time) <= 0).any():
        raise ValueError("time: must increase strictly")
    labels = ["time"] + [f"/forceset/{m}" for m in model.muscles]
    _write_table(path, name, labels, np.column_stack([time, excitation]), in_degrees=False)


def read_controls(model, path):
    """(time, excitation: rows x muscles) of a controls table (columns /forceset/<muscle>, as Moco
    writes them, or plain <muscle>). ValueError naming the file and a missing muscle."""
    table = read_sto(path)
    if "time" not in table:
        raise ValueError(f"{path}: no column 'time'")
    columns = []
    for muscle in model.muscles:
        label = next((c for c in (f"/forceset/{muscle}", muscle) if c in table), None)
        if label is None:
            raise ValueError(f"{path}: no column '/forceset/{muscle}'")
        columns.append(table[label])
    return table["time"], np.column_stack(columns)


def _write_table(path, name, labels, data, in_degrees):
    """OpenSim storage: a header, the labels and tab-separated rows, renamed into place."""
    path = pathlib.Path(path)
    header = (f"{name}\nversion=1\nnRows={data.shape[0]}\nnColumns={data.shape[1]}\n"
              f"inDegrees={'yes' if in_degrees else 'no'}\nendheader\n" + "\t".join(labels) + "\n")
    with tempfile.NamedTemporaryFile("w", dir=path.parent, suffix=".tmp", delete=False) as f:
        f.write(header)
        for row in data:
            f.write("\t".join(repr(float(x)) for x in row) + "\n")
    os.replace(f.name, path)


def main(argv=None):
    from ._flatsos import Model
    parser = argparse.ArgumentParser(
        prog="python3 -m flatsos.sto",
        description="Writes an OpenSim motion file (.mot: coordinate names, degrees, the coordinates the model "
                    "held fixed included) from a state table a flatsos program wrote (simulation.sto or plan.sto).")
    parser.add_argument("--model", required=True, help="the model file (JSON) the table was made with")
    parser.add_argument("--states", required=True, help="a state table (.sto)")
    parser.add_argument("--out", required=True, help="the motion file to write (.mot)")
    args = parser.parse_args(argv)
    try:
        model = Model(args.model)
        time, q = joint_angles(model, read_sto(args.states), args.states)
        pathlib.Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        write_motion(model, time, q, args.out, name=pathlib.Path(args.out).stem)
    except (ValueError, OSError) as e:
        print(f"flatsos.sto: error: {e}", file=sys.stderr)
        return 2
    print(f"flatsos.sto: wrote {args.out} ({len(time)} rows, {len(model.coordinates) + len(model.held_coordinates)} "
          "coordinates, degrees)")
    return 0


if __name__ == "__main__":
    from flatsos.sto import main as package_main
    sys.exit(package_main())
