#include "flatsos/muscles/musculotendon_path.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace flatsos::muscles {

namespace {
void require_jet_count(int count) {
  if (count < 1 || count > LengthPolynomial::kMaxJetCount)
    throw std::invalid_argument("muscle path: jet count " + std::to_string(count) + " is outside [1, " +
                                std::to_string(LengthPolynomial::kMaxJetCount) + "]");
}
}  // namespace

MusculotendonPath::MusculotendonPath(LengthPolynomial length_m, std::vector<PathCoordinate> coordinates,
                                     int num_joints)
    : length_(std::move(length_m)), coordinates_(std::move(coordinates)), num_joints_(num_joints) {
  const int d = length_.dimension();
  if (num_joints < 0) throw std::invalid_argument("muscle path: negative joint count");
  if (static_cast<int>(coordinates_.size()) != d)
    throw std::invalid_argument("muscle path: " + std::to_string(coordinates_.size()) +
                                " coordinates for a length polynomial of dimension " + std::to_string(d));
  std::vector<bool> used(static_cast<std::size_t>(num_joints), false);
  for (int k = 0; k < d; ++k) {
    const PathCoordinate& c = coordinates_[k];
    if (c.held()) {
      if (c.joint != -1) throw std::invalid_argument("muscle path: coordinate " + std::to_string(k) + ": joint index " + std::to_string(c.joint));
      if (!std::isfinite(c.held_value_rad))
        throw std::invalid_argument("muscle path: coordinate " + std::to_string(k) + ": held value is not finite");
      continue;
    }
    if (c.joint >= num_joints)
      throw std::invalid_argument("muscle path: coordinate " + std::to_string(k) + ": joint index " +
                                  std::to_string(c.joint) + " outside [0, " + std::to_string(num_joints) + ")");
    if (used[c.joint])
      throw std::invalid_argument("muscle path: joint " + std::to_string(c.joint) + " is given twice");
    used[c.joint] = true;
    if (!length_.independentOf(k)) crossed_.push_back(c.joint);
  }
  std::sort(crossed_.begin(), crossed_.end());
  free_length_ = length_;
  for (int k = d - 1; k >= 0; --k)  // from the last, so that the earlier arguments keep their index
    if (coordinates_[k].held()) free_length_ = free_length_.withArgumentHeld(k, coordinates_[k].held_value_rad);
  for (const PathCoordinate& c : coordinates_)
    if (!c.held()) free_joint_.push_back(c.joint);
  const int free = free_length_.dimension();
  for (int k = 0; k < free; ++k) gradient_.push_back(free_length_.derivative(k));
  for (int k = 0; k < free; ++k)
    for (int l = 0; l < free; ++l) hessian_.push_back(gradient_[k].derivative(l));
}

MusculotendonPath MusculotendonPath::constantMomentArms(double length_at_zero_angles_m,
                                                        const std::vector<double>& moment_arms_m) {
  std::vector<PathCoordinate> coordinates;
  for (std::size_t i = 0; i < moment_arms_m.size(); ++i)
    if (moment_arms_m[i] != 0.0) coordinates.push_back({static_cast<int>(i), 0.0});
  // Order 1 in OpenSim's order: the constant, then the last argument's term, ..., the first's.
  std::vector<double> c{length_at_zero_angles_m};
  for (auto it = coordinates.rbegin(); it != coordinates.rend(); ++it) c.push_back(-moment_arms_m[it->joint]);
  const int d = static_cast<int>(coordinates.size());
  return MusculotendonPath(LengthPolynomial(d, 1, std::move(c)), std::move(coordinates),
                           static_cast<int>(moment_arms_m.size()));
}

void MusculotendonPath::arguments(const double* q_jet, int count, double* x_jet) const {
  const int d = static_cast<int>(free_joint_.size());
  for (int k = 0; k < d; ++k)
    for (int j = 0; j < count; ++j) x_jet[j * d + k] = q_jet[j * num_joints_ + free_joint_[k]];
}

double MusculotendonPath::length(const double* q_rad) const {
  double x[LengthPolynomial::kMaxDimension];
  arguments(q_rad, 1, x);
  return free_length_.value(x);
}

void MusculotendonPath::momentArms(const double* q_rad, double* r_m) const {
  double x[LengthPolynomial::kMaxDimension];
  arguments(q_rad, 1, x);
  std::fill(r_m, r_m + num_joints_, 0.0);
  for (std::size_t k = 0; k < free_joint_.size(); ++k) r_m[free_joint_[k]] = -gradient_[k].value(x);
}

void MusculotendonPath::momentArmJacobian(const double* q_rad, double* out) const {
  double x[LengthPolynomial::kMaxDimension];
  arguments(q_rad, 1, x);
  std::fill(out, out + num_joints_ * num_joints_, 0.0);
  const std::size_t d = free_joint_.size();
  for (std::size_t k = 0; k < d; ++k)
    for (std::size_t l = 0; l < d; ++l) out[free_joint_[k] * num_joints_ + free_joint_[l]] = -hessian_[k * d + l].value(x);
}

void MusculotendonPath::lengthJet(const double* q_jet, int count, double* out) const {
  require_jet_count(count);
  double x[LengthPolynomial::kMaxDimension * LengthPolynomial::kMaxJetCount];
  arguments(q_jet, count, x);
  free_length_.timeDerivatives(x, count, out);
}

void MusculotendonPath::momentArmJets(const double* q_jet, int count, double* out) const {
  require_jet_count(count);
  double x[LengthPolynomial::kMaxDimension * LengthPolynomial::kMaxJetCount];
  arguments(q_jet, count, x);
  std::fill(out, out + count * num_joints_, 0.0);
  double jet[LengthPolynomial::kMaxJetCount];
  for (std::size_t k = 0; k < free_joint_.size(); ++k) {
    gradient_[k].timeDerivatives(x, count, jet);
    for (int j = 0; j < count; ++j) out[j * num_joints_ + free_joint_[k]] = -jet[j];
  }
}

}  // namespace flatsos::muscles
