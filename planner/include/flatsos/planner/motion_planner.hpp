#pragma once
// The planner's two entry points in one include: the open-loop planner (open_loop.hpp) and the
// receding-horizon step (receding_horizon_step.hpp).

#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/receding_horizon_step.hpp"
