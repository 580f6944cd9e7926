"""Batch studies on Dask: one open-loop plan (or one tracking run) per random sample of a model's
muscle strengths and targets, on a local cluster or on an existing one, written as one table.

    import flatsos.study
    result = flatsos.study.run("models/arm_richter_warner.json",
                               {"strength": {"low": 0.8, "high": 1.2}}, samples=1000)
    result.write("results/strength_study")      # table.csv and summary.json

or from a shell: python3 -m flatsos.study --help.

The study description (a dict, or a JSON file on the command line):
    "plan":     the plan of every sample, plan_open_loop's inputs in the model files' units:
                q0_deg, qd0_deg_per_s, a0 (null: the minimum-effort rest state at q0),
                target_deg, duration_s, reserves_N (one number or one per muscle) and
                "options" (plan_open_loop's keywords; with a nonlinear "effort" such as
                "excitation_squared" the table's cost column is cost_s); what it leaves out comes from the
                model file's "open_loop" scenario, else q0 = 0, at rest, 30 deg on, 1 s, 10 N.
                A slider's entries are in m (m/s), as in the model file; its default
                target is 0.05 m on.
    "strength": {"low": l, "high": h}: each muscle's maximum isometric force times a factor
                drawn uniformly from [l, h], independently (absent: the model's forces).
    "target_deg": {"low": [...], "high": [...]}: the target drawn uniformly in this box, one
                bound per joint (absent: the plan's target).
    "track":    instead of plans, the receding-horizon controller following a measured motion
                (flatsos.track) on a plant whose muscles are the sample's strengths and the
                controller's the model's: {"coordinates": motion file (.mot or .sto),
                "options": track's keywords in its units (horizon, period, correction in s,
                observer_gain in 1/s, reserves in N, cutoff_hz, tolerance in rad; effort: a
                name such as "activation_squared", or null for the model's linear effort;
                default "excitation_squared")}. The table then has each joint's RMS and largest
                tracking error (deg; a slider's m) and the integral of the summed squared
                excitations; "plan" and "target_deg" do not apply.
Samples are drawn on the client from numpy's generator with the given seed, so a study gives
the same table on any cluster, and the same as the serial loop (workers=0).
"""
import argparse
import collections
import csv
import hashlib
import json
import math
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

from ._flatsos import Model, plan_open_loop, track

# Columns that measure the machine rather than the plan (or tracking run): they differ between runs.
_PLAN_TIMING_COLUMNS = ("setup_s", "solve_s", "certify_s", "check_s", "plan_s", "worker")
TIMING_COLUMNS = _PLAN_TIMING_COLUMNS + ("track_s",)
_TRACK_KEYWORDS = {"horizon", "period", "correction", "observer_gain", "reserves", "cutoff_hz", "tolerance", "effort"}
# The nonlinear efforts a study can name (null or "paper": the model's effort_weights, the linear effort).
_NONLINEAR_EFFORTS = {"excitation_squared", "excitation_cubed", "activation_squared", "activation_cubed", "stress_squared",
                  "stress_cubed"}
_SAMPLES_FOR_PEAKS = 301


class StudyError(ValueError):
    """A study description or option that cannot run; the message names the field."""


def _numbers(value, count, field, broadcast=False):
    if isinstance(value, (int, float)) and not isinstance(value, bool) and broadcast:
        value = [value] * count
    try:
        out = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise StudyError(f"{field}: expected {count} numbers") from None
    if out.shape != (count,):
        raise StudyError(f"{field}: expected {count} numbers" + (" or one number" if broadcast else "") +
                         f", got {out.size}")
    if not np.isfinite(out).all():
        raise StudyError(f"{field}: values must be finite")
    return out


def _range(spec, count, field, broadcast):
    if not isinstance(spec, dict) or set(spec) != {"low", "high"}:
        raise StudyError(f"{field}: expected an object with 'low' and 'high'")
    low = _numbers(spec["low"], count, field + ".low", broadcast)
    high = _numbers(spec["high"], count, field + ".high", broadcast)
    if (low > high).any():
        raise StudyError(f"{field}: low must not exceed high")
    return low, high


