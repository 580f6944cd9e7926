// The Hermite-Simpson transcription's exact derivatives against finite-difference twins: the
// objective's gradient, every Jacobian entry (and no nonzero outside the declared pattern), and
// the Hessian of the Lagrangian with random multipliers, on the paper's arm at a random point
// away from the laws' kinks (slack tendon, u = 0): along a prescribed joint path, with the
// path free (joint unknowns, inverse dynamics, lengths of q), and along a measured motion (the
// muscles free at both ends, moment arms that change from point to point); with the arm's muscles following
// each muscle model in turn (Thelen's and De Groote's without passive force), and minimizing each
// kind of effort (tendon forces; powers of excitations, activations and stress).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <utility>

#include "collocation/hermite_simpson.hpp"
#include "finite_difference.hpp"
#include "flatsos/muscles/hill_laws.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/planner/collocation.hpp"
#include "flatsos/plugin/io/model_file.hpp"
#include "scenario_fixture.hpp"

namespace fpl = flatsos::planner;
namespace fpd = flatsos::planner::detail;
using flatsos::test::central_difference;

namespace {

// The paper's arm with every muscle following `model` at that model's defaults.
std::shared_ptr<const flatsos::plugin::MusculoskeletalModel> arm_with(const std::string& model) {
  flatsos::plugin::ModelDescription d = flatsos::plugin::load_model_file(flatsos::test::arm_model_path());
  if (model != "richter_warner")
    for (auto& m : d.muscles) {
      m.parameters.model = flatsos::muscles::muscle_model_named(model);
      m.parameters.model->setDefaults(m.parameters);
      m.parameters.passive_fiber_strain_at_one_norm_force = 0.0;
    }
  return std::make_shared<const flatsos::plugin::MusculoskeletalModel>(d);
}

// (muscle model, effort) pairs.
class CollocationDerivatives : public ::testing::TestWithParam<std::pair<std::string, std::string>> {
 protected:
  struct Arm {
    std::shared_ptr<const flatsos::plugin::MusculoskeletalModel> model;
    fpl::FlatOutputMap flat{model};
  } arm{arm_with(GetParam().first)};
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);

  // kind 0: along the plan's path; 1: the path free; 2: along it as a measured motion.
  fpd::HermiteSimpsonProblem problem(int kind) {
    const bool free = kind == 1;
    auto o = flatsos::test::open_loop_options();
    o.sos.bounds.enforce = false;
    // Reserves below the start's forces: De Groote's narrower active curve leaves the posterior
    // deltoid 0.84 N at the paper's initial activation, under the paper's 10 N.
    for (int j = 0; j < arm.model->numMuscles(); ++j)
      o.reserves_N[j] = std::min(o.reserves_N[j],
                                 0.5 * flatsos::muscles::tendon_force(arm.model->muscle(j).getParameters(), s0.tendon_length_m[j]));
    const auto plan = fpl::plan_open_loop(arm.flat, s0, o);
    // Its path is all the test needs; without bounds the plan may leave the muscles' domain.
    if (plan.path.numJoints() != arm.model->numJoints()) throw std::runtime_error("no flatness path: " + plan.message);
    auto ws = arm.flat.makeWorkspace();
    const std::string& effort = GetParam().second;
    const Eigen::VectorXd w = effort == "tendon_force" ? fpl::flat_output_effort_weights(arm.flat)
                                                       : Eigen::VectorXd::LinSpaced(arm.model->numMuscles(), 0.5, 2.0);
    std::optional<fpd::FreeJoints> joints;
    if (free) joints = fpd::free_joints(arm.flat, plan.path);
    // Two intervals, the second 1.5 times as long as the first: an interval's length taken from
    // the wrong interval shows in the derivatives.
    fpd::PathSamples samples = fpd::sample_path(arm.flat, ws, plan.path, 2, 1.5);
    if (kind == 2)  // arms that differ at every point, as posture-dependent ones do
      for (int i = 0; i < samples.time_s.size(); ++i)
        samples.moment_arms_at.push_back(samples.moment_arms_m * (1.0 + 0.1 * std::sin(1.0 + i)));
    return fpd::HermiteSimpsonProblem(fpd::collocation_muscles(arm.flat, s0, o.reserves_N, 0.0), std::move(samples),
                                      fpl::effort_named(effort, w), joints, kind == 2);
  }

