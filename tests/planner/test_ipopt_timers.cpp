// What flatsos changes in Ipopt's process-wide state is scoped to its own solves
// (numerics/ipopt_support.cpp, numerics/ipopt_dense_kkt.cpp). Inside them libipopt's calls of
// CpuTime reach the monotonic wall clock, not getrusage, and its ma27 slot holds flatsos's dense
// solver; outside them another library's Ipopt problem meets Ipopt's own timers and an empty
// slot. A problem whose objective sleeps makes the timers visible: a sleeping process uses no CPU
// time, so only the monotonic clock counts the sleep in Ipopt's statistics.
#include <gtest/gtest.h>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>
#include <HSLLoader.h>

#include <chrono>
#include <thread>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "numerics/ipopt_support.hpp"

namespace {

// The sleep is long beside the CPU time of a solve: under the sanitizers on a busy machine
// Ipopt's own work took 57 ms of CPU time (CI, session 47), more than a 50 ms sleep.
constexpr double kSleepSeconds = 0.3;

// minimize (x - 1)^2 over x in [-10, 10]; the first evaluation of f sleeps.
class SleepyQuadratic : public Ipopt::TNLP {
 public:
  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = 1;
    m = 0;
    nnz_jac = 0;
    nnz_h = 1;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index, Ipopt::Number*,
                       Ipopt::Number*) override {
    xl[0] = -10.0;
    xu[0] = 10.0;
    return true;
  }
  bool get_starting_point(Ipopt::Index, bool, Ipopt::Number* x, bool, Ipopt::Number*, Ipopt::Number*, Ipopt::Index,
                          bool, Ipopt::Number*) override {
    x[0] = 0.0;
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    if (!slept_) {
      std::this_thread::sleep_for(std::chrono::duration<double>(kSleepSeconds));
      slept_ = true;
    }
    f = (x[0] - 1.0) * (x[0] - 1.0);
    return true;
  }
  bool eval_grad_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number* g) override {
    g[0] = 2.0 * (x[0] - 1.0);
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Number*) override { return true; }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Index, Ipopt::Index, Ipopt::Index*, Ipopt::Index*,
                  Ipopt::Number*) override {
    return true;
  }
  bool eval_h(Ipopt::Index, const Ipopt::Number*, bool, Ipopt::Number obj_factor, Ipopt::Index, const Ipopt::Number*,
              bool, Ipopt::Index, Ipopt::Index* rows, Ipopt::Index* cols, Ipopt::Number* values) override {
    if (values == nullptr) {
      rows[0] = 0;
      cols[0] = 0;
    } else {
      values[0] = 2.0 * obj_factor;
    }
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number*, const Ipopt::Number*,
                         const Ipopt::Number*, Ipopt::Index, const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {}

 private:
  bool slept_ = false;
};

// A plain Ipopt application, as another library in the process makes one.
Ipopt::SmartPtr<Ipopt::IpoptApplication> plain_ipopt(const char* linear_solver) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("linear_solver", linear_solver);
  return app;
}

}  // namespace

TEST(IpoptProcessState, InsideFlatsosSolvesIpoptsCpuClockIsTheMonotonicWallClock) {
  flatsos::planner::set_ipopt_linear_solver(flatsos::planner::IpoptLinearSolver::Automatic);
  Ipopt::SmartPtr<Ipopt::TNLP> nlp = new SleepyQuadratic;
  {
    const flatsos::planner::detail::IpoptSession session = flatsos::planner::detail::make_ipopt(1e-8, 100, *nlp);
    EXPECT_TRUE(flatsos::planner::detail::FlatsosSolveScope::active());
    ASSERT_EQ(session.linear_solver, flatsos::planner::IpoptLinearSolver::DenseLdlt);  // 1 variable
    EXPECT_TRUE(LSL_isMA27available());
    ASSERT_EQ(session->OptimizeTNLP(nlp), Ipopt::Solve_Succeeded);
    // getrusage would count (almost) none of the time asleep.
    EXPECT_GE(session->Statistics()->TotalCpuTime(), 0.95 * kSleepSeconds);
    EXPECT_EQ(session->Statistics()->TotalSysTime(), 0.0);
  }
  EXPECT_FALSE(flatsos::planner::detail::FlatsosSolveScope::active());
  EXPECT_FALSE(LSL_isMA27available());  // the slot is emptied with the session
}

TEST(IpoptProcessState, AnotherIpoptProblemKeepsIpoptsOwnTimers) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = plain_ipopt("mumps");
  ASSERT_EQ(app->Initialize(""), Ipopt::Solve_Succeeded);
  ASSERT_EQ(app->OptimizeTNLP(new SleepyQuadratic), Ipopt::Solve_Succeeded);
  // getrusage's user time: the time asleep is not in it.
  EXPECT_LT(app->Statistics()->TotalCpuTime(), 0.5 * kSleepSeconds);
  EXPECT_GE(app->Statistics()->TotalCpuTime(), 0.0);
}

TEST(IpoptProcessState, AnotherIpoptProblemFindsTheMa27SlotEmptyAfterAFlatsosSolve) {
  flatsos::planner::set_ipopt_linear_solver(flatsos::planner::IpoptLinearSolver::Automatic);
  {  // a flatsos solve with its dense solver in the slot
    Ipopt::SmartPtr<Ipopt::TNLP> nlp = new SleepyQuadratic;
    const flatsos::planner::detail::IpoptSession session = flatsos::planner::detail::make_ipopt(1e-8, 100, *nlp);
    ASSERT_EQ(session->OptimizeTNLP(nlp), Ipopt::Solve_Succeeded);
  }
  // Ipopt's own behaviour without HSL: asking for ma27 fails instead of running flatsos's code.
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = plain_ipopt("ma27");
  ASSERT_EQ(app->Initialize(""), Ipopt::Solve_Succeeded);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(new SleepyQuadratic);
  EXPECT_NE(status, Ipopt::Solve_Succeeded);
  EXPECT_NE(status, Ipopt::Solved_To_Acceptable_Level);
  EXPECT_FALSE(LSL_isMA27available());
}