class Study:
    """A validated study description for one model (see the module's documentation)."""

    def __init__(self, model_text, description, source="model"):
        if not isinstance(description, dict):
            raise StudyError("study: expected a JSON object")
        unknown = set(description) - {"plan", "strength", "target_deg", "track"}
        if unknown:
            raise StudyError(f"study: unknown field(s) {sorted(unknown)} (plan, strength, target_deg, track)")
        self.track = _track_description(description["track"]) if "track" in description else None
        if self.track and ({"plan", "target_deg"} & set(description)):
            raise StudyError("track: a tracking study has no plan or target_deg (the motion is the task)")
        model = json.loads(model_text)
        joints = [j["name"] for j in model["joints"]]
        muscles = [m["name"] for m in model["muscles"]]
        self.model_text, self.source, self.joints, self.muscles = model_text, source, joints, muscles
        self.sliders = np.array([j.get("type", "pin") == "slider" for j in model["joints"]], dtype=bool)
        n, m = len(joints), len(muscles)
        scenario = model.get("scenarios", {}).get("open_loop", {})
        plan = description.get("plan", {})
        if not isinstance(plan, dict):
            raise StudyError("plan: expected a JSON object")
        allowed = {"q0_deg", "qd0_deg_per_s", "a0", "target_deg", "duration_s", "reserves_N", "options"}
        if set(plan) - allowed:
            raise StudyError(f"plan: unknown field(s) {sorted(set(plan) - allowed)} ({', '.join(sorted(allowed))})")
        given = dict(scenario, **plan)
        if "a0" not in plan and "activations" in scenario:
            given["a0"] = scenario["activations"]
        self.q0_deg = _numbers(given.get("q0_deg", [0.0] * n), n, "plan.q0_deg")
        self.qd0_deg_per_s = _numbers(given.get("qd0_deg_per_s", [0.0] * n), n, "plan.qd0_deg_per_s")
        self.a0 = None if given.get("a0") is None else _numbers(given["a0"], m, "plan.a0")
        self.target_deg = _numbers(given.get("target_deg", self.q0_deg + np.where(self.sliders, 0.05, 30.0)), n,
                                   "plan.target_deg")
        self.duration_s = float(given.get("duration_s", 1.0))
        if not (self.duration_s > 0.0 and math.isfinite(self.duration_s)):
            raise StudyError("plan.duration_s: must be a positive number of seconds")
        self.reserves_N = _numbers(given.get("reserves_N", 10.0), m, "plan.reserves_N", broadcast=True)
        self.options = dict(plan.get("options", {}))
        keywords = {"preset", "flat_output_degree", "flat_output_spans", "flat_output_span_growth", "torque_pieces",
                    "torque_piece_growth", "torque_degree", "bounds", "effort", "weights"}
        if set(self.options) - keywords:
            raise StudyError(f"plan.options: unknown field(s) {sorted(set(self.options) - keywords)} "
                             f"({', '.join(sorted(keywords))})")
        effort = self.options.get("effort")
        if effort is not None and effort != "paper" and effort not in _NONLINEAR_EFFORTS:
            raise StudyError(f"plan.options.effort: expected null, \"paper\" or one of {', '.join(sorted(_NONLINEAR_EFFORTS))}")
        # The cost's unit: N s for the model's linear effort, s for the others (dimensionless integrands).
        self.cost_column = "cost_Ns" if effort in (None, "paper") else "cost_s"
        self.strength = _range(description["strength"], m, "strength", True) if "strength" in description else None
        self.target_box = _range(description["target_deg"], n, "target_deg", False) \
            if "target_deg" in description else None
        self.description = description

    def to_si(self, shown):
        """Per joint from the description's units: degrees to radians, a slider's metres kept."""
        shown = np.asarray(shown, dtype=float)
        return np.where(self.sliders, shown, np.radians(shown))

    def draw(self, samples, seed):
        """(strength factors, targets in degrees): one row per sample."""
        if not (isinstance(samples, int) and samples >= 1):
            raise StudyError("samples: must be a whole number >= 1")
        rng = np.random.default_rng(seed)
        m, n = len(self.muscles), len(self.joints)
        strength = rng.uniform(*self.strength, size=(samples, m)) if self.strength else np.ones((samples, m))
        target = rng.uniform(*self.target_box, size=(samples, n)) if self.target_box else \
            np.tile(self.target_deg, (samples, 1))
        return strength, target

    def columns(self):
        if self.track:
            return (["sample"] + [f"strength_{name}" for name in self.muscles] + ["status"] +
                    [f"rms_error_{name}_deg" for name in self.joints] +
                    [f"max_error_{name}_deg" for name in self.joints] +
                    ["excitation_squared_integral", "message", "track_s", "worker"])
        return (["sample"] + [f"strength_{name}" for name in self.muscles] +
                [f"target_{name}_deg" for name in self.joints] +
                ["status", self.cost_column, "peak_excitation", "peak_activation", "min_activation", "message"] +
                list(_PLAN_TIMING_COLUMNS))


