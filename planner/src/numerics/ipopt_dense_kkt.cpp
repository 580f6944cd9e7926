#include "numerics/ipopt_dense_kkt.hpp"

#include <HSLLoader.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include "flatsos/planner/numerics/ipopt_linear_solver.hpp"
#include "numerics/condensed_kkt.hpp"
#include "numerics/dense_ldlt.hpp"
#include "numerics/sparse_kkt.hpp"

namespace flatsos::planner::detail {
namespace {

static_assert(std::is_same_v<ipfint, int>, "Ipopt's Fortran integer is not int: the slot's signatures differ");

// Three ways to factor, chosen by the analysis and kept in ikeep[0] (ikeep lives from the analysis
// to every factorization) and iw[0] (from a factorization to its solves):
//   dense:     the whole matrix by the dense LDL^T; iw: mode, the factor's offset in the real
//              workspace, n, then n pivots;
//   condensed: above kDenseKktMaxDimension, when the matrix has inequality rows' slack and
//              multiplier pairs, those eliminated first (numerics/condensed_kkt.hpp); ikeep:
//              mode, core, pairs, couplings, then the n roles; iw: mode, the factor's offset,
//              then the condensed factor's integers.
//   sparse:    on request (set_sparse_kkt_primal_rows), the sparse LDL^T in time order; ikeep:
//              mode, the factor's serial number, the primal rows; iw: mode, serial number.
enum Mode : int { kDense = 0, kCondensed = 1, kSparse = 2 };
constexpr int kHeader = 3;
constexpr int kCondensedHeader = 2;
constexpr int kKeepHeader = 5;  // mode, core, pairs, couplings, the analysis' serial number

// The condensed factorizations' scatter plans (condensed_kkt.hpp), one per analysis, found by the
// serial number the analysis leaves in ikeep (the slot's calls carry no other state). The most
// recent few are kept; a factorization whose plan was dropped builds it again from the triplets.
class ScatterPlans {
 public:
  int add(std::shared_ptr<const CondensedScatter> plan) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const int serial = next_serial_++;
    if (next_serial_ == INT_MAX) next_serial_ = 0;
    keep(serial, std::move(plan));
    return serial;
  }
  std::shared_ptr<const CondensedScatter> find(int serial) const {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [s, plan] : plans_)
      if (s == serial) return plan;
    return nullptr;
  }
  void replace(int serial, std::shared_ptr<const CondensedScatter> plan) {
    const std::lock_guard<std::mutex> lock(mutex_);
    keep(serial, std::move(plan));
  }

 private:
  // Enough for a few threads' solves at once (more only rebuild plans). Each plan holds 16 bytes
  // per triplet: about 5 MB for the arm's free path at 160 points, so at most a few tens of MB
  // stay behind after the solves.
  static constexpr std::size_t kKept = 4;
  void keep(int serial, std::shared_ptr<const CondensedScatter> plan) {
    plans_.erase(std::remove_if(plans_.begin(), plans_.end(), [&](const auto& e) { return e.first == serial; }),
                 plans_.end());
    plans_.emplace_back(serial, std::move(plan));
    if (plans_.size() > kKept) plans_.erase(plans_.begin());
  }
  mutable std::mutex mutex_;
  int next_serial_ = 0;
  std::vector<std::pair<int, std::shared_ptr<const CondensedScatter>>> plans_;
};

ScatterPlans& scatter_plans() {
  static ScatterPlans plans;
  return plans;
}