  // The start, moved randomly: stretches by a few percent, activations and excitations inside
  // (0, 1), fibre velocities away from the kink of g'' at 0.
  static std::vector<double> random_point(const fpd::HermiteSimpsonProblem& p, unsigned seed) {
    std::vector<double> x(p.variables());
    p.startingPoint(x.data());
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    using H = fpd::HermiteSimpsonProblem;
    for (int i = 0; i < p.points(); ++i)
      for (int j = 0; j < p.muscles(); ++j) {
        x[p.index(i, j, H::kStretch)] *= 1.0 + 0.05 * (unit(rng) - 0.5);
        x[p.index(i, j, H::kActivation)] = 0.05 + 0.5 * unit(rng);
        x[p.index(i, j, H::kExcitation)] = 0.05 + 0.9 * unit(rng);
        x[p.index(i, j, H::kVelocity)] = (unit(rng) < 0.5 ? -1.0 : 1.0) * (0.05 + 0.2 * unit(rng));
      }
    if (p.freePath())  // angles within a few degrees of the path, speeds and accelerations of any
                       // sign
      for (int i = 0; i < p.points(); ++i)
        for (int r = 0; r < p.joints(); ++r) {
          x[p.jointIndex(i, r, H::kAngle)] += 0.1 * (unit(rng) - 0.5);
          x[p.jointIndex(i, r, H::kSpeed)] += 2.0 * (unit(rng) - 0.5);
          x[p.jointIndex(i, r, H::kAcceleration)] += 10.0 * (unit(rng) - 0.5);
        }
    return x;
  }

  static std::map<std::pair<int, int>, double> jacobian(const fpd::HermiteSimpsonProblem& p,
                                                        const std::vector<double>& x) {
    std::vector<double> values(p.jacobianNonzeros());
    p.jacobianValues(x.data(), values.data());
    std::map<std::pair<int, int>, double> J;
    for (std::size_t k = 0; k < values.size(); ++k)
      J[{p.jacobianRows()[k], p.jacobianColumns()[k]}] = values[k];
    return J;
  }
};

}  // namespace

TEST_P(CollocationDerivatives, ThePatternsHaveNoDuplicatesAndTheHessianIsLowerTriangular) {
  for (int kind : {0, 1, 2}) {
    SCOPED_TRACE(kind == 1 ? "free joint path" : kind == 2 ? "along a measured motion" : "prescribed joint path");
    const auto p = problem(kind);
    std::set<std::pair<int, int>> jac, hess;
    for (int k = 0; k < p.jacobianNonzeros(); ++k) {
      EXPECT_TRUE(jac.insert({p.jacobianRows()[k], p.jacobianColumns()[k]}).second)
          << "duplicate Jacobian entry " << k;
      EXPECT_LT(p.jacobianRows()[k], p.constraints());
      EXPECT_LT(p.jacobianColumns()[k], p.variables());
    }
    for (int k = 0; k < p.hessianNonzeros(); ++k) {
      EXPECT_TRUE(hess.insert({p.hessianRows()[k], p.hessianColumns()[k]}).second)
          << "duplicate Hessian entry " << k;
      EXPECT_GE(p.hessianRows()[k], p.hessianColumns()[k]);
    }
    if (kind == 0) {
      // 5 points x 6 muscles x 4 unknowns; 30 equilibrium rows, 4 x 2 torque rows (not at t = 0),
      // 2 intervals x 6 muscles x 4 defects, 6 rest rows.
      EXPECT_EQ(p.variables(), 120);
      EXPECT_EQ(p.constraints(), 30 + 8 + 48 + 6);
    } else if (kind == 2) {
      // torque rows at t = 0 too (no initial state fixes the forces there); the rest rows unbounded.
      EXPECT_EQ(p.variables(), 120);
      EXPECT_EQ(p.constraints(), 30 + 10 + 48 + 6);
    } else {
      // and 5 points x 2 joints x 3 unknowns; torque rows at all 5 points, 2 intervals x 2 joints
      // x 4 joint defects.
      EXPECT_EQ(p.variables(), 120 + 30);
      EXPECT_EQ(p.constraints(), 30 + 10 + 48 + 16 + 6);
    }
  }
}

TEST_P(CollocationDerivatives, TheObjectiveGradientMatchesFiniteDifferences) {
  for (int kind : {0, 1, 2}) {
    SCOPED_TRACE(kind == 1 ? "free joint path" : kind == 2 ? "along a measured motion" : "prescribed joint path");
    const auto p = problem(kind);
    std::vector<double> x = random_point(p, 1);
    std::vector<double> grad(p.variables());
    p.objectiveGradient(x.data(), grad.data());
    for (int v = 0; v < p.variables(); ++v) {
      auto f = [&](double xv) {
        std::vector<double> y = x;
        y[v] = xv;
        return p.objective(y.data());
      };
      const auto fd = central_difference(f, x[v], 1e-5);
      EXPECT_NEAR(grad[v], fd.estimate, fd.tolerance + 1e-9) << "variable " << v;
    }
  }
}

