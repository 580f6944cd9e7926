#include "numerics/condensed_kkt.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Core>

namespace flatsos::planner::detail {
namespace {

// Integer factor layout: a header, then the core's indices, the pairs' s and d indices, each
// pair's coupling range, the couplings' core positions, and S's pivots.
enum Header { kCore, kPairs, kCouplings, kHeaderSize };
struct IntegerLayout {
  std::int64_t core_index, pair_s, pair_d, start, position, pivots, size;
  IntegerLayout(std::int64_t core, std::int64_t pairs, std::int64_t couplings) {
    core_index = kHeaderSize;
    pair_s = core_index + core;
    pair_d = pair_s + pairs;
    start = pair_d + pairs;
    position = start + pairs + 1;
    pivots = position + couplings;
    size = pivots + core;
  }
};
// Real factor layout: S (core x core, column-major), the pairs' inverse blocks (ss, sd, dd),
// then the couplings' values.
struct RealLayout {
  std::int64_t inverse, coupling, size;
  RealLayout(std::int64_t core, std::int64_t pairs, std::int64_t couplings) {
    inverse = core * core;
    coupling = inverse + 3 * pairs;
    size = coupling + couplings;
  }
};

// Runs of pairs with the same couplings shorter than this update the core pair by pair.
constexpr int kSmallestDenseRun = 4;

// As the dense slot: only exact cancellation counts as zero.
const double kRelativeZero = std::numeric_limits<double>::epsilon() * std::numeric_limits<double>::epsilon();

enum Kind : int { kCoreIndex, kSlack, kMultiplier };

}  // namespace

CondensedPattern find_eliminable_pairs(int n, int nz, const int* irn, const int* icn) {
  // Distinct off-diagonal neighbours per index (compressed rows).
  std::vector<std::int64_t> start(static_cast<std::size_t>(n) + 1, 0);
  for (int e = 0; e < nz; ++e)
    if (irn[e] != icn[e]) ++start[static_cast<std::size_t>(irn[e])], ++start[static_cast<std::size_t>(icn[e])];
  for (int i = 0; i < n; ++i) start[static_cast<std::size_t>(i) + 1] += start[static_cast<std::size_t>(i)];
  std::vector<int> neighbour(static_cast<std::size_t>(start[static_cast<std::size_t>(n)]));
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (int e = 0; e < nz; ++e) {
    const int i = irn[e] - 1, j = icn[e] - 1;
    if (i == j) continue;
    neighbour[static_cast<std::size_t>(fill[static_cast<std::size_t>(i)]++)] = j;
    neighbour[static_cast<std::size_t>(fill[static_cast<std::size_t>(j)]++)] = i;
  }
  // Duplicates out, by the last index that saw each neighbour (no sort: the core's indices have
  // thousands of neighbours each, and only their count and membership matter below).
  std::vector<int> degree(static_cast<std::size_t>(n)), seen_by(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    std::int64_t distinct = start[static_cast<std::size_t>(i)];
    for (std::int64_t k = start[static_cast<std::size_t>(i)]; k < start[static_cast<std::size_t>(i) + 1]; ++k) {
      const int j = neighbour[static_cast<std::size_t>(k)];
      if (seen_by[static_cast<std::size_t>(j)] == i) continue;
      seen_by[static_cast<std::size_t>(j)] = i;
      neighbour[static_cast<std::size_t>(distinct++)] = j;
    }
    degree[static_cast<std::size_t>(i)] = static_cast<int>(distinct - start[static_cast<std::size_t>(i)]);
  }
  auto neighbours_of = [&](int i) {
    const int* first = neighbour.data() + start[static_cast<std::size_t>(i)];
    return std::pair<const int*, const int*>{first, first + degree[static_cast<std::size_t>(i)]};
  };

  CondensedPattern p;
  p.role.assign(static_cast<std::size_t>(n), 0);
  std::vector<Kind> kind(static_cast<std::size_t>(n), kCoreIndex);
  for (int s = 0; s < n; ++s) {
    if (degree[static_cast<std::size_t>(s)] != 1 || kind[static_cast<std::size_t>(s)] != kCoreIndex) continue;
    const int d = *neighbours_of(s).first;
    if (kind[static_cast<std::size_t>(d)] != kCoreIndex) continue;
    // d's other neighbours must stay in the core: the pairs' blocks then couple only to it.
    const auto [first, last] = neighbours_of(d);
    if (std::any_of(first, last, [&](int k) { return k != s && kind[static_cast<std::size_t>(k)] != kCoreIndex; })) continue;
    kind[static_cast<std::size_t>(s)] = kSlack;
    kind[static_cast<std::size_t>(d)] = kMultiplier;
    p.role[static_cast<std::size_t>(s)] = -1 - 2 * p.pairs;
    p.role[static_cast<std::size_t>(d)] = -2 - 2 * p.pairs;
    p.couplings += degree[static_cast<std::size_t>(d)] - 1;
    ++p.pairs;
  }
  for (int i = 0; i < n; ++i)
    if (kind[static_cast<std::size_t>(i)] == kCoreIndex) p.role[static_cast<std::size_t>(i)] = p.core++;
  return p;
}

std::int64_t condensed_integer_workspace(const CondensedPattern& p) {
  return IntegerLayout(p.core, p.pairs, p.couplings).size;
}

std::int64_t condensed_real_workspace(const CondensedPattern& p) { return RealLayout(p.core, p.pairs, p.couplings).size; }

int condensed_core(const int* iw) { return iw[kCore]; }

bool build_condensed_scatter(int n, int nz, const int* irn, const int* icn, const CondensedPattern& p,
                             CondensedScatter& out) {
  const int* role = p.role.data();
  const int core = p.core, pairs = p.pairs;
  auto pair_of_multiplier = [&](int i) { return role[i] < 0 && (-role[i]) % 2 == 0 ? (-role[i] - 2) / 2 : -1; };
  // The couplings as the triplets list them (a (d, core) pair may come more than once).
  std::vector<int> raw_start(static_cast<std::size_t>(pairs) + 1, 0);
  for (int e = 0; e < nz; ++e) {
    const int i = irn[e] - 1, j = icn[e] - 1;
    if (role[i] >= 0 && pair_of_multiplier(j) >= 0) ++raw_start[static_cast<std::size_t>(pair_of_multiplier(j)) + 1];
    else if (role[j] >= 0 && pair_of_multiplier(i) >= 0) ++raw_start[static_cast<std::size_t>(pair_of_multiplier(i)) + 1];
  }
  for (int q = 0; q < pairs; ++q) raw_start[static_cast<std::size_t>(q) + 1] += raw_start[static_cast<std::size_t>(q)];
  std::vector<int> raw_position(static_cast<std::size_t>(raw_start.back())), raw_entry(raw_position.size());
  std::vector<int> raw_fill(raw_start.begin(), raw_start.end() - 1);
  const RealLayout R(core, pairs, p.couplings);
  out.destination.assign(static_cast<std::size_t>(nz), 0);
  for (int e = 0; e < nz; ++e) {
    const int i = irn[e] - 1, j = icn[e] - 1, ri = role[i], rj = role[j];
    std::int64_t& to = out.destination[static_cast<std::size_t>(e)];
    if (ri >= 0 && rj >= 0) {
      to = static_cast<std::int64_t>(std::min(ri, rj)) * core + std::max(ri, rj);  // S's lower triangle
    } else if (ri < 0 && rj < 0) {  // within one pair (the pattern allows no other case)
      const auto q = static_cast<std::int64_t>((-std::max(ri, rj) - 1) / 2);
      const int slot = i != j ? 1 : (-ri) % 2 == 1 ? 0 : 2;
      to = R.inverse + 3 * q + slot;  // the pair's block, summed where its inverse will be
    } else {
      const int q = pair_of_multiplier(ri < 0 ? i : j);
      const auto k = static_cast<std::size_t>(raw_fill[static_cast<std::size_t>(q)]++);
      raw_position[k] = ri < 0 ? rj : ri;
      raw_entry[k] = e;
    }
  }

  // Each pair's couplings with repeated positions summed into one slot (as many as the pattern
  // has, unless the triplets are not the pattern's).
  std::vector<int> slot_of(static_cast<std::size_t>(core), -1);
  std::int64_t distinct = 0;
  for (int q = 0; q < pairs; ++q)
    for (int k = raw_start[static_cast<std::size_t>(q)]; k < raw_start[static_cast<std::size_t>(q) + 1]; ++k) {
      int& mark = slot_of[static_cast<std::size_t>(raw_position[static_cast<std::size_t>(k)])];
      if (mark != q) mark = q, ++distinct;
    }
  if (distinct != p.couplings) return false;
  std::fill(slot_of.begin(), slot_of.end(), -1);
  const IntegerLayout L(core, pairs, p.couplings);
  out.integers.assign(static_cast<std::size_t>(L.pivots), 0);
  int* iw = out.integers.data();
  iw[kCore] = core;
  iw[kPairs] = pairs;
  iw[kCouplings] = static_cast<int>(p.couplings);
  for (int i = 0; i < n; ++i) {
    if (role[i] >= 0) iw[L.core_index + role[i]] = i;
    else if ((-role[i]) % 2 == 1) iw[L.pair_s + (-role[i] - 1) / 2] = i;
    else iw[L.pair_d + (-role[i] - 2) / 2] = i;
  }
  int* start = iw + L.start;
  int* position = iw + L.position;
  int kept = 0;
  for (int q = 0; q < pairs; ++q) {
    start[q] = kept;
    for (int k = raw_start[static_cast<std::size_t>(q)]; k < raw_start[static_cast<std::size_t>(q) + 1]; ++k) {
      const int pos = raw_position[static_cast<std::size_t>(k)];
      int& slot = slot_of[static_cast<std::size_t>(pos)];
      if (slot < start[q]) {
        slot = kept++;
        position[slot] = pos;
      }
      out.destination[static_cast<std::size_t>(raw_entry[static_cast<std::size_t>(k)])] = R.coupling + slot;
    }
  }
  start[pairs] = kept;

  // Runs of pairs that couple to the same core positions in the same order (the rows of one time
  // point: a few dozen), whose Schur updates are summed as one dense product.
  out.run_start.clear();
  for (int q = 0; q < pairs;) {
    out.run_start.push_back(q);
    const int first = start[q], count = start[q + 1] - start[q];
    int end = q + 1;
    while (end < pairs && start[end + 1] - start[end] == count &&
           std::equal(position + first, position + first + count, position + start[end]))
      ++end;
    q = end;
  }
  out.run_start.push_back(pairs);
  out.pattern = p;
  out.rows.assign(irn, irn + nz);
  out.columns.assign(icn, icn + nz);
  return true;
}

bool same_pattern(const CondensedScatter& scatter, int nz, const int* irn, const int* icn) {
  return static_cast<std::size_t>(nz) == scatter.rows.size() && std::equal(scatter.rows.begin(), scatter.rows.end(), irn) &&
         std::equal(scatter.columns.begin(), scatter.columns.end(), icn);
}

void factor_condensed(const CondensedScatter& scatter, const double* values, int* iw, double* real, Inertia& inertia) {
  const int core = scatter.pattern.core, pairs = scatter.pattern.pairs;
  const RealLayout R(core, pairs, scatter.pattern.couplings);
  // The values summed into place: S's lower triangle, the pairs' blocks (where their inverses
  // go), the couplings.
  std::fill(real, real + R.size, 0.0);
  const std::int64_t* to = scatter.destination.data();
  for (std::size_t e = 0; e < scatter.destination.size(); ++e) real[to[e]] += values[e];
  std::copy(scatter.integers.begin(), scatter.integers.end(), iw);
  const IntegerLayout L(core, pairs, scatter.pattern.couplings);
  const int* start = iw + L.start;
  const int* position = iw + L.position;
  const double* coupling = real + R.coupling;
  double* S = real;

  // Each pair's block inverted in place (its inertia counted).
  inertia = Inertia{};
  double* inverse = real + R.inverse;
  for (int q = 0; q < pairs; ++q) {
    double* inv = inverse + 3 * static_cast<std::int64_t>(q);
    const double ss = inv[0], sd = inv[1], dd = inv[2];
    const double det = ss * dd - sd * sd;
    if (!(std::abs(det) > kRelativeZero * std::max(std::abs(ss * dd), sd * sd))) {
      inv[0] = inv[1] = inv[2] = 0.0;
      const double trace = ss + dd;
      inertia.zero += trace == 0.0 ? 2 : 1;
      if (trace > 0.0) ++inertia.positive;
      else if (trace < 0.0) ++inertia.negative;
      continue;
    }
    if (det < 0.0) ++inertia.positive, ++inertia.negative;
    else if (ss > 0.0) inertia.positive += 2;
    else inertia.negative += 2;
    inv[0] = dd / det;
    inv[1] = -sd / det;
    inv[2] = ss / det;
  }
  // Their Schur updates of the core, S -= sum_q gamma_q b_q b_q^T (gamma_q = (P_q^-1)_dd). A run
  // of pairs with the same couplings is summed as one dense product, B diag(gamma) B^T, and
  // scattered once: row by row, the scattered rank-one updates were most of the factorization's
  // time.
  Eigen::MatrixXd B, weighted, sum;
  for (std::size_t r = 0; r + 1 < scatter.run_start.size(); ++r) {
    int q = scatter.run_start[r];
    const int end = scatter.run_start[r + 1], run = end - q;
    const int first = start[q], count = start[q + 1] - start[q];
    if (run < kSmallestDenseRun) {
      for (; q < end; ++q) {
        const double gamma = inverse[3 * static_cast<std::int64_t>(q) + 2];
        for (int a = start[q]; a < start[q + 1]; ++a) {
          const double ga = gamma * coupling[a];
          const int pa = position[a];
          for (int b = start[q]; b <= a; ++b) {
            const int pb = position[b];
            S[static_cast<std::int64_t>(std::min(pa, pb)) * core + std::max(pa, pb)] -= ga * coupling[b];
          }
        }
      }
      continue;
    }
    B.resize(count, run);
    weighted.resize(count, run);
    for (int k = 0; k < run; ++k) {
      const double gamma = inverse[3 * static_cast<std::int64_t>(q + k) + 2];
      for (int a = 0; a < count; ++a) {
        B(a, k) = coupling[start[q + k] + a];
        weighted(a, k) = gamma * B(a, k);
      }
    }
    // The lower triangle only: half the product's work.
    sum.resize(count, count);
    sum.triangularView<Eigen::Lower>() = B * weighted.transpose();
    for (int a = 0; a < count; ++a) {
      const int pa = position[first + a];
      for (int b = 0; b <= a; ++b) {
        const int pb = position[first + b];
        S[static_cast<std::int64_t>(std::min(pa, pb)) * core + std::max(pa, pb)] -= sum(a, b);
      }
    }
  }
  double largest = 0.0;
  for (int j = 0; j < core; ++j)
    for (int i = j; i < core; ++i) largest = std::max(largest, std::abs(S[static_cast<std::int64_t>(j) * core + i]));
  const Inertia of_core = factor_ldlt_in_place(S, core, iw + L.pivots, kRelativeZero * largest);
  inertia.positive += of_core.positive;
  inertia.negative += of_core.negative;
  inertia.zero += of_core.zero;
}

bool factor_condensed(int n, int nz, const int* irn, const int* icn, const double* values, const CondensedPattern& p,
                      int* iw, double* real, Inertia& inertia) {
  CondensedScatter scatter;
  if (!build_condensed_scatter(n, nz, irn, icn, p, scatter)) return false;
  factor_condensed(scatter, values, iw, real, inertia);
  return true;
}

void solve_condensed(const int* iw, const double* real, double* rhs, double* scratch) {
  const int core = iw[kCore], pairs = iw[kPairs];
  const IntegerLayout L(core, pairs, iw[kCouplings]);
  const RealLayout R(core, pairs, iw[kCouplings]);
  const int* core_index = iw + L.core_index;
  const int* pair_s = iw + L.pair_s;
  const int* pair_d = iw + L.pair_d;
  const int* start = iw + L.start;
  const int* position = iw + L.position;
  const double* inverse = real + R.inverse;
  const double* coupling = real + R.coupling;
  double* x = scratch;
  for (int k = 0; k < core; ++k) x[k] = rhs[core_index[k]];
  // The core's right-hand side less each pair's share: b (P^-1 [r_s; r_d])_d.
  for (int q = 0; q < pairs; ++q) {
    const double* inv = inverse + 3 * static_cast<std::int64_t>(q);
    const double y = inv[1] * rhs[pair_s[q]] + inv[2] * rhs[pair_d[q]];
    for (int a = start[q]; a < start[q + 1]; ++a) x[position[a]] -= coupling[a] * y;
  }
  solve_ldlt_in_place(real, core, iw + L.pivots, x);
  // Each pair from its own block: [s; d] = P^-1 ([r_s; r_d] - [0; b^T x]).
  for (int q = 0; q < pairs; ++q) {
    const double* inv = inverse + 3 * static_cast<std::int64_t>(q);
    double bx = 0.0;
    for (int a = start[q]; a < start[q + 1]; ++a) bx += coupling[a] * x[position[a]];
    const double rs = rhs[pair_s[q]], rd = rhs[pair_d[q]] - bx;
    rhs[pair_s[q]] = inv[0] * rs + inv[1] * rd;
    rhs[pair_d[q]] = inv[1] * rs + inv[2] * rd;
  }
  for (int k = 0; k < core; ++k) rhs[core_index[k]] = x[k];
}

}  // namespace flatsos::planner::detail