def _track_description(track_spec):
    if not isinstance(track_spec, dict):
        raise StudyError("track: expected a JSON object")
    if set(track_spec) - {"coordinates", "options"}:
        raise StudyError(f"track: unknown field(s) {sorted(set(track_spec) - {'coordinates', 'options'})} "
                         "(coordinates, options)")
    if "coordinates" not in track_spec:
        raise StudyError("track.coordinates: the motion file to follow is missing")
    coordinates = str(pathlib.Path(track_spec["coordinates"]).resolve())
    if not pathlib.Path(coordinates).is_file():
        raise StudyError(f"track.coordinates: no file '{track_spec['coordinates']}'")
    options = track_spec.get("options", {})
    if not isinstance(options, dict) or set(options) - _TRACK_KEYWORDS:
        raise StudyError(f"track.options: expected an object of {', '.join(sorted(_TRACK_KEYWORDS))}")
    for key, value in options.items():  # numbers (reserves: one or one per muscle), refused here
        if key == "effort":
            if value is not None and not (isinstance(value, str) and value in _NONLINEAR_EFFORTS):
                raise StudyError(f"track.options.effort: expected null or one of {', '.join(sorted(_NONLINEAR_EFFORTS))}")
            continue
        values = value if key == "reserves" and isinstance(value, list) else [value]
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
            raise StudyError(f"track.options.{key}: expected a finite number" +
                             (" or one per muscle" if key == "reserves" else ""))
    return {"coordinates": coordinates, "options": dict(options)}


# The models a process has loaded, by their text's digest: a worker loads each model once
# (a library choice of flat outputs can take a second), whatever the number of tasks.
_models = {}


def _model(text, source):
    key = hashlib.sha256(text.encode()).hexdigest()
    if key not in _models:
        _models[key] = Model.from_json(text, source)
    return _models[key]


def cached_models():
    """How many models this process holds (a worker's cache; tests ask the workers)."""
    return len(_models)


def _worker_name():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return "serial"


def _plan_one(model, study, index, strength, target_deg):
    row = {"sample": index}
    row.update({f"strength_{name}": f for name, f in zip(study.muscles, strength)})
    row.update({f"target_{name}_deg": t for name, t in zip(study.joints, target_deg)})
    start = time.perf_counter()
    peaks = (math.nan, math.nan, math.nan)
    try:
        subject = model.with_strength(strength) if study.strength else model
        plan = plan_open_loop(subject, study.to_si(study.q0_deg), study.to_si(study.qd0_deg_per_s), study.a0,
                              study.to_si(target_deg), study.duration_s, study.reserves_N, **study.options)
        status, cost, message, seconds = plan.status, plan.cost, plan.message, plan.seconds
        if status == "solved":
            s = plan.sample(np.linspace(0.0, study.duration_s, _SAMPLES_FOR_PEAKS))
            peaks = (s["excitation"].max(), s["activation"].max(), s["activation"].min())
    except ValueError as e:  # the library refused this sample's inputs: a row that says why
        status, cost, message, seconds = "failed", None, f"error: {e}", {}
    row[study.cost_column] = math.nan if cost is None else cost
    row.update(status=status, peak_excitation=peaks[0],
               peak_activation=peaks[1], min_activation=peaks[2], message=message,
               setup_s=seconds.get("setup", math.nan), solve_s=seconds.get("solve", math.nan),
               certify_s=seconds.get("certify", math.nan), check_s=seconds.get("check", math.nan),
               plan_s=time.perf_counter() - start, worker=_worker_name())
    return row


def _track_one(model, study, index, strength):
    row = {"sample": index}
    row.update({f"strength_{name}": f for name, f in zip(study.muscles, strength)})
    start = time.perf_counter()
    nan = [math.nan] * len(study.joints)
    rms, largest, effort = nan, nan, math.nan
    try:
        plant = model.with_strength(strength) if study.strength else None
        r = track(model, study.track["coordinates"], plant=plant, **study.track["options"])
        shown = lambda x: np.where(study.sliders, x, np.degrees(x))  # noqa: E731 (the table's units)
        rms, largest, effort = shown(r["rms_error"]), shown(r["max_abs_error"]), r["excitation_squared_integral"]
        status, message = ("tracked" if r["success"] else "failed"), r["message"]
    except (ValueError, TypeError) as e:  # the library refused this sample's inputs: a row that says why
        status, message = "failed", f"error: {e}"
    row["status"] = status
    row.update({f"rms_error_{name}_deg": float(v) for name, v in zip(study.joints, rms)})
    row.update({f"max_error_{name}_deg": float(v) for name, v in zip(study.joints, largest)})
    row.update(excitation_squared_integral=effort, message=message, track_s=time.perf_counter() - start,
               worker=_worker_name())
    return row


