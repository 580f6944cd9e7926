// Range narrowing for the default import (opensim_range_narrowing.hpp): a grid over the current
// box; the unusable posture nearest a face (relative to the range) moves that face past it; the
// grid is laid again over the smaller box until every posture is usable.

#include "opensim_range_narrowing.hpp"

#include <algorithm>
#include <cmath>

#include "flatsos/muscles/length_polynomial.hpp"

namespace flatsos::plugin::opensim_import {

namespace {

using muscles::LengthPolynomial;

constexpr double kLeastMomentArm_m = 1e-3;  // a muscle pulls about a coordinate (for a slider: m/m)
constexpr int kMaxRounds = 50;

struct FittedMuscle {
  double tendon_slack_length_m = 0.0;
  double least_fiber_length_along_tendon_m = 0.0;  // a tenth of the optimal fibre's projection
  LengthPolynomial length;
  std::vector<LengthPolynomial> length_derivative;  // per argument
  std::vector<int> coordinate;                      // argument -> index into the kept coordinates
};

class Usability {
 public:
  Usability(const OpenSimModel& osim, const PathFit& fit, const std::vector<std::string>& kept) : kept_(kept) {
    for (const OpenSimPolynomialPath& p : fit.paths) {
      const OpenSimMuscle* muscle = osim.muscle(p.muscle);
      if (!muscle) continue;
      FittedMuscle m;
      m.tendon_slack_length_m = muscle->tendon_slack_length_m;
      m.least_fiber_length_along_tendon_m =
          0.1 * muscle->optimal_fiber_length_m * std::cos(muscle->pennation_angle_at_optimal_rad);
      m.length = LengthPolynomial(static_cast<int>(p.coordinates.size()), p.order, p.coefficients);
      for (std::size_t k = 0; k < p.coordinates.size(); ++k) {
        m.length_derivative.push_back(m.length.derivative(static_cast<int>(k)));
        m.coordinate.push_back(static_cast<int>(std::find(kept.begin(), kept.end(), p.coordinates[k]) - kept.begin()));
      }
      muscles_.push_back(std::move(m));
    }
  }

  // Every tendon taut, and each coordinate some muscle crosses pulled both ways.
  bool usable(const std::vector<double>& q) const {
    const std::size_t d = kept_.size();
    std::vector<char> positive(d, 0), negative(d, 0), crossed(d, 0);
    std::vector<double> x;
    for (const FittedMuscle& m : muscles_) {
      x.clear();
      for (int c : m.coordinate) x.push_back(q[c]);
      if (!(m.length.value(x.data()) > m.tendon_slack_length_m + m.least_fiber_length_along_tendon_m)) return false;
      for (std::size_t k = 0; k < m.coordinate.size(); ++k) {
        const double arm = -m.length_derivative[k].value(x.data());
        const int c = m.coordinate[k];
        crossed[c] = 1;
        positive[c] |= arm > kLeastMomentArm_m;
        negative[c] |= arm < -kLeastMomentArm_m;
      }
    }
    for (std::size_t c = 0; c < d; ++c)
      if (crossed[c] && !(positive[c] && negative[c])) return false;
    return true;
  }

 private:
  std::vector<std::string> kept_;
  std::vector<FittedMuscle> muscles_;
};

int points_per_coordinate(std::size_t dimension) {
  const int n = static_cast<int>(std::floor(std::pow(4000.0, 1.0 / static_cast<double>(dimension)) + 1e-9));
  return std::clamp(n, 3, 101);
}

}  // namespace

CoordinateRanges narrow_to_usable_ranges(const OpenSimModel& osim, const PathFit& fit, const CoordinateRanges& ranges) {
  std::vector<std::string> kept;
  std::vector<std::array<double, 2>> box;
  for (const auto& [name, range] : ranges) kept.push_back(name), box.push_back(range);
  const Usability check(osim, fit, kept);
  const std::size_t d = kept.size();
  const int n = points_per_coordinate(d);
  long total = 1;
  for (std::size_t k = 0; k < d; ++k) total *= n;
  std::vector<double> q(d);
  std::vector<int> index_of(d);
  for (int round = 0; round < kMaxRounds; ++round) {
    // Which grid layers (per coordinate, per index) hold an unusable posture.
    std::vector<std::vector<char>> layer_unusable(d, std::vector<char>(n, 0));
    bool any = false;
    for (long index = 0; index < total; ++index) {
      long rest = index;
      for (std::size_t k = 0; k < d; ++k, rest /= n) {
        index_of[k] = static_cast<int>(rest % n);
        q[k] = box[k][0] + (box[k][1] - box[k][0]) * index_of[k] / (n - 1);
      }
      if (check.usable(q)) continue;
      any = true;
      for (std::size_t k = 0; k < d; ++k) layer_unusable[k][index_of[k]] = 1;
    }
    if (!any) {
      CoordinateRanges out;
      for (std::size_t k = 0; k < d; ++k) out[kept[k]] = box[k];
      return out;
    }
    // Keep the longest run of usable layers of the coordinate where that run is longest: every
    // unusable posture lies in an unusable layer of each coordinate, so this removes them all.
    int best_k = -1, best_first = 0, best_length = 1;
    for (std::size_t k = 0; k < d; ++k) {
      for (int i = 0, run = 0; i < n; ++i) {
        run = layer_unusable[k][i] ? 0 : run + 1;
        if (run > best_length) best_k = static_cast<int>(k), best_first = i - run + 1, best_length = run;
      }
    }
    if (best_k < 0) break;  // no two neighbouring usable layers in any coordinate
    auto& range = box[static_cast<std::size_t>(best_k)];
    const double step = (range[1] - range[0]) / (n - 1);
    range = {range[0] + step * best_first, range[0] + step * (best_first + best_length - 1)};
  }
  throw OpenSimModelError("no range of the kept coordinates where every muscle's tendon can be taut and each coordinate has "
                          "muscles pulling both ways; choose the coordinates and ranges with opensim_to_model --keep --range");
}

}  // namespace flatsos::plugin::opensim_import
