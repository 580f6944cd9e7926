#include "flatsos/planner/flat_output_choice.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::planner {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMarginTie = 1e-9;  // margins this close are equal; the condition number decides

// The postures a score visits, with their moment arms: about `budget` of them over the joints
// whose moment arms vary, or the single posture 0 for constant moment arms. R's rows are scaled
// to unit length (v = C_Y 1 does not change: R v = 0 either way) so that the condition number
// compares metres with weights.
struct PostureSet {
  std::vector<Eigen::VectorXd> q_rad;
  std::vector<Eigen::MatrixXd> R_unit;  // N x m
};

PostureSet posture_set(const plugin::MusculoskeletalModel& model, long budget, const plugin::JointRanges& region) {
  PostureSet set;
  const plugin::ModelDescription& d = model.description();
  auto add = [&](const Eigen::VectorXd& q) {
    set.q_rad.push_back(q);
    Eigen::MatrixXd R = model.momentArmMatrix(q);
    for (Eigen::Index i = 0; i < R.rows(); ++i)
      if (R.row(i).norm() > 0.0) R.row(i) /= R.row(i).norm();
    set.R_unit.push_back(std::move(R));
  };
  if (model.hasConstantMomentArms())
    add(Eigen::VectorXd::Zero(model.numJoints()));
  else
    plugin::for_each_posture(d, plugin::posture_dependent_joints(d), budget, add, region);
  return set;
}

// The score of E at one posture: v = C_Y 1 from one LU of C = [R; E] (R's rows at unit length)
// and the factorization's estimate of its 1-norm condition number; singular where that exceeds
// 1e10 (about where the map's full-pivot LU, threshold 1e-10, calls C singular).
struct PostureScore {
  bool singular = true;
  double margin = -kInf;
  int muscle = -1;
  double condition_number = kInf;
};

PostureScore score_at(const Eigen::MatrixXd& R_unit, const Eigen::MatrixXd& E, Eigen::MatrixXd& C, Eigen::VectorXd& rhs) {
  const Eigen::Index n = R_unit.rows(), m = R_unit.cols();
  C.resize(m, m);
  C << R_unit, E;
  rhs.setZero(m);
  rhs.tail(m - n).setOnes();
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(C);
  PostureScore s;
  const double rcond = lu.rcond();
  if (!(rcond > 1e-10)) return s;
  const Eigen::VectorXd v = lu.solve(rhs);
  if (!v.allFinite()) return s;
  s.singular = false;
  Eigen::Index j = 0;
  s.margin = v.minCoeff(&j);
  s.muscle = static_cast<int>(j);
  s.condition_number = 1.0 / rcond;
  return s;
}

// The margin of E over a posture set, visiting the postures in `order`. Stops early once the
// score cannot beat `bar` (see better(): its margin below bar's, or no larger and its condition
// number already above bar's; more postures only lower the one and raise the other) and then
// moves the posture that stopped it to the front of `order`: the postures that bind are few, so
// the next score meets them first. A stopped score is partial, and never better than `bar`.
FlatOutputMargin score_over(const PostureSet& set, const Eigen::MatrixXd& E, std::vector<std::size_t>& order,
                            const FlatOutputMargin* bar = nullptr) {
  FlatOutputMargin out;
  out.margin = kInf;
  out.condition_number = 0.0;
  Eigen::MatrixXd C;
  Eigen::VectorXd rhs;
  auto stop_at = [&](std::size_t at) {
    std::rotate(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(at), order.begin() + static_cast<std::ptrdiff_t>(at) + 1);
  };
  for (std::size_t at = 0; at < order.size(); ++at) {
    const std::size_t k = order[at];
    const PostureScore s = score_at(set.R_unit[k], E, C, rhs);
    if (s.singular) {
      out.margin = -kInf;
      out.muscle = -1;
      out.condition_number = kInf;
      out.posture_rad = set.q_rad[k];
      stop_at(at);
      return out;
    }
    if (s.margin < out.margin) {
      out.margin = s.margin;
      out.muscle = s.muscle;
      out.posture_rad = set.q_rad[k];
    }
    out.condition_number = std::max(out.condition_number, s.condition_number);
    if (!bar) continue;
    const bool below = out.margin < bar->margin - kMarginTie;
    const bool no_better = out.margin <= bar->margin + kMarginTie && !(out.condition_number < bar->condition_number * (1.0 - 1e-12));
    if (below || no_better) {
      stop_at(at);
      return out;
    }
  }
  return out;
}

