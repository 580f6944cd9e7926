#include "flatsos/muscles/muscle_model_check.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "flatsos/muscles/muscle_model.hpp"

namespace flatsos::muscles {
namespace {

// Step of the differences relative to the argument's scale: truncation ~ 1e-12, round-off ~ 1e-10
// of the derivative's scale.
constexpr double kRelativeStep = 1e-6;
// How close a reported derivative must be to a one-sided difference (error O(step)) for a
// mismatch of the central one to count as a kink of the law.
constexpr double kOneSidedTolerance = 1e-3;
// A derivative this many times its scale marks an inverse next to its branch point (two roots
// merging), where no difference of a fixed step resolves it.
constexpr double kIllConditioned = 20.0;

std::vector<double> grid(double lo, double hi, int count) {
  // Irrational offsets keep the points off the laws' kinks (0, 1, the end of a toe region).
  std::vector<double> out;
  for (int k = 0; k < count; ++k) out.push_back(lo + (hi - lo) * (k + 0.5 * std::sqrt(2.0) - 0.2) / count);
  return out;
}

class Checker {
 public:
  explicit Checker(double tolerance) : tolerance_(tolerance) {}

  void compare(const std::string& quantity, double at, double reported, double expected, double scale) {
    ++result_.checked;
    const bool finite = std::isfinite(reported) && std::isfinite(expected);
    if (!finite || std::abs(reported - expected) > tolerance_ * std::max(std::abs(expected), scale))
      result_.mismatches.push_back({quantity, at, reported, expected});
  }

  /// reported = d value / dx at x, by central differences with step h; a mismatch that one
  /// one-sided difference explains is a kink.
  void derivative(const std::string& quantity, const std::function<double(double)>& value, double x,
                  double reported, double step, double scale) {
    const double up = value(x + step), down = value(x - step), here = value(x);
    // Richardson's extrapolation of two central differences: error O(step^4).
    const double half = (value(x + 0.5 * step) - value(x - 0.5 * step)) / step;
    const double central = (4.0 * half - (up - down) / (2.0 * step)) / 3.0;
    ++result_.checked;
    const double allowed = tolerance_ * std::max(std::abs(central), scale);
    if (std::isfinite(reported) && std::abs(reported - central) <= allowed) return;
    const double right = (up - here) / step, left = (here - down) / step;
    const double one_sided = kOneSidedTolerance * std::max(std::abs(reported), scale);
    if (std::isfinite(reported) && std::abs(right - left) > one_sided &&
        (std::abs(reported - right) <= one_sided || std::abs(reported - left) <= one_sided)) {
      ++result_.skipped;
      return;
    }
    if (std::abs(reported) > kIllConditioned * scale) {  // next to a branch point of an inverse
      ++result_.skipped;
      return;
    }
    result_.mismatches.push_back({quantity, x, reported, central});
  }

  MuscleModelCheck result() const { return result_; }