// The sparse factors, found by the serial number their analysis leaves in ikeep and their
// factorization in iw (the factor lives here, not in Ipopt's arrays). Solves are serialized by
// the Ipopt session lock; the most recent few are kept, and a factorization whose entry was
// dropped analyses its pattern again.
class SparseFactors {
 public:
  int add(std::unique_ptr<SparseKkt> kkt) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const int serial = next_serial_++;
    if (next_serial_ == INT_MAX) next_serial_ = 0;
    keep(serial, std::move(kkt));
    return serial;
  }
  SparseKkt* find(int serial) {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (auto& [s, kkt] : kept_)
      if (s == serial) return kkt.get();
    return nullptr;
  }
  SparseKkt* replace(int serial, std::unique_ptr<SparseKkt> kkt) {
    const std::lock_guard<std::mutex> lock(mutex_);
    SparseKkt* raw = kkt.get();
    keep(serial, std::move(kkt));
    return raw;
  }

 private:
  static constexpr std::size_t kKept = 4;
  void keep(int serial, std::unique_ptr<SparseKkt> kkt) {
    kept_.erase(std::remove_if(kept_.begin(), kept_.end(), [&](const auto& e) { return e.first == serial; }), kept_.end());
    kept_.emplace_back(serial, std::move(kkt));
    if (kept_.size() > kKept) kept_.erase(kept_.begin());
  }
  std::mutex mutex_;
  int next_serial_ = 0;
  std::vector<std::pair<int, std::unique_ptr<SparseKkt>>> kept_;
};

SparseFactors& sparse_factors() {
  static SparseFactors factors;
  return factors;
}

thread_local int sparse_primal_rows_on_thread = 0;

// A pivot column is zero when its largest entry is below this fraction of the matrix's largest:
// only cancellation to rounding level of exactly dependent rows, as MUMPS (and MA27 with its
// default zero-pivot threshold 0) report singular only for exact zeros. Ipopt's KKT entries
// span 1e-10 to 1e10, so anything coarser would call regular matrices singular.
const double kRelativeZeroPivot = std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();

std::int64_t real_workspace(std::int64_t n, std::int64_t nz) { return nz + n * n; }

}  // namespace

void dense_kkt_defaults(int* icntl, double* cntl) {
  std::fill(icntl, icntl + 30, 0);
  std::fill(cntl, cntl + 5, 0.0);
}

void dense_kkt_analyse(int* n, int* nz, const int* irn, const int* icn, int* /*iw*/, int* /*liw*/,
                       int* ikeep, int* /*iw1*/, int* nsteps, int* iflag, int* /*icntl*/,
                       double* /*cntl*/, int* info, double* ops) {
  std::fill(info, info + 20, 0);
  *nsteps = 1;  // Ipopt sizes a scratch array by it; the dense solve needs none
  *ops = 0.0;
  if (*n < 1 || *nz < 0) {
    info[0] = *iflag = -1;
    info[1] = *n;
    return;
  }
  for (ipfint e = 0; e < *nz; ++e)
    if (irn[e] < 1 || irn[e] > *n || icn[e] < 1 || icn[e] > *n) {
      info[0] = *iflag = 1;
      info[1] = e + 1;
      return;
    }
  ikeep[0] = kDense;
  if (*n > kDenseKktMaxDimension && sparse_primal_rows_on_thread > 0) {
    ikeep[0] = kSparse;
    ikeep[2] = std::min(sparse_primal_rows_on_thread, *n);
    ikeep[1] = sparse_factors().add(analyse_sparse_kkt(*n, *nz, irn, icn, ikeep[2]));
    info[4] = std::max(*nz, 1);  // Ipopt's values only: the factor is kept apart
    info[5] = kHeader;
    *ops = 0.0;
    return;
  }
  if (*n > kDenseKktMaxDimension) {
    CondensedPattern p = find_eliminable_pairs(*n, *nz, irn, icn);
    const std::int64_t reals = *nz + condensed_real_workspace(p), integers = kCondensedHeader + condensed_integer_workspace(p);
    auto scatter = std::make_shared<CondensedScatter>();
    if (p.pairs > 0 && reals <= INT_MAX && integers <= INT_MAX &&
        build_condensed_scatter(*n, *nz, irn, icn, p, *scatter)) {
      ikeep[0] = kCondensed;
      ikeep[1] = p.core;
      ikeep[2] = p.pairs;
      ikeep[3] = static_cast<int>(p.couplings);
      ikeep[4] = scatter_plans().add(std::move(scatter));
      std::copy(p.role.begin(), p.role.end(), ikeep + kKeepHeader);
      info[4] = static_cast<int>(reals);
      info[5] = static_cast<int>(integers);
      *ops = static_cast<double>(p.core) * p.core * p.core / 3.0;
      return;
    }
  }
  const std::int64_t need = real_workspace(*n, *nz);
  if (need > INT_MAX) {  // too large for one dense factor
    info[0] = *iflag = -1;
    info[1] = *n;
    return;
  }
  info[4] = static_cast<int>(need);
  info[5] = kHeader + *n;
  *ops = static_cast<double>(*n) * *n * *n / 3.0;
}

