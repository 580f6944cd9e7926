"""flatsos from Python: minimum-effort muscle excitations of musculoskeletal models by
differential flatness and sum-of-squares programming, with numpy arrays in and out.

SI units throughout (radians, seconds, newtons). Bad input raises ValueError with the
library's message; the C++ core releases the GIL while it plans.

    import numpy as np, flatsos
    arm = flatsos.Model("models/arm_richter_warner.json")
    plan = flatsos.plan_open_loop(arm, q0=np.radians([0, 10]), qd0=[0, 0], a0=None,
                                  target=np.radians([90, 0]), duration=3.0, reserves=10.0)
    plan.status, plan.cost, plan.sample(np.linspace(0, 3, 301))["excitation"]

Also: shortest_transfer (the least duration with a plan), simulate_plan (Simbody, open loop), simulate (Simbody
under given excitations), run_receding_horizon (the closed loop),
static_optimization (OpenSim's, along a measured motion), solve_inverse (the inverse problem
along a measured motion, as OpenSim's MocoInverse), track (the controller following a
measured motion, as OpenSim's CMC); the
submodules flatsos.study (batch studies on Dask), flatsos.animation (GIF and MP4 of planar
models) and flatsos.sto (OpenSim tables and motion files), each runnable with python3 -m.
"""

from ._flatsos import (Model, OpenLoopPlan, plan_open_loop, run_receding_horizon, shortest_transfer, simulate,
                       simulate_plan, solve_inverse, static_optimization, track)

__all__ = ["Model", "OpenLoopPlan", "plan_open_loop", "run_receding_horizon", "shortest_transfer", "simulate",
           "simulate_plan", "solve_inverse", "static_optimization", "track"]
