#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "flatsos/planner/open_loop.hpp"
#include "flatsos/planner/plan_excitations.hpp"

namespace flatsos::planner {

Jet OpenLoopPlan::flatOutputJet(double t) const {
  if (!Y) throw std::logic_error("open-loop plan: no flat outputs (" + message + ")");
  return Y->jet(t, 3);
}

PlanCheck check_plan(const FlatOutputMap& flat, plugin::ModelWorkspace& workspace, const JointPath& path,
                     const SplineTrajectory& Y, const Eigen::VectorXd& reserves, int points, double bound_tolerance) {
  if (points < 2) throw std::invalid_argument("plan check: need at least 2 points");
  PlanCheck c;
  c.points = points;
  c.min_tendon_force_N = c.min_reserve_margin_N = c.min_activation = c.min_excitation = 1e300;
  c.max_activation = c.max_excitation = -1e300;
  const double h = path.duration_s / (points - 1);
  const std::vector<TorqueJet> jets = torque_jets_on_grid(flat, workspace, path, h, points);
  DomainViolation limiting;           // the most fundamental kind, then the largest excess
  std::size_t limiting_muscle = 0;
  std::map<std::pair<std::size_t, DomainViolation::Kind>, double> first_time;  // per muscle and kind
  Jet q_jet(flat.numJoints(), 5), y_jet(flat.numFlatOutputs(), 3);
  MusclePoint mp;
  for (int i = 0; i < points; ++i) {
    const double t = h * i;
    path.jetInto(t, q_jet);
    Y.jetInto(t, y_jet);
    flat.inverseFromTorque(q_jet, jets[static_cast<std::size_t>(i)], y_jet, mp);
    c.min_tendon_force_N = std::min(c.min_tendon_force_N, mp.tendon_force_N.minCoeff());
    c.min_reserve_margin_N = std::min(c.min_reserve_margin_N, (mp.tendon_force_N - reserves).minCoeff());
    if (mp.activation.allFinite()) {
      c.min_activation = std::min(c.min_activation, mp.activation.minCoeff());
      c.max_activation = std::max(c.max_activation, mp.activation.maxCoeff());
    }
    if (mp.excitation.allFinite()) {
      c.min_excitation = std::min(c.min_excitation, mp.excitation.minCoeff());
      c.max_excitation = std::max(c.max_excitation, mp.excitation.maxCoeff());
    }
    bool outside = false;
    for (std::size_t j = 0; j < mp.domain_violation.size(); ++j) {
      const DomainViolation& v = mp.domain_violation[j];
      if (!v.violated()) continue;
      const bool bound_kind = v.kind == DomainViolation::Kind::ActivationOutsideUnitInterval ||
                              v.kind == DomainViolation::Kind::ActivationBelowFloor ||
                              v.kind == DomainViolation::Kind::ExcitationOutsideUnitInterval;
      if (bound_kind && v.excess() <= bound_tolerance) continue;
      outside = true;
      if (c.first_violation.empty()) {
        std::ostringstream why;
        why << "t = " << t << " s, muscle '" << flat.model().description().muscles[j].parameters.name
            << "': " << v.describe();
        c.first_violation = why.str();
      }
      first_time.try_emplace({j, v.kind}, t);
      if (!limiting.violated() || v.kind < limiting.kind || (v.kind == limiting.kind && v.excess() > limiting.excess())) {
        limiting = v;
        limiting_muscle = j;
      }
    }
    if (outside) ++c.points_outside_domain;
  }
  if (limiting.violated()) {
    std::ostringstream why;
    why << "muscle '" << flat.model().description().muscles[limiting_muscle].parameters.name
        << "': " << limiting.describe() << " (worst), from t = " << first_time.at({limiting_muscle, limiting.kind}) << " s";
    c.limiting_violation = why.str();
  }
  return c;
}

}  // namespace flatsos::planner