 private:
  double tolerance_;
  MuscleModelCheck result_;
};

using Law = CurveJet (MuscleModel::*)(const MuscleParameters&, double) const;

// slope and curvature of one law against differences of its value and slope.
void check_curve(Checker& c, const MuscleParameters& p, Law law, const std::string& name,
                 const std::vector<double>& xs, double arg_scale, double value_scale) {
  const MuscleModel& m = *p.model;
  const double h = kRelativeStep * arg_scale;
  for (double x : xs) {
    const CurveJet j = (m.*law)(p, x);
    c.derivative(name + ".slope", [&](double y) { return (m.*law)(p, y).value; }, x, j.slope, h,
                 value_scale / arg_scale);
    c.derivative(name + ".curvature", [&](double y) { return (m.*law)(p, y).slope; }, x, j.curvature, h,
                 value_scale / (arg_scale * arg_scale));
  }
}

void check_tendon(Checker& c, const MuscleParameters& p) {
  const MuscleModel& m = *p.model;
  const double stretch_scale = p.tendon_strain_at_max_force * p.tendon_slack_length_m;
  const double fmax = p.max_isometric_force_N;
  std::vector<double> lengths;
  for (double t : grid(0.02, 1.6, 24)) lengths.push_back(p.tendon_slack_length_m + t * stretch_scale);
  check_curve(c, p, &MuscleModel::tendonForce, "tendonForce", lengths, stretch_scale, fmax);
  const double h = kRelativeStep * stretch_scale;
  for (double l : lengths) {
    c.derivative("tendonForceThirdDerivative", [&](double y) { return m.tendonForce(p, y).curvature; }, l,
                 m.tendonForceThirdDerivative(p, l), h, fmax / std::pow(stretch_scale, 3));
    c.compare("tendonLengthFromForce round trip", l, m.tendonLengthFromForce(p, m.tendonForce(p, l).value), l,
              stretch_scale);
  }
  c.compare("tendonForce at slack", p.tendon_slack_length_m, m.tendonForce(p, p.tendon_slack_length_m).value, 0.0,
            fmax);
}

void check_fiber(Checker& c, const MuscleParameters& p) {
  const MuscleModel& m = *p.model;
  std::vector<double> lengths;
  for (double t : grid(0.4, 1.7, 26)) lengths.push_back(t * p.optimal_fiber_length_m);
  check_curve(c, p, &MuscleModel::activeForceLength, "activeForceLength", lengths, p.optimal_fiber_length_m, 1.0);
  check_curve(c, p, &MuscleModel::passiveFiberForce, "passiveFiberForce", lengths, p.optimal_fiber_length_m,
              p.max_isometric_force_N);
  c.compare("activeForceLength at optimal", p.optimal_fiber_length_m,
            m.activeForceLength(p, p.optimal_fiber_length_m).value, 1.0, 1.0);

  const double vmax = p.max_shortening_velocity_m_per_s();
  std::vector<double> velocities;
  for (double t : grid(-0.95, 0.95, 38)) velocities.push_back(t * vmax);
  check_curve(c, p, &MuscleModel::forceVelocity, "forceVelocity", velocities, vmax, 1.0);
  c.compare("forceVelocity at 0", 0.0, m.forceVelocity(p, 0.0).value, 1.0, 1.0);
  // A model exact at every force ratio is checked up to 2 (beyond any Flen in use).
  const double z_hi = std::min(m.forceRatioExactUpperBound(p), 2.0);
  for (double u : velocities) {
    const double z = m.forceVelocity(p, u).value;
    if (z > 0.0 && z < z_hi)
      c.compare("forceVelocityInverse round trip", u, m.forceVelocityInverse(p, z), u, vmax);
  }
  // The forward model's inverse of g: exact on [0, z_hi], with its slope.
  for (double z : grid(-0.2, z_hi + 0.3, 30)) {
    const CurveJet u = m.fiberVelocityFromForceRatio(p, z);
    if (z >= 0.0 && z <= z_hi) c.compare("fiberVelocityFromForceRatio = inverse", z, u.value, m.forceVelocityInverse(p, z), vmax);
    c.derivative("fiberVelocityFromForceRatio.slope", [&](double y) { return m.fiberVelocityFromForceRatio(p, y).value; },
                 z, u.slope, kRelativeStep, vmax);
  }
}

// k(a) = Vmax(a) / Vmax: its derivatives, k(1) = 1 (the muscle's Vmax is at full activation),
// and k > 0 over the activations the dynamics use; exactly 1 when the model says it is.
void check_max_velocity_scale(Checker& c, const MuscleParameters& p) {
  const MuscleModel& m = *p.model;
  for (double a : grid(p.activation_floor, 1.0, 12)) {
    const CurveJet k = m.maxVelocityScale(p, a);
    c.derivative("maxVelocityScale.slope", [&](double y) { return m.maxVelocityScale(p, y).value; }, a, k.slope,
                 kRelativeStep, 1.0);
    c.derivative("maxVelocityScale.curvature", [&](double y) { return m.maxVelocityScale(p, y).slope; }, a, k.curvature,
                 kRelativeStep, 1.0);
    c.compare("maxVelocityScale > 0", a, k.value > 0.0 ? 1.0 : 0.0, 1.0, 1.0);
    if (!m.scalesMaxVelocityWithActivation()) c.compare("maxVelocityScale = 1 (not scaling)", a, k.value, 1.0, 1.0);
  }
  c.compare("maxVelocityScale at full activation", 1.0, m.maxVelocityScale(p, 1.0).value, 1.0, 1.0);
}

void check_activation(Checker& c, const MuscleParameters& p) {
  const MuscleModel& m = *p.model;
  const double rate_scale = 1.0 / p.activation_time_constant_s;
  const double h = kRelativeStep;
  const std::vector<double> levels = grid(std::max(p.activation_floor, 0.02), 0.98, 9);
  for (double a : levels)
    for (double n : grid(0.0, 1.0, 11)) {
      const ActivationRate r = m.activationRate(p, n, a);
      auto in_n = [&](double y) { return m.activationRate(p, y, a); };
      auto in_a = [&](double y) { return m.activationRate(p, n, y); };
      c.derivative("activationRate.d_excitation", [&](double y) { return in_n(y).value; }, n, r.d_excitation, h, rate_scale);
      c.derivative("activationRate.d_activation", [&](double y) { return in_a(y).value; }, a, r.d_activation, h, rate_scale);
      c.derivative("activationRate.d_excitation2", [&](double y) { return in_n(y).d_excitation; }, n, r.d_excitation2, h,
                   rate_scale);
      c.derivative("activationRate.d_excitation_activation", [&](double y) { return in_a(y).d_excitation; }, a,
                   r.d_excitation_activation, h, rate_scale);
      c.derivative("activationRate.d_activation2", [&](double y) { return in_a(y).d_activation; }, a, r.d_activation2, h,
                   rate_scale);

      // The inverse: a solution, with its partials, and the margins' verdict agrees with it.
      const ExcitationFromActivation inv = m.excitationFromActivation(p, a, r.value);
      c.compare("excitationFromActivation solves rate(n, a) = da/dt", a,
                inv.real_root ? m.activationRate(p, inv.excitation, a).value : NAN, r.value, rate_scale);
      auto n_of_a = [&](double y) { return m.excitationFromActivation(p, y, r.value).excitation; };
      auto n_of_rate = [&](double y) { return m.excitationFromActivation(p, a, y).excitation; };
      c.derivative("excitationFromActivation.d_activation", n_of_a, a, inv.d_activation, h, 1.0);
      c.derivative("excitationFromActivation.d_activation_rate_s", n_of_rate, r.value, inv.d_activation_rate_s,
                   h * rate_scale, 1.0 / rate_scale);
    }
  // Margins: partials, and >= 0 both exactly where an excitation in [0, 1] gives da/dt.
  for (double a : levels)
    for (double rate : grid(-2.0 * rate_scale, 2.0 * rate_scale, 21)) {
      const ExcitationBoundMargins mg = m.excitationBoundMargins(p, a, rate);
      auto at_a = [&](double y) { return m.excitationBoundMargins(p, y, rate); };
      auto at_rate = [&](double y) { return m.excitationBoundMargins(p, a, y); };
      c.derivative("excitationBoundMargins.lower_d_activation", [&](double y) { return at_a(y).lower; }, a,
                   mg.lower_d_activation, h, 1.0);
      c.derivative("excitationBoundMargins.upper_d_activation", [&](double y) { return at_a(y).upper; }, a,
                   mg.upper_d_activation, h, 1.0);
      c.derivative("excitationBoundMargins.lower_d_rate_s", [&](double y) { return at_rate(y).lower; }, rate,
                   mg.lower_d_rate_s, h * rate_scale, 1.0 / rate_scale);
      c.derivative("excitationBoundMargins.upper_d_rate_s", [&](double y) { return at_rate(y).upper; }, rate,
                   mg.upper_d_rate_s, h * rate_scale, 1.0 / rate_scale);
      if (std::min(std::abs(mg.lower), std::abs(mg.upper)) < 1e-9) continue;  // on the boundary
      const bool margins_hold = mg.lower >= 0.0 && mg.upper >= 0.0;
      const ExcitationFromActivation n = m.excitationFromActivation(p, a, rate);
      const bool attainable = n.real_root && n.excitation >= m.minimumExcitation(p) && n.excitation <= 1.0;
      c.compare("excitationBoundMargins agree with the inverse", rate, margins_hold ? 1.0 : 0.0,
                attainable ? 1.0 : 0.0, 1.0);
    }
}

}  // namespace

std::string MuscleModelCheck::summary() const {
  std::ostringstream out;
  out << checked << " comparisons, " << skipped << " skipped, " << mismatches.size() << " mismatches";
  for (std::size_t k = 0; k < mismatches.size() && k < 20; ++k)
    out << "\n  " << mismatches[k].quantity << " at " << mismatches[k].at << ": reported " << mismatches[k].reported
        << ", expected " << mismatches[k].expected;
  return out.str();
}

MuscleModelCheck check_muscle_model(const MuscleParameters& p, double relative_tolerance) {
  validate(p);
  Checker c(relative_tolerance);
  check_tendon(c, p);
  check_fiber(c, p);
  check_max_velocity_scale(c, p);
  check_activation(c, p);
  return c.result();
}

}  // namespace flatsos::muscles
