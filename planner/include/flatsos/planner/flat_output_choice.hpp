#pragma once
// Flat outputs Y = E F: how well a given E satisfies Assumption 1 over a model's range of motion,
// and an E the library chooses when the model gives none (docs/method/flatness.md, "Flat outputs
// the library chooses").
//
// The margin of E is the smallest entry of C_Y(q) 1 over the postures: the tendon forces that
// one newton more of every flat output adds (equal to 1 - C_tau(q) R(q) 1, condition 3 of
// Assumption 1). It must be positive everywhere, so that a large enough constant Y makes every
// tendon taut whatever the torques (the planners' starting point and the SLP's vertex). With
// nonnegative rows of E (weighted means of tendon forces) it is at most 1: E v = 1 makes some
// v_j <= 1.
//
// The search scores E built from candidate rows (each muscle alone; each agonist-antagonist pair
// at half weights, as the paper's arm pairs them) by the margin first and, between equal margins,
// by the worst condition number of C(q): exhaustively when the combinations are few, otherwise by
// exchanging one row at a time from two starts until no exchange improves the score.
// Scores stop at the first posture where they can no longer beat the best so far (a smaller
// margin, or an equal one with a larger condition number: at 40 muscles most margins tie at 1),
// and the postures that stopped one are visited first by the next.

#include "flatsos/plugin/ndebug_guard.hpp"  // first: see there
#include "flatsos/plugin/simtk_namespace_guard.hpp"  // before Eigen: see there

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "flatsos/plugin/model/musculoskeletal_model.hpp"
#include "flatsos/plugin/model/posture_grid.hpp"

namespace flatsos::planner {

/// Thrown when C = [R; E] violates Assumption 1 of the paper (in some posture), or E has the
/// wrong shape.
class FlatnessError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};


/// How well flat outputs E satisfy Assumption 1 over a grid of postures.
struct FlatOutputMargin {
  /// min over the postures and muscles of (C_Y(q) 1)_j; > 0 iff condition 3 holds at every
  /// posture; -inf when C(q) is singular at one.
  double margin = -std::numeric_limits<double>::infinity();
  /// Where the margin is smallest, or C(q) singular (N; all 0 with constant moment arms).
  Eigen::VectorXd posture_rad;
  int muscle = -1;              ///< the muscle whose entry is smallest (-1: C(q) singular)
  /// The largest 1-norm condition number of C(q) = [R(q); E] over the postures (the LU's
  /// estimate, a lower bound), each row of R scaled to unit length (so that metres and weights
  /// compare); +inf where singular (an estimate above 1e10).
  double condition_number = std::numeric_limits<double>::infinity();
  bool holds() const { return margin > 0.0; }
};

/// The flat outputs a planner uses and where they came from.
struct FlatOutputChoice {
  Eigen::MatrixXd E;                ///< p x m, rows summing to 1
  std::vector<std::string> names;   ///< one per row
  bool automatic = false;           ///< chosen by choose_flat_outputs (the model gave none)
  FlatOutputMargin margin;          ///< over `region` (the grid of posture_grid.hpp)
  long candidates_scored = 0;       ///< automatic only: how many E the search scored
  /// Where E was chosen and Assumption 1 checked: a box of postures inside the joint ranges
  /// (task_region.hpp), or empty: the joint ranges themselves.
  plugin::JointRanges region;
};

struct FlatOutputSearchOptions {
  /// Score every combination of candidate rows when there are at most this many (most scores
  /// stop at their first posture once a good E is known); otherwise exchange rows from two starts.
  long exhaustive_limit = 20000;
  /// Postures per score while searching (posture-dependent paths); the winner is then scored
  /// over the full grid.
  long search_postures = 64;
  /// Postures of the final score (as many as the load-time Assumption 1 check visits).
  long final_postures = 20000;
  bool force_exchange_search = false;  ///< skip the exhaustive search (to compare the two)
  /// The postures E must serve (one range per joint); empty: the joint ranges.
  plugin::JointRanges region;
  /// The exchange search stops after this many scores with the best E so far (each score
  /// factors an m x m matrix per posture: dozens of muscles make many candidates).
  long max_exchange_scores = 200000;
};

/// The margin of E (p x m) over about `postures` postures of a grid over the joint ranges (or
/// `region`'s) of the joints whose moment arms vary (one posture, all zeros, for constant moment
/// arms). Rows of E not summing to 1 are not checked here (see FlatOutputMap::checkAssumption1).
FlatOutputMargin flat_output_margin(const plugin::MusculoskeletalModel& model, const Eigen::MatrixXd& E,
                                    long postures, const plugin::JointRanges& region = {});

/// The rows the search combines, with their names: "<a>_<b>_cocontraction" (weights 1/2, 1/2)
/// for every pair of muscles whose moment arms about some joint have opposite signs at some
/// search posture, then "<a>_force" for every muscle.
struct FlatOutputCandidates {
  Eigen::MatrixXd rows;  ///< one candidate per row (m columns)
  std::vector<std::string> names;
};
FlatOutputCandidates flat_output_candidates(const plugin::MusculoskeletalModel& model, long postures);

/// The E with the largest margin the search finds (ties: the smaller condition number), scored
/// over the full grid (of options.region, else of the joint ranges). Throws FlatnessError when the model has no redundant muscle (m = N), or
/// when no candidate satisfies Assumption 1 everywhere (naming the best one's failing posture
/// and muscle, and a joint no muscle pair opposes, if there is one).
FlatOutputChoice choose_flat_outputs(const plugin::MusculoskeletalModel& model,
                                     const FlatOutputSearchOptions& options = {});

}  // namespace flatsos::planner