namespace {

void factor_condensed_into(int n, int nz, const int* irn, const int* icn, double* a, int la, int* iw, int liw,
                           const int* ikeep, int* maxfrt, int* info) {
  CondensedPattern p;
  p.core = ikeep[1];
  p.pairs = ikeep[2];
  p.couplings = ikeep[3];
  const std::int64_t reals = nz + condensed_real_workspace(p), integers = kCondensedHeader + condensed_integer_workspace(p);
  if (liw < integers) {
    info[0] = -3;
    info[1] = static_cast<int>(integers);
    return;
  }
  if (la < reals) {
    info[0] = -4;
    info[1] = static_cast<int>(reals);
    return;
  }
  iw[0] = kCondensed;
  iw[1] = nz;
  std::shared_ptr<const CondensedScatter> scatter = scatter_plans().find(ikeep[4]);
  // Built again when it was dropped; triplets that are not its pattern are refused by the build.
  if (!scatter || !same_pattern(*scatter, nz, irn, icn)) {
    auto rebuilt = std::make_shared<CondensedScatter>();
    p.role.assign(ikeep + kKeepHeader, ikeep + kKeepHeader + n);
    if (!build_condensed_scatter(n, nz, irn, icn, p, *rebuilt)) {
      info[0] = -1;  // the triplets are not the analysed pattern
      return;
    }
    scatter = rebuilt;
    scatter_plans().replace(ikeep[4], std::move(rebuilt));
  }
  Inertia inertia;
  factor_condensed(*scatter, a, iw + kCondensedHeader, a + nz, inertia);
  *maxfrt = std::max(1, p.core);  // Ipopt allocates the solve's scratch vector of this length
  info[0] = inertia.zero > 0 ? 3 : 0;
  info[1] = n - inertia.zero;
  info[14] = inertia.negative;
}

void factor_sparse_into(int n, int nz, const int* irn, const int* icn, const double* a, int* iw, int liw,
                        const int* ikeep, int* maxfrt, int* info) {
  if (liw < kHeader) {
    info[0] = -3;
    info[1] = kHeader;
    return;
  }
  SparseKkt* kkt = sparse_factors().find(ikeep[1]);
  if (!kkt || kkt->n != n || !same_sparse_pattern(*kkt, nz, irn, icn))
    kkt = sparse_factors().replace(ikeep[1], analyse_sparse_kkt(n, nz, irn, icn, ikeep[2]));
  int negative = 0;
  const bool regular = factor_sparse_kkt(*kkt, a, negative);
  iw[0] = kSparse;
  iw[1] = ikeep[1];
  *maxfrt = 1;  // Ipopt allocates the solve's scratch vector of this length; the solve needs none
  info[0] = regular ? 0 : 3;
  info[1] = regular ? n : n - 1;
  info[14] = negative;
}

}  // namespace

