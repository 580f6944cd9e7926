// The whole SOS program as one Ipopt problem (sos/whole_program_nlp.hpp): its derivatives against
// finite differences, and the same optimum as the exchange method on the paper's quartic open
// loop (and a quintic on three spans), every piece certified by its own factors, from a strictly
// feasible start that is not the optimum.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "flatsos/planner/open_loop_study.hpp"
#include "scenario_fixture.hpp"
#include "sos/whole_program_nlp.hpp"

namespace fpl = flatsos::planner;
namespace fd = flatsos::planner::detail;

namespace {

// Two blocks (h = 2 and h = 3) on three free coefficients, random data.
struct SmallProgram {
  std::vector<fd::SquaresBlock> blocks;
  Eigen::VectorXd cost = Eigen::VectorXd::Random(3);
  int n = 3, m = 0;
  SmallProgram() {
    for (int h : {2, 3}) {
      fd::SquaresBlock b;
      b.half = h;
      b.base = Eigen::VectorXd::Random(b.rows());
      b.G = Eigen::MatrixXd::Random(b.rows(), 3);
      b.G(1, 2) = 0.0;  // a structural zero
      b.var_offset = n;
      b.con_offset = m;
      n += 2 * h + 1;
      m += b.rows();
      blocks.push_back(b);
    }
  }
};

}  // namespace

TEST(WholeProgramNlpDerivatives, JacobianAndHessianMatchCentralDifferences) {
  std::srand(7);
  const SmallProgram p;
  const Eigen::VectorXd x = Eigen::VectorXd::Random(p.n), center = Eigen::VectorXd::Random(p.n);
  const Eigen::VectorXd lambda = Eigen::VectorXd::Random(p.m), rho = Eigen::VectorXd::Random(p.n).cwiseAbs();
  Ipopt::SmartPtr<Ipopt::TNLP> nlp = fd::make_whole_program_nlp(p.blocks, p.cost, center, lambda, rho);
  Ipopt::Index n, m, nnz_jac, nnz_h;
  Ipopt::TNLP::IndexStyleEnum style;
  ASSERT_TRUE(nlp->get_nlp_info(n, m, nnz_jac, nnz_h, style));
  ASSERT_EQ(n, p.n);
  ASSERT_EQ(m, p.m);
  std::vector<Ipopt::Index> jr(nnz_jac), jc(nnz_jac), hr(nnz_h), hc(nnz_h);
  std::vector<double> jv(nnz_jac), hv(nnz_h);
  nlp->eval_jac_g(n, x.data(), true, m, nnz_jac, jr.data(), jc.data(), nullptr);
  nlp->eval_jac_g(n, x.data(), true, m, nnz_jac, nullptr, nullptr, jv.data());
  const double obj_factor = 0.7;
  nlp->eval_h(n, x.data(), true, obj_factor, m, lambda.data(), true, nnz_h, hr.data(), hc.data(), nullptr);
  nlp->eval_h(n, x.data(), true, obj_factor, m, lambda.data(), true, nnz_h, nullptr, nullptr, hv.data());

  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, n), H = Eigen::MatrixXd::Zero(n, n);
  for (int e = 0; e < nnz_jac; ++e) J(jr[e], jc[e]) += jv[e];
  for (int e = 0; e < nnz_h; ++e) {
    ASSERT_GE(hr[e], hc[e]) << "lower triangle only";
    H(hr[e], hc[e]) += hv[e];
    if (hr[e] != hc[e]) H(hc[e], hr[e]) += hv[e];
  }
  // Central differences of g and of the Lagrangian's gradient obj_factor grad f + J^T lambda.
  auto g_at = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd g(m);
    nlp->eval_g(n, y.data(), true, m, g.data());
    return g;
  };
  auto lagrangian_gradient = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd grad(n);
    nlp->eval_grad_f(n, y.data(), true, grad.data());
    std::vector<double> v(nnz_jac);
    nlp->eval_jac_g(n, y.data(), true, m, nnz_jac, nullptr, nullptr, v.data());
    Eigen::VectorXd out = obj_factor * grad;
    for (int e = 0; e < nnz_jac; ++e) out[jc[e]] += v[e] * lambda[jr[e]];
    return out;
  };
  const double h = 1e-6;
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd up = x, down = x;
    up[i] += h;
    down[i] -= h;
    const Eigen::VectorXd dg = (g_at(up) - g_at(down)) / (2 * h);
    const Eigen::VectorXd dl = (lagrangian_gradient(up) - lagrangian_gradient(down)) / (2 * h);
    EXPECT_LT((dg - J.col(i)).cwiseAbs().maxCoeff(), 1e-8) << "Jacobian column " << i;
    EXPECT_LT((dl - H.col(i)).cwiseAbs().maxCoeff(), 1e-8) << "Hessian column " << i;
  }
  // The cost and its gradient: c^T theta + (1/2) sum rho (x - center)^2.
  double f = 0.0;
  nlp->eval_f(n, x.data(), true, f);
  const double expected = p.cost.dot(x.head(3)) + 0.5 * (rho.array() * (x - center).array().square()).sum();
  EXPECT_NEAR(f, expected, 1e-12);
}