std::vector<std::size_t> in_grid_order(const PostureSet& set) {
  std::vector<std::size_t> order(set.R_unit.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  return order;
}

// The order of scores: the larger margin; between equal margins, the smaller condition number.
bool better(const FlatOutputMargin& a, const FlatOutputMargin& b) {
  if (a.margin > b.margin + kMarginTie) return true;
  if (!(std::abs(a.margin - b.margin) <= kMarginTie)) return false;
  return a.condition_number < b.condition_number * (1.0 - 1e-12);
}

Eigen::MatrixXd rows_of(const FlatOutputCandidates& c, const std::vector<int>& pick) {
  Eigen::MatrixXd E(static_cast<Eigen::Index>(pick.size()), c.rows.cols());
  for (std::size_t i = 0; i < pick.size(); ++i) E.row(static_cast<Eigen::Index>(i)) = c.rows.row(pick[i]);
  return E;
}

FlatOutputCandidates candidates_over(const plugin::MusculoskeletalModel& model, const PostureSet& set) {
  const int n = model.numJoints(), m = model.numMuscles();
  constexpr double kArm = 1e-9;  // smaller (relative) moment arms do not pull either way
  FlatOutputCandidates out;
  std::vector<Eigen::RowVectorXd> rows;
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b) {
      bool opposed = false;
      for (const Eigen::MatrixXd& R : set.R_unit)
        for (int i = 0; i < n && !opposed; ++i)
          opposed = (R(i, a) > kArm && R(i, b) < -kArm) || (R(i, a) < -kArm && R(i, b) > kArm);
      if (!opposed) continue;
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(m);
      row[a] = row[b] = 0.5;
      rows.push_back(row);
      out.names.push_back(model.muscle(a).getParameters().name + "_" + model.muscle(b).getParameters().name +
                          "_cocontraction");
    }
  for (int a = 0; a < m; ++a) {
    rows.push_back(Eigen::RowVectorXd::Unit(m, a));
    out.names.push_back(model.muscle(a).getParameters().name + "_force");
  }
  out.rows.resize(static_cast<Eigen::Index>(rows.size()), m);
  for (std::size_t k = 0; k < rows.size(); ++k) out.rows.row(static_cast<Eigen::Index>(k)) = rows[k];
  return out;
}

// C(n, k), saturating at `cap` (the count only decides whether to enumerate).
double combinations(int n, int k, double cap) {
  double c = 1.0;
  for (int i = 1; i <= k && c <= cap; ++i) c = c * (n - k + i) / i;
  return c;
}

struct Search {
  Search(const PostureSet& s, const FlatOutputCandidates& c, int p, long budget)
      : set(s), candidates(c), rows(p), max_scores(budget) {}
  const PostureSet& set;
  const FlatOutputCandidates& candidates;
  int rows = 0;  // p
  long max_scores = 0;  // of the exchange search
  long scored = 0;
  std::vector<int> best_pick;
  FlatOutputMargin best;
  std::vector<std::size_t> order = in_grid_order(set);  // of the postures: see score_over

  FlatOutputMargin score(const std::vector<int>& pick, const FlatOutputMargin* bar) {
    ++scored;
    return score_over(set, rows_of(candidates, pick), order, bar);
  }
  void offer(const std::vector<int>& pick, const FlatOutputMargin& s) {
    if (best_pick.empty() || better(s, best)) {
      best = s;
      best_pick = pick;
    }
  }

  void exhaustive() {
    const int count = static_cast<int>(candidates.rows.rows());
    std::vector<int> pick(static_cast<std::size_t>(rows));
    for (int i = 0; i < rows; ++i) pick[static_cast<std::size_t>(i)] = i;
    while (true) {
      offer(pick, score(pick, best_pick.empty() ? nullptr : &best));
      int i = rows - 1;
      while (i >= 0 && pick[static_cast<std::size_t>(i)] == count - rows + i) --i;
      if (i < 0) return;
      ++pick[static_cast<std::size_t>(i)];
      for (int k = i + 1; k < rows; ++k) pick[static_cast<std::size_t>(k)] = pick[static_cast<std::size_t>(k - 1)] + 1;
    }
  }

  // Rows taken in `preference` order while they keep [R; rows] of full rank at the first search
  // posture.
  std::vector<int> greedy_start(const std::vector<int>& preference) const {
    const Eigen::MatrixXd& R = set.R_unit.front();
    std::vector<int> pick;
    for (int c : preference) {
      if (static_cast<int>(pick.size()) == rows) break;
      std::vector<int> trial = pick;
      trial.push_back(c);
      Eigen::MatrixXd stacked(R.rows() + static_cast<Eigen::Index>(trial.size()), R.cols());
      stacked << R, rows_of(candidates, trial);
      Eigen::FullPivLU<Eigen::MatrixXd> lu(stacked);
      lu.setThreshold(1e-10);
      if (lu.rank() == stacked.rows()) pick = trial;
    }
    return pick;
  }

  // Exchanges one row at a time, taking each exchange that improves the score at once, until a
  // whole pass over the rows and candidates improves nothing (or the budget is spent).
  void exchange_from(std::vector<int> pick) {
    if (static_cast<int>(pick.size()) != rows) return;
    FlatOutputMargin current = score(pick, nullptr);
    const int count = static_cast<int>(candidates.rows.rows());
    bool improved = true;
    while (improved && scored < max_scores) {
      improved = false;
      for (int i = 0; i < rows && scored < max_scores; ++i)
        for (int c = 0; c < count && scored < max_scores; ++c) {
          if (std::find(pick.begin(), pick.end(), c) != pick.end()) continue;
          std::vector<int> trial = pick;
          trial[static_cast<std::size_t>(i)] = c;
          const FlatOutputMargin s = score(trial, &current);
          if (better(s, current)) {
            current = s;
            pick = trial;
            improved = true;
          }
        }
    }
    offer(pick, current);
  }
};