def _plan_block(study, indices, strength, target_deg):
    """A task: the plans (or tracking runs) of a block of samples (one Dask task each block, to
    keep the scheduler's per-task cost small against plans of milliseconds)."""
    model = _model(study.model_text, study.source)
    if study.track:
        return [_track_one(model, study, i, s) for i, s in zip(indices, strength)]
    return [_plan_one(model, study, i, s, t) for i, s, t in zip(indices, strength, target_deg)]


def local_cluster(workers=2):
    """A Dask LocalCluster of `workers` processes, one thread each, no dashboard. Dask's workers
    trim the heap above 64 KiB (MALLOC_TRIM_THRESHOLD_), which costs a plan's many small
    allocations 10 % (measured); these hold small models, so they trim above 64 MiB instead."""
    import dask
    from distributed import LocalCluster
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": 64 * 2**20}):
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)


class StudyResult:
    """One row per plan (`rows`, in sample order; `table()` as numpy columns) and a summary."""

    def __init__(self, study, rows, summary):
        self.study, self.rows, self.summary = study, rows, summary

    def table(self):
        """{column: numpy array}: numbers as float arrays, status, message and worker as str."""
        out = {}
        for column in self.study.columns():
            values = [row[column] for row in self.rows]
            out[column] = np.array(values, dtype=object if column in ("status", "message", "worker") else float)
        return out

    def write(self, folder):
        """folder/table.csv and folder/summary.json, each written whole or not at all."""
        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=folder, suffix=".csv.tmp", delete=False, newline="") as f:
            writer = csv.DictWriter(f, fieldnames=self.study.columns())
            writer.writeheader()
            for row in self.rows:
                writer.writerow({k: repr(v) if isinstance(v, float) else v for k, v in row.items()})
        os.replace(f.name, folder / "table.csv")
        with tempfile.NamedTemporaryFile("w", dir=folder, suffix=".json.tmp", delete=False) as f:
            json.dump(self.summary, f, indent=2)
            f.write("\n")
        os.replace(f.name, folder / "summary.json")


def _summarize(study, rows, samples, seed, where, wall_s):
    statuses = collections.Counter(row["status"] for row in rows)
    solved = [row for row in rows if row["status"] in ("solved", "tracked")]

    def spread(column):
        values = np.array([row[column] for row in solved])
        if values.size == 0:
            return None
        q = np.percentile(values, [0, 5, 50, 95, 100])
        return {"min": q[0], "p5": q[1], "median": q[2], "p95": q[3], "max": q[4]}

    if study.track:
        return {
            "model": study.source, "samples": samples, "seed": seed, "study": study.description, "ran_on": where,
            "statuses": dict(statuses), "tracked_fraction": statuses["tracked"] / samples,
            "rms_error_deg": {name: spread(f"rms_error_{name}_deg") for name in study.joints},
            "max_error_deg": {name: spread(f"max_error_{name}_deg") for name in study.joints},
            "excitation_squared_integral": spread("excitation_squared_integral"),
            "track_seconds_median": float(np.median([row["track_s"] for row in rows])),
            "wall_seconds": wall_s, "runs_per_second": samples / wall_s,
        }
    return {
        "model": study.source, "samples": samples, "seed": seed, "study": study.description, "ran_on": where,
        "statuses": dict(statuses), "feasible_fraction": statuses["solved"] / samples,
        study.cost_column: spread(study.cost_column), "peak_excitation": spread("peak_excitation"),
        "peak_activation": spread("peak_activation"),
        "plan_seconds_median": float(np.median([row["plan_s"] for row in rows])),
        "wall_seconds": wall_s, "plans_per_second": samples / wall_s,
    }