class WholeProgramNlp : public ::testing::Test {
 protected:
  flatsos::test::ArmPlanning arm;
  fpl::MuscleState s0 = flatsos::test::open_loop_initial_state(*arm.model);

  /// Returns the NLP's Ipopt calls (0 when a check failed before they were known).
  int expect_same_optimum(fpl::OpenLoopOptions options, const char* what) {
    const auto exchange = fpl::plan_open_loop(arm.flat, s0, options);
    EXPECT_EQ(exchange.status, fpl::SolveStatus::Solved) << exchange.message;
    if (exchange.status != fpl::SolveStatus::Solved) return 0;
    fpl::OpenLoopStudyOptions whole;
    whole.sos.method = fpl::SosProgramMethod::WholeProgramNlp;
    const auto nlp = fpl::plan_open_loop(arm.flat, s0, options, whole);
    EXPECT_EQ(nlp.status, fpl::SolveStatus::Solved) << nlp.message;
    if (nlp.status != fpl::SolveStatus::Solved) return 0;
    std::printf("%s: exchange %.9f N s, whole-program NLP %.9f N s (%d Ipopt iterations in %d rounds, %d variables, "
                "%d equalities, %.1f ms, certificate residual %.1e N)\n",
                what, exchange.sos.cost_N_s, nlp.sos.cost_N_s, nlp.sos.ipopt_iterations, nlp.sos.ipopt_calls,
                nlp.sos.nlp_variables, nlp.sos.nlp_equalities, 1e3 * nlp.sos.solve_seconds,
                nlp.sos.max_certificate_residual_N);
    EXPECT_NEAR(nlp.sos.cost_N_s, exchange.sos.cost_N_s, 1e-6 * exchange.sos.cost_N_s);
    EXPECT_TRUE(nlp.sos.certified) << nlp.sos.certified_pieces << " of " << nlp.sos.near_active_pieces;
    EXPECT_EQ(nlp.sos.certified_pieces, nlp.sos.near_active_pieces);
    EXPECT_LE(nlp.sos.max_certificate_residual_N, 1e-9);
    EXPECT_GE(nlp.sos.min_constraint_value_N, -2e-9);
    // No Gram freedom: the factors have as many entries as the matched coefficients, so the
    // free coefficients theta are all the problem's degrees of freedom.
    EXPECT_GT(nlp.sos.nlp_variables, nlp.sos.nlp_equalities);
    EXPECT_LE(nlp.sos.nlp_variables - nlp.sos.nlp_equalities, 2 * 8);
    EXPECT_GT(nlp.sos.ipopt_calls, 1);  // the proximal rounds
    EXPECT_EQ(nlp.sos.exchange_rounds, 0);
    // The plan the NLP's flat outputs give meets every reserve on the check grid, as the exchange's does.
    EXPECT_GE(nlp.check.min_reserve_margin_N, -1e-8);
    return nlp.sos.ipopt_calls;
  }
};

TEST_F(WholeProgramNlp, ReachesTheExchangeOptimumOnThePapersQuartic) {
  expect_same_optimum(flatsos::test::open_loop_options(), "quartic, 1 span, 3 s");
}

TEST_F(WholeProgramNlp, ReachesTheExchangeOptimumOnAQuinticOnThreeSpans) {
  auto options = flatsos::test::open_loop_options(2.0, 5, 3);
  options.sos.bounds.enforce = false;
  expect_same_optimum(options, "quintic, 3 spans, 2 s");
}

// Two programs the first formulation failed on. On 2 spans the constraint polynomials have 7
// coefficients but degree 4: blocks sized by the count (degree 6) had to cancel their top
// coefficients, f and g shared a root at infinity, and restoration failed in the first round.
TEST_F(WholeProgramNlp, ReachesTheExchangeOptimumOnAQuarticOnTwoSpans) {
  auto options = flatsos::test::open_loop_options(3.0, 4, 2);
  options.sos.bounds.enforce = false;
  expect_same_optimum(options, "quartic, 2 spans, 3 s");
}

TEST_F(WholeProgramNlp, ReachesTheExchangeOptimumOnThePapersQuarticWithThirtyTorquePieces) {
  auto options = flatsos::test::open_loop_options();
  options.torque.pieces = 30;
  expect_same_optimum(options, "quartic, 30 torque pieces, 3 s");
}

// A program on which a tenfold fall of the proximal weight fails in one round: the round is
// tried again from the same point with a smaller fall, so more rounds than the seven of the
// tenfold schedule.
TEST_F(WholeProgramNlp, ARoundThatFailsIsTriedAgainWithASmallerFall) {
  auto options = flatsos::test::open_loop_options(1.5, 6, 1);
  options.sos.bounds.enforce = false;
  const int calls = expect_same_optimum(options, "sextic, 1 span, 1.5 s");
  EXPECT_GT(calls, 7);
}