void dense_kkt_factor(int* n, int* nz, const int* irn, const int* icn, double* a, int* la, int* iw,
                      int* liw, int* ikeep, int* /*nsteps*/, int* maxfrt, int* /*iw1*/,
                      int* /*icntl*/, double* /*cntl*/, int* info) {
  std::fill(info, info + 20, 0);
  if (ikeep[0] == kCondensed) {
    factor_condensed_into(*n, *nz, irn, icn, a, *la, iw, *liw, ikeep, maxfrt, info);
    return;
  }
  if (ikeep[0] == kSparse) {
    factor_sparse_into(*n, *nz, irn, icn, a, iw, *liw, ikeep, maxfrt, info);
    return;
  }
  const int dim = *n, entries = *nz;
  const std::int64_t need = real_workspace(dim, entries);
  if (*liw < kHeader + dim) {
    info[0] = -3;
    info[1] = kHeader + dim;
    return;
  }
  if (*la < need) {
    info[0] = -4;
    info[1] = static_cast<int>(need);
    return;
  }
  // Assemble the lower triangle behind the values Ipopt wrote (which it rewrites before every
  // factorization), summing duplicates.
  double* dense = a + entries;
  std::fill(dense, dense + static_cast<std::int64_t>(dim) * dim, 0.0);
  double largest = 0.0;
  for (int e = 0; e < entries; ++e) {
    const int i = irn[e] - 1, j = icn[e] - 1;
    dense[static_cast<std::int64_t>(std::min(i, j)) * dim + std::max(i, j)] += a[e];
  }
  for (int j = 0; j < dim; ++j)
    for (int i = j; i < dim; ++i) largest = std::max(largest, std::abs(dense[static_cast<std::int64_t>(j) * dim + i]));

  int* pivots = iw + kHeader;
  const Inertia inertia = factor_ldlt_in_place(dense, dim, pivots, kRelativeZeroPivot * largest);
  iw[0] = kDense;
  iw[1] = entries;
  iw[2] = dim;
  *maxfrt = dim;  // Ipopt allocates a scratch vector of this length for the solve
  info[0] = inertia.zero > 0 ? 3 : 0;
  info[1] = dim - inertia.zero;
  info[8] = static_cast<int>(static_cast<std::int64_t>(dim) * dim);
  info[9] = dim;
  info[14] = inertia.negative;
}

void dense_kkt_solve(int* n, double* a, int* /*la*/, int* iw, int* /*liw*/, double* w,
                     int* /*maxfrt*/, double* rhs, int* /*iw1*/, int* /*nsteps*/, int* /*icntl*/,
                     double* /*cntl*/) {
  if (iw[0] == kCondensed) {
    solve_condensed(iw + kCondensedHeader, a + iw[1], rhs, w);
    return;
  }
  if (iw[0] == kSparse) {
    if (SparseKkt* kkt = sparse_factors().find(iw[1])) solve_sparse_kkt(*kkt, rhs);
    else std::fill(rhs, rhs + *n, std::numeric_limits<double>::quiet_NaN());  // dropped: Ipopt sees the failure
    return;
  }
  solve_ldlt_in_place(a + iw[1], *n, iw + kHeader, rhs);
}

namespace {
int slot_claims = 0;  // guarded by the Ipopt session lock
}  // namespace

bool claim_dense_kkt_slot() {
  if (slot_claims == 0) {
    if (LSL_isMA27available()) return false;  // someone else's MA27
    LSL_setMA27(&dense_kkt_analyse, &dense_kkt_factor, &dense_kkt_solve, &dense_kkt_defaults);
  }
  ++slot_claims;
  return true;
}

int set_sparse_kkt_primal_rows(int primal_rows) {
  const int previous = sparse_primal_rows_on_thread;
  sparse_primal_rows_on_thread = primal_rows;
  return previous;
}

void return_dense_kkt_slot() {
  if (slot_claims == 0) return;
  if (--slot_claims == 0) LSL_setMA27(nullptr, nullptr, nullptr, nullptr);
}

}  // namespace flatsos::planner::detail
