#pragma once
// The Python module flatsos._flatsos: each file registers one part of the API.
#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>  // every file the same casters: std::vector, std::optional, Eigen

#include "flatsos/planner/flat_outputs.hpp"
#include "flatsos/planner/motion_planner.hpp"
#include "flatsos/plugin/io/sto_file.hpp"
#include "flatsos/plugin/model/musculoskeletal_model.hpp"

namespace flatsos::python {

/// A model file loaded, with its flat-output map (built once: at 40 muscles without flat outputs
/// in the file, the library's choice takes about a second).
struct Model {
  std::shared_ptr<const plugin::MusculoskeletalModel> model;
  /// Null when the model gives no flat outputs and none serves its joint ranges (OpenSim's
  /// ranges often): each task then gets flat outputs over its own region (flat_for_task).
  std::shared_ptr<const planner::FlatOutputMap> flat;
};

/// The model's flat-output map, or, when it has none for its whole ranges, one chosen over the
/// region a task visiting `postures` needs (planner/task_region.hpp). Call with the GIL released.
std::shared_ptr<const planner::FlatOutputMap> flat_for_task(const Model& m, const std::vector<Eigen::VectorXd>& postures);

/// An open-loop plan, the model it was made for, and the state it starts from (what simulating
/// it needs).
struct Plan {
  std::shared_ptr<const plugin::MusculoskeletalModel> model;
  std::shared_ptr<const planner::FlatOutputMap> flat;
  planner::OpenLoopPlan plan;
  SimTK::State initial;
};

/// What the module returns as a numpy array of one row per time.
using Table = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A vector from a number (for every entry, when `broadcast`) or a sequence of `n` numbers; a
/// ValueError naming the argument otherwise.
Eigen::VectorXd vector_argument(const pybind11::handle& x, Eigen::Index n, const std::string& name, bool broadcast = false);

/// The `effort=` keyword: None or "paper" give null (the model's own linear effort, its
/// effort_weights); another name the effort of planner::effort_names(), weighted per muscle by
/// `weights` (None: 1 each); a ValueError naming the known efforts otherwise.
std::shared_ptr<const planner::Effort> effort_argument(const pybind11::handle& effort, const pybind11::handle& weights,
                                                       Eigen::Index muscles);

/// a0 of the API: None, or one activation in (0, 1] per muscle (a ValueError otherwise).
std::optional<Eigen::VectorXd> activations_argument(const pybind11::handle& a0, Eigen::Index muscles);

/// A table's columns as numpy-ready arrays (std::out_of_range naming an absent label).
Eigen::VectorXd column_vector(const plugin::StoTable& table, const std::string& label);
Table columns_table(const plugin::StoTable& table, const std::vector<std::string>& labels);
/// The state table's labels of each joint's angle, and of each muscle's `suffix` ("" in a
/// controls table: the excitation).
std::vector<std::string> joint_value_columns(const plugin::MusculoskeletalModel& model);
std::vector<std::string> muscle_columns(const plugin::MusculoskeletalModel& model, const std::string& suffix);

void register_model(pybind11::module_& m);
void register_open_loop(pybind11::module_& m);
void register_simulation(pybind11::module_& m);
void register_receding_horizon(pybind11::module_& m);
void register_static_optimization(pybind11::module_& m);
void register_inverse_problem(pybind11::module_& m);
void register_tracking(pybind11::module_& m);

}  // namespace flatsos::python
