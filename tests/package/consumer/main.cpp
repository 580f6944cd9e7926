// Adds one flatsos Hill muscle to a user-built Simbody pendulum and simulates it briefly.
#include <cmath>
#include <iostream>

#include <Simbody.h>

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/planner/slp.hpp"
#include "flatsos/plugin/force/hill_muscle.hpp"
#include "flatsos/plugin/integration/muscle_rosenbrock_integrator.hpp"

int main() {
  SimTK::MultibodySystem system;
  SimTK::SimbodyMatterSubsystem matter(system);
  SimTK::GeneralForceSubsystem forces(system);
  SimTK::Force::Gravity gravity(forces, matter, SimTK::Vec3(0, -9.81, 0));
  const SimTK::Vec3 com(0.2, 0, 0);
  const SimTK::MassProperties mass(1.0, com, SimTK::Inertia(0.01).shiftFromMassCenter(com, 1.0));
  SimTK::MobilizedBody::Pin link(matter.Ground(), SimTK::Transform(), SimTK::Body::Rigid(mass),
                                 SimTK::Transform());
  flatsos::muscles::MuscleParameters p;
  p.name = "flexor";
  p.max_isometric_force_N = 500;
  p.optimal_fiber_length_m = 0.1;
  p.tendon_slack_length_m = 0.2;
  flatsos::plugin::HillMuscle muscle(forces, p, {0.3, {{link, 0.03}}});
  system.realizeTopology();
  SimTK::State s = system.getDefaultState();
  muscle.setActivation(s, 0.5);
  muscle.setExcitation(s, 0.5);
  muscle.setTendonLength(s, 0.205);
  SimTK::RungeKuttaMersonIntegrator integ(system);
  integ.initialize(s);
  integ.stepTo(0.1);
  integ.stepTo(0.1);
  const double q = link.getOneQ(integ.getState(), 0);
  std::cout << "q(0.1 s) = " << q << " rad, tendon force " << muscle.getTendonForce(integ.getState()) << " N\n";
  // The muscle Rosenbrock integrator on the same user-built system, with one report.
  flatsos::plugin::MuscleRosenbrockIntegrator rosenbrock(system, {muscle}, 1e-8);
  rosenbrock.initialize(s);
  double q_report = NAN;
  const bool advanced = rosenbrock.advanceTo(0.1, {0.05}, [&](const SimTK::State& at) { q_report = link.getOneQ(at, 0); });
  const double q_rosenbrock = link.getOneQ(rosenbrock.state(), 0);
  std::cout << "Rosenbrock: q(0.05 s) = " << q_report << ", q(0.1 s) = " << q_rosenbrock << " rad\n";
  // The planner's Ipopt link: a 2-output SLP, min a + b s.t. a >= 1, b >= 2.
  const auto slp = flatsos::planner::solve_slp(Eigen::Matrix2d::Identity(), Eigen::Vector2d(1.0, 2.0));
  std::cout << "SLP cost " << slp.cost_N << " (expected 3)\n";
  const bool integrators_agree = advanced && std::isfinite(q_report) && std::abs(q_rosenbrock - q) < 1e-4;  // RKM runs at its default accuracy 1e-3
  return std::isfinite(q) && integ.getTime() == 0.1 && integrators_agree && std::abs(slp.cost_N - 3.0) < 1e-6 &&
                 !slp.used_fallback
             ? 0
             : 1;
}
