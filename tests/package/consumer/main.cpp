// Adds one flatsos Hill muscle to a user-built Simbody pendulum and simulates it briefly, in a
// file that says `using namespace SimTK;` before the muscle headers (they include no Eigen).
#include <cmath>
#include <iostream>
#include <vector>

#include <Simbody.h>
using namespace SimTK;

#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/static_equilibrium.hpp"
#include "flatsos/plugin/force/hill_muscle.hpp"
#include "flatsos/plugin/integration/muscle_rosenbrock_integrator.hpp"

double slp_cost_of_unit_problem();  // planner_part.cpp

int main() {
  MultibodySystem system;
  SimbodyMatterSubsystem matter(system);
  GeneralForceSubsystem forces(system);
  Force::Gravity gravity(forces, matter, Vec3(0, -9.81, 0));
  const Vec3 com(0.2, 0, 0);
  const MassProperties mass(1.0, com, Inertia(0.01).shiftFromMassCenter(com, 1.0));
  MobilizedBody::Pin link(matter.Ground(), Transform(), Body::Rigid(mass),
                                 Transform());
  flatsos::muscles::MuscleParameters p;
  p.name = "flexor";
  p.max_isometric_force_N = 500;
  p.optimal_fiber_length_m = 0.1;
  p.tendon_slack_length_m = 0.2;
  flatsos::plugin::HillMuscle muscle(forces, p, flatsos::plugin::MusclePath::constantMomentArms(0.3, {{link, 0.03}}));
  system.realizeTopology();
  State s = system.getDefaultState();
  muscle.setActivation(s, 0.5);
  muscle.setExcitation(s, 0.5);
  const double L = muscle.getPath().length_m.value(std::vector<double>{0.0}.data());  // at q = 0
  muscle.setTendonLength(s, flatsos::muscles::static_equilibrium_tendon_length(p, L, 0.5));
  RungeKuttaMersonIntegrator integ(system);
  integ.initialize(s);
  integ.stepTo(0.1);
  integ.stepTo(0.1);
  const double q = link.getOneQ(integ.getState(), 0);
  std::cout << "q(0.1 s) = " << q << " rad, tendon force " << muscle.getTendonForce(integ.getState()) << " N\n";
  // The muscle Rosenbrock integrator on the same user-built system, with one report.
  flatsos::plugin::MuscleRosenbrockIntegrator rosenbrock(system, {muscle}, 1e-8);
  rosenbrock.initialize(s);
  double q_report = NAN;
  const bool advanced = rosenbrock.advanceTo(0.1, {0.05}, [&](const State& at) { q_report = link.getOneQ(at, 0); });
  const double q_rosenbrock = link.getOneQ(rosenbrock.state(), 0);
  std::cout << "Rosenbrock: q(0.05 s) = " << q_report << ", q(0.1 s) = " << q_rosenbrock << " rad\n";
  const double slp_cost = slp_cost_of_unit_problem();
  std::cout << "SLP cost " << slp_cost << " (expected 3)\n";
  const bool integrators_agree = advanced && std::isfinite(q_report) && std::abs(q_rosenbrock - q) < 1e-4;  // RKM runs at its default accuracy 1e-3
  return std::isfinite(q) && integ.getTime() == 0.1 && integrators_agree && std::abs(slp_cost - 3.0) < 1e-6 ? 0 : 1;
}