// A joint that, at some posture, no muscle pair opposes: every muscle crossing it pulls one way
// (empty when there is none).
std::string unopposed_joint(const plugin::MusculoskeletalModel& model, const PostureSet& set) {
  const plugin::ModelDescription& d = model.description();
  for (std::size_t k = 0; k < set.R_unit.size(); ++k)
    for (int i = 0; i < model.numJoints(); ++i) {
      const Eigen::RowVectorXd r = set.R_unit[k].row(i);
      const bool pulls = r.cwiseAbs().maxCoeff() > 0.0;
      if (pulls && (r.minCoeff() >= 0.0 || r.maxCoeff() <= 0.0)) {
        return "every muscle crossing joint '" + d.joints[static_cast<std::size_t>(i)].name + "' pulls the same way at " +
               plugin::describe_posture(d, set.q_rad[k]) +
               ", so no tendon forces that are all positive balance there";
      }
    }
  return "";
}

}  // namespace

FlatOutputMargin flat_output_margin(const plugin::MusculoskeletalModel& model, const Eigen::MatrixXd& E, long postures,
                                    const plugin::JointRanges& region) {
  if (E.rows() != model.numMuscles() - model.numJoints() || E.cols() != model.numMuscles())
    throw std::invalid_argument("flat-output margin: E must be (m - N) x m");
  const PostureSet set = posture_set(model, postures, region);
  std::vector<std::size_t> order = in_grid_order(set);
  return score_over(set, E, order);
}

FlatOutputCandidates flat_output_candidates(const plugin::MusculoskeletalModel& model, long postures) {
  return candidates_over(model, posture_set(model, postures, {}));
}

FlatOutputChoice choose_flat_outputs(const plugin::MusculoskeletalModel& model, const FlatOutputSearchOptions& options) {
  const std::string& name = model.description().name;
  const int n = model.numJoints(), m = model.numMuscles(), p = m - n;
  if (p < 1)
    throw FlatnessError("model '" + name + "' has " + std::to_string(m) + " muscles for " + std::to_string(n) +
                        " joints: flat outputs need more muscles than joints");
  const PostureSet set = posture_set(model, options.search_postures, options.region);
  const FlatOutputCandidates candidates = candidates_over(model, set);
  Search search(set, candidates, p, options.max_exchange_scores);
  const int count = static_cast<int>(candidates.rows.rows());
  const double limit = static_cast<double>(options.exhaustive_limit);
  if (!options.force_exchange_search && combinations(count, p, limit + 1.0) <= limit) {
    search.exhaustive();
  } else {
    // Two starts: the pairs first (candidate order), and the single muscles first.
    std::vector<int> pairs_first(static_cast<std::size_t>(count));
    for (int c = 0; c < count; ++c) pairs_first[static_cast<std::size_t>(c)] = c;
    std::vector<int> singles_first(pairs_first.end() - m, pairs_first.end());
    singles_first.insert(singles_first.end(), pairs_first.begin(), pairs_first.end() - m);
    search.exchange_from(search.greedy_start(pairs_first));
    search.exchange_from(search.greedy_start(singles_first));
  }
  if (search.best_pick.empty() || !search.best.holds()) {
    std::ostringstream why;
    why << "model '" << name << "' gives no flat_outputs and none of the " << search.scored
        << " E the library tried satisfies Assumption 1 over the "
        << (options.region.empty() ? "joint ranges" : "region " + plugin::describe_region(model.description(), options.region));
    const std::string joint = unopposed_joint(model, set);
    if (!joint.empty()) {
      why << ": " << joint;
    } else if (!search.best_pick.empty()) {
      why << "; the best (";
      for (std::size_t k = 0; k < search.best_pick.size(); ++k)
        why << (k ? ", " : "") << candidates.names[static_cast<std::size_t>(search.best_pick[k])];
      why << ") reaches " << search.best.margin << " at " << plugin::describe_posture(model.description(), search.best.posture_rad);
      if (search.best.muscle >= 0) why << " for muscle '" << model.muscle(search.best.muscle).getParameters().name << "'";
    }
    throw FlatnessError(why.str());
  }
  FlatOutputChoice choice;
  choice.E = rows_of(candidates, search.best_pick);
  for (int c : search.best_pick) choice.names.push_back(candidates.names[static_cast<std::size_t>(c)]);
  choice.automatic = true;
  choice.candidates_scored = search.scored;
  choice.region = options.region;
  choice.margin = flat_output_margin(model, choice.E, options.final_postures, options.region);
  return choice;
}

}  // namespace flatsos::planner
