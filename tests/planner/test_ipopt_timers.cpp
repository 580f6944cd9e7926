// Ipopt's CPU timers are served by flatsos (numerics/ipopt_support.cpp): libipopt's own calls of
// CpuTime reach the monotonic wall clock, not getrusage. A problem whose objective sleeps makes
// the difference visible: a sleeping process uses no CPU time, so only the replacement counts
// the sleep in Ipopt's statistics.
#include <gtest/gtest.h>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include <chrono>
#include <thread>

namespace {

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
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
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

}  // namespace

TEST(IpoptTimers, IpoptsCpuClockIsTheMonotonicWallClock) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  ASSERT_EQ(app->Initialize(""), Ipopt::Solve_Succeeded);
  ASSERT_EQ(app->OptimizeTNLP(new SleepyQuadratic), Ipopt::Solve_Succeeded);
  // getrusage would count (almost) none of the 50 ms asleep.
  EXPECT_GE(app->Statistics()->TotalCpuTime(), 0.045);
  EXPECT_EQ(app->Statistics()->TotalSysTime(), 0.0);
}