def run(model, study, samples, *, seed=0, scheduler=None, workers=2, block=25, progress=False):
    """Plans every sample of `study` (a dict, see the module) for `model` (a model file's path)
    and returns a StudyResult.

    scheduler: the address of a running Dask scheduler (tcp://host:port), or a
    distributed.Client; None: a local cluster of `workers` processes (one thread each), closed
    at the end; workers=0: a serial loop in this process (no Dask). block: samples per task.
    progress: print the plans done to standard error as they finish. Bad input raises
    StudyError (a ValueError) naming the field.
    """
    path = pathlib.Path(model)
    try:
        text = path.read_text()
    except OSError as e:
        raise StudyError(f"model: cannot read '{model}': {e.strerror}") from None
    try:
        json.loads(text)
    except json.JSONDecodeError as e:
        raise StudyError(f"model: '{model}' is not JSON: {e}") from None
    _model(text, str(path))  # a bad model is refused here, by the library, not in a worker; a serial loop reuses it
    spec = Study(text, study, str(path))
    if not (isinstance(block, int) and block >= 1):
        raise StudyError("block: must be a whole number >= 1")
    if not (isinstance(workers, int) and workers >= 0):
        raise StudyError("workers: must be a whole number >= 0")
    strength, target = spec.draw(samples, seed)
    blocks = [range(k, min(k + block, samples)) for k in range(0, samples, block)]
    start = time.perf_counter()
    rows = []

    tty = sys.stderr.isatty()
    reported = [0]

    def report(done):  # on a terminal one line redrawn; in a log a line per tenth
        if not progress:
            return
        if tty:
            print(f"\rstudy: {done}/{samples} plans", end="" if done < samples else "\n", file=sys.stderr, flush=True)
        elif 10 * done // samples > reported[0] or done == samples:
            reported[0] = 10 * done // samples
            print(f"study: {done}/{samples} plans", file=sys.stderr, flush=True)

    if scheduler is None and workers == 0:
        where = "serial"
        for b in blocks:
            rows += _plan_block(spec, list(b), strength[b.start:b.stop], target[b.start:b.stop])
            report(len(rows))
    else:
        from distributed import Client, as_completed
        cluster = None
        if scheduler is None:
            cluster = local_cluster(workers)
            client = Client(cluster)
            where = f"local cluster of {workers} worker processes"
        elif isinstance(scheduler, Client):
            client, where = scheduler, f"scheduler {scheduler.scheduler.address}"
        else:
            client, where = Client(scheduler), f"scheduler {scheduler}"
        try:
            futures = [client.submit(_plan_block, spec, list(b), strength[b.start:b.stop], target[b.start:b.stop],
                                     pure=False) for b in blocks]
            for future in as_completed(futures):
                rows += future.result()
                report(len(rows))
        finally:
            if client is not scheduler:
                client.close()
            if cluster is not None:
                cluster.close()
    rows.sort(key=lambda row: row["sample"])
    wall = time.perf_counter() - start
    return StudyResult(spec, rows, _summarize(spec, rows, samples, seed, where, wall))


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="python3 -m flatsos.study",
        description="A batch study on Dask: one open-loop plan (or, with a \"track\" field, one run of the "
                    "controller following a measured motion) per random sample of a model's muscle strengths "
                    "and targets. Writes OUT/table.csv (one row per sample: its inputs, status, cost or tracking "
                    "errors, timings) and OUT/summary.json. The study file's fields are described in the module "
                    "flatsos.study.")
    parser.add_argument("--model", required=True, help="model file (JSON)")
    parser.add_argument("--study", required=True, help="study description (JSON file)")
    parser.add_argument("--samples", type=int, default=1000, help="number of plans (default 1000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random samples (default 0)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    parser.add_argument("--workers", type=int, default=2,
                        help="worker processes of the local cluster (default 2; 0: a serial loop without Dask)")
    parser.add_argument("--block", type=int, default=25, help="samples per Dask task (default 25)")
    parser.add_argument("--out", default="results/study", help="output folder (default results/study)")
    args = parser.parse_args(argv)
    try:
        try:
            description = json.loads(pathlib.Path(args.study).read_text())
        except OSError as e:
            raise StudyError(f"study: cannot read '{args.study}': {e.strerror}") from None
        except json.JSONDecodeError as e:
            raise StudyError(f"study: '{args.study}' is not JSON: {e}") from None
        result = run(args.model, description, args.samples, seed=args.seed, scheduler=args.scheduler,
                     workers=args.workers, block=args.block, progress=True)
    except ValueError as e:
        print(f"flatsos.study: error: {e}", file=sys.stderr)
        return 2
    result.write(args.out)
    s = result.summary
    what, rate = ("tracking runs", s["runs_per_second"]) if "runs_per_second" in s else ("plans", s["plans_per_second"])
    print(f"flatsos.study: {args.samples} {what} on {s['ran_on']} in {s['wall_seconds']:.2f} s "
          f"({rate:.1f}/s); statuses {s['statuses']}; wrote {args.out}/table.csv, summary.json")
    return 0


if __name__ == "__main__":
    # The package's module rather than this __main__: Dask pickles its functions by name then.
    from flatsos.study import main as package_main
    sys.exit(package_main())
