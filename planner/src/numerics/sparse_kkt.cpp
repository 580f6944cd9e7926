#include "numerics/sparse_kkt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace flatsos::planner::detail {

namespace {

// As the dense slot: only a pivot at rounding level of the matrix's largest entry is zero.
const double kRelativeZeroPivot =
    std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();

// Each index's place: primal indices in their order, each other index right after the last
// primal index its row touches (at the end when it touches none).
std::vector<int> interleaved_order(int n, int nz, const int* irn, const int* icn, int primal) {
  std::vector<double> key(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) key[static_cast<std::size_t>(i)] = i < primal ? i : -1.0;
  for (int e = 0; e < nz; ++e) {
    const int i = irn[e] - 1, j = icn[e] - 1;
    if (i >= primal && j < primal)
      key[static_cast<std::size_t>(i)] = std::max(key[static_cast<std::size_t>(i)], j + 0.5);
    if (j >= primal && i < primal)
      key[static_cast<std::size_t>(j)] = std::max(key[static_cast<std::size_t>(j)], i + 0.5);
  }
  for (int i = primal; i < n; ++i)
    if (key[static_cast<std::size_t>(i)] < 0.0) key[static_cast<std::size_t>(i)] = n;
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
  });
  std::vector<int> position(static_cast<std::size_t>(n));
  for (int place = 0; place < n; ++place)
    position[static_cast<std::size_t>(order[static_cast<std::size_t>(place)])] = place;
  return position;
}

}  // namespace

std::unique_ptr<SparseKkt> analyse_sparse_kkt(int n, int nz, const int* irn, const int* icn,
                                              int primal) {
  auto kkt = std::make_unique<SparseKkt>();
  kkt->n = n;
  kkt->rows.assign(irn, irn + nz);
  kkt->columns.assign(icn, icn + nz);
  kkt->position = interleaved_order(n, nz, irn, icn, primal);
  auto place = [&](int e, int& row, int& column) {
    const int a = kkt->position[static_cast<std::size_t>(irn[e] - 1)],
              b = kkt->position[static_cast<std::size_t>(icn[e] - 1)];
    row = std::max(a, b);
    column = std::min(a, b);
  };
  std::vector<Eigen::Triplet<double>> pattern;
  pattern.reserve(static_cast<std::size_t>(nz) + static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    pattern.emplace_back(i, i, 0.0);  // every pivot present, even if never given
  for (int e = 0; e < nz; ++e) {
    int row = 0, column = 0;
    place(e, row, column);
    pattern.emplace_back(row, column, 0.0);
  }
  kkt->lower.resize(n, n);
  kkt->lower.setFromTriplets(pattern.begin(), pattern.end());
  kkt->lower.makeCompressed();
  kkt->destination.resize(static_cast<std::size_t>(nz));
  const int* outer = kkt->lower.outerIndexPtr();
  const int* inner = kkt->lower.innerIndexPtr();
  for (int e = 0; e < nz; ++e) {
    int row = 0, column = 0;
    place(e, row, column);
    const int* slot = std::lower_bound(inner + outer[column], inner + outer[column + 1], row);
    kkt->destination[static_cast<std::size_t>(e)] = static_cast<int>(slot - inner);
  }
  kkt->factor.analyzePattern(kkt->lower);
  kkt->scratch.resize(n);
  return kkt;
}

bool same_sparse_pattern(const SparseKkt& kkt, int nz, const int* irn, const int* icn) {
  return static_cast<int>(kkt.rows.size()) == nz &&
         std::equal(kkt.rows.begin(), kkt.rows.end(), irn) &&
         std::equal(kkt.columns.begin(), kkt.columns.end(), icn);
}

bool factor_sparse_kkt(SparseKkt& kkt, const double* a, int& negative) {
  double* values = kkt.lower.valuePtr();
  std::fill(values, values + kkt.lower.nonZeros(), 0.0);
  for (std::size_t e = 0; e < kkt.destination.size(); ++e) values[kkt.destination[e]] += a[e];
  double largest = 0.0;
  for (Eigen::Index k = 0; k < kkt.lower.nonZeros(); ++k)
    largest = std::max(largest, std::abs(values[k]));
  kkt.factor.factorize(kkt.lower);
  if (kkt.factor.info() != Eigen::Success) return false;
  const Eigen::VectorXd& d = kkt.factor.vectorD();
  negative = 0;
  for (Eigen::Index k = 0; k < d.size(); ++k) {
    if (!std::isfinite(d[k]) || std::abs(d[k]) <= kRelativeZeroPivot * largest) return false;
    negative += d[k] < 0.0;
  }
  return true;
}

void solve_sparse_kkt(SparseKkt& kkt, double* rhs) {
  Eigen::VectorXd& x = kkt.scratch;
  for (int i = 0; i < kkt.n; ++i) x[kkt.position[static_cast<std::size_t>(i)]] = rhs[i];
  x = kkt.factor.solve(x);
  for (int i = 0; i < kkt.n; ++i) rhs[i] = x[kkt.position[static_cast<std::size_t>(i)]];
}

}  // namespace flatsos::planner::detail