TEST_P(CollocationDerivatives, EveryJacobianEntryMatchesFiniteDifferences) {
  for (int kind : {0, 1, 2}) {
    SCOPED_TRACE(kind == 1 ? "free joint path" : kind == 2 ? "along a measured motion" : "prescribed joint path");
    const auto p = problem(kind);
    for (unsigned seed : {2u, 3u}) {
      std::vector<double> x = random_point(p, seed);
      const auto J = jacobian(p, x);
      std::vector<double> gp(p.constraints()), gm(p.constraints()), gp2(p.constraints()),
          gm2(p.constraints());
      int checked = 0;
      for (int v = 0; v < p.variables(); ++v) {
        const double h = 1e-5;  // rows such as A F - tau cancel larger terms: at 1e-6 their rounding reached the tolerance
        std::vector<double> y = x;
        y[v] = x[v] + h, p.constraintValues(y.data(), gp.data());
        y[v] = x[v] - h, p.constraintValues(y.data(), gm.data());
        y[v] = x[v] + 2 * h, p.constraintValues(y.data(), gp2.data());
        y[v] = x[v] - 2 * h, p.constraintValues(y.data(), gm2.data());
        for (int r = 0; r < p.constraints(); ++r) {
          const double d1 = (gp[r] - gm[r]) / (2 * h), d2 = (gp2[r] - gm2[r]) / (4 * h);
          const double tol =
              10.0 * (std::abs(d2 - d1) / 3.0 + 1e-16 * (std::abs(gp[r]) + 1.0) / h) + 1e-8;
          const auto it = J.find({r, v});
          const double analytic = it == J.end() ? 0.0 : it->second;
          EXPECT_NEAR(analytic, d1, tol) << "row " << r << ", variable " << v
                                         << (it == J.end() ? " (outside the pattern)" : "");
          checked += it != J.end();
        }
      }
      EXPECT_EQ(checked, p.jacobianNonzeros());
    }
  }
}

TEST_P(CollocationDerivatives, TheHessianOfTheLagrangianMatchesFiniteDifferencesOfTheGradients) {
  for (int kind : {0, 1, 2}) {
    SCOPED_TRACE(kind == 1 ? "free joint path" : kind == 2 ? "along a measured motion" : "prescribed joint path");
    const auto p = problem(kind);
    std::vector<double> x = random_point(p, 4);
    std::mt19937 rng(5);
    std::normal_distribution<double> normal;
    std::vector<double> lambda(p.constraints());
    for (double& l : lambda) l = normal(rng);
    const double sigma = 0.7;
    // The Lagrangian's gradient from the analytic first derivatives, and the sum of its terms'
    // magnitudes (what its rounding error scales with: the terms cancel).
    std::vector<double> magnitude(p.variables());
    auto lagrangian_gradient = [&](const std::vector<double>& y) {
      std::vector<double> grad(p.variables());
      p.objectiveGradient(y.data(), grad.data());
      for (int v = 0; v < p.variables(); ++v) grad[v] *= sigma, magnitude[v] = std::abs(grad[v]);
      std::vector<double> values(p.jacobianNonzeros());
      p.jacobianValues(y.data(), values.data());
      for (int k = 0; k < p.jacobianNonzeros(); ++k) {
        grad[p.jacobianColumns()[k]] += lambda[p.jacobianRows()[k]] * values[k];
        magnitude[p.jacobianColumns()[k]] += std::abs(lambda[p.jacobianRows()[k]] * values[k]);
      }
      return grad;
    };
    std::vector<double> values(p.hessianNonzeros());
    p.hessianValues(x.data(), sigma, lambda.data(), values.data());
    std::map<std::pair<int, int>, double> H;
    for (int k = 0; k < p.hessianNonzeros(); ++k)
      H[{p.hessianRows()[k], p.hessianColumns()[k]}] = values[k];
    for (int v = 0; v < p.variables(); ++v) {
      const double h = 1e-5;  // as above: at 1e-6 the gradients' rounding reached the tolerance
      std::vector<double> y = x;
      y[v] = x[v] + h;
      const auto gp = lagrangian_gradient(y);
      y[v] = x[v] - h;
      const auto gm = lagrangian_gradient(y);
      y[v] = x[v] + 2 * h;
      const auto gp2 = lagrangian_gradient(y);
      y[v] = x[v] - 2 * h;
      const auto gm2 = lagrangian_gradient(y);
      for (int w = 0; w < p.variables(); ++w) {
        const double d1 = (gp[w] - gm[w]) / (2 * h), d2 = (gp2[w] - gm2[w]) / (4 * h);
        const double tol =
            10.0 * (std::abs(d2 - d1) / 3.0 + 1e-16 * (magnitude[w] + 1.0) / h) + 1e-7;
        const auto it = H.find({std::max(v, w), std::min(v, w)});
        EXPECT_NEAR(it == H.end() ? 0.0 : it->second, d1, tol)
            << "entry (" << w << ", " << v << ")";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    MuscleModelsAndEfforts, CollocationDerivatives,
    ::testing::Values(std::pair<std::string, std::string>{"richter_warner", "tendon_force"},
                      std::pair<std::string, std::string>{"thelen2003", "tendon_force"},
                      std::pair<std::string, std::string>{"degroote_fregly2016", "tendon_force"},
                      std::pair<std::string, std::string>{"richter_warner", "excitation_squared"},
                      std::pair<std::string, std::string>{"richter_warner", "activation_cubed"},
                      std::pair<std::string, std::string>{"degroote_fregly2016", "stress_squared"}),
    [](const ::testing::TestParamInfo<std::pair<std::string, std::string>>& param) {
      return param.param.first + "_" + param.param.second;
    });
