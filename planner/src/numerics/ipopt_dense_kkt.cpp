#include "numerics/ipopt_dense_kkt.hpp"

#include <HSLLoader.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <type_traits>

#include "numerics/dense_ldlt.hpp"

namespace flatsos::planner::detail {
namespace {

static_assert(std::is_same_v<ipfint, int>, "Ipopt's Fortran integer is not int: the slot's signatures differ");

// Integer workspace: the factor's offset in the real workspace, n, then n pivots.
constexpr int kHeader = 2;

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
                       int* /*ikeep*/, int* /*iw1*/, int* nsteps, int* iflag, int* /*icntl*/,
                       double* /*cntl*/, int* info, double* ops) {
  std::fill(info, info + 20, 0);
  *nsteps = 1;  // Ipopt sizes a scratch array by it; the dense solve needs none
  *ops = 0.0;
  const std::int64_t need = real_workspace(*n, *nz);
  if (*n < 1 || *nz < 0 || need > INT_MAX) {  // too large for one dense factor
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
  info[4] = static_cast<int>(need);
  info[5] = kHeader + *n;
  *ops = static_cast<double>(*n) * *n * *n / 3.0;
}

void dense_kkt_factor(int* n, int* nz, const int* irn, const int* icn, double* a, int* la, int* iw,
                      int* liw, int* /*ikeep*/, int* /*nsteps*/, int* maxfrt, int* /*iw1*/,
                      int* /*icntl*/, double* /*cntl*/, int* info) {
  std::fill(info, info + 20, 0);
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
  iw[0] = entries;
  iw[1] = dim;
  *maxfrt = dim;  // Ipopt allocates a scratch vector of this length for the solve
  info[0] = inertia.zero > 0 ? 3 : 0;
  info[1] = dim - inertia.zero;
  info[8] = static_cast<int>(static_cast<std::int64_t>(dim) * dim);
  info[9] = dim;
  info[14] = inertia.negative;
}

void dense_kkt_solve(int* n, double* a, int* /*la*/, int* iw, int* /*liw*/, double* /*w*/,
                     int* /*maxfrt*/, double* rhs, int* /*iw1*/, int* /*nsteps*/, int* /*icntl*/,
                     double* /*cntl*/) {
  solve_ldlt_in_place(a + iw[0], *n, iw + kHeader, rhs);
}

void register_dense_kkt_solver() {
  static std::once_flag once;
  std::call_once(once, [] { LSL_setMA27(&dense_kkt_analyse, &dense_kkt_factor, &dense_kkt_solve, &dense_kkt_defaults); });
}

}  // namespace flatsos::planner::detail
