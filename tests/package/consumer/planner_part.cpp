// The planner's Ipopt link from a file that uses Eigen through flatsos. Here a namespace-scope
// `using namespace SimTK;` is impossible (GCC 12 then picks SimTK's catch-all operator!= inside
// Eigen's templates, even when Eigen was included first: flatsos/plugin/simtk_namespace_guard.hpp);
// using-declarations and a block-scope using-directive work, as below.
#include <Simbody.h>

#include "flatsos/planner/slp.hpp"
#include "flatsos/plugin/model/static_equilibrium.hpp"

using SimTK::Vec3;

double slp_cost_of_unit_problem() {
  const Vec3 unused(1, 2, 3);
  // A 2-output SLP: min a + b s.t. a >= 1, b >= 2.
  const auto slp = flatsos::planner::solve_slp(Eigen::Matrix2d::Identity(), Eigen::Vector2d(1.0, 2.0));
  double weight = 0.0;
  {
    using namespace SimTK;  // block scope: Eigen's templates are not instantiated in here
    weight = square(unused[0]) - 1.0;
  }
  return slp.used_fallback ? -1.0 : slp.cost_N + weight;
}
