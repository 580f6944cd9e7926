#include "flatsos/planner/joint_reference.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace flatsos::planner {

JointReference JointReference::fromMotion(const plugin::MusculoskeletalModel& model,
                                          const plugin::ProcessedCoordinates& motion) {
  if (motion.report_times_s.empty()) throw std::invalid_argument("joint reference: the motion has no report times");
  JointReference r;
  for (const auto& joint : model.description().joints) {
    const std::string& name = joint.coordinateName();
    bool found = false;
    for (std::size_t k = 0; k < motion.names.size() && !found; ++k)
      if (motion.names[k] == name) r.splines_.push_back(motion.splines[k]), found = true;
    if (!found) throw std::invalid_argument("joint reference: the motion has no column for the coordinate '" + name + "'");
  }
  r.joints_ = model.numJoints();
  r.start_s_ = motion.report_times_s.front();
  r.end_s_ = motion.report_times_s.back();
  return r;
}

JointReference JointReference::fromPath(JointPath path, double start_time_s) {
  if (path.numJoints() < 1 || !(path.duration_s > 0.0))
    throw std::invalid_argument("joint reference: the path has no joints or no duration");
  if (path.reference) throw std::invalid_argument("joint reference: the path follows a reference itself");
  if (!std::isfinite(start_time_s)) throw std::invalid_argument("joint reference: the start time is not finite");
  JointReference r;
  r.joints_ = path.numJoints();
  r.start_s_ = start_time_s;
  r.end_s_ = start_time_s + path.duration_s;
  r.path_ = std::move(path);
  return r;
}

double JointReference::derivative(int joint, double t, int order) const {
  if (joint < 0 || joint >= joints_) throw std::invalid_argument("joint reference: no joint " + std::to_string(joint));
  if (order < 0 || order > 5) throw std::invalid_argument("joint reference: derivative order must be 0..5");
  if (!std::isfinite(t)) throw std::invalid_argument("joint reference: the time is not finite");
  if (!path_) return splines_[static_cast<std::size_t>(joint)].continuedDerivative(t, order);
  // Before its start a plan rests at its start posture; after its end at its end posture (the
  // open-loop plans start and end with their first four derivatives zero).
  const double tau = std::min(std::max(0.0, t - start_s_), path_->duration_s);
  if (order > 0 && (t < start_s_ || t - start_s_ > path_->duration_s)) return 0.0;
  if (path_->spline) return path_->spline->derivativeAt(joint, tau, order);
  return path_->q[static_cast<std::size_t>(joint)].derivativeAt(tau, order);
}

void JointReference::jetInto(double t, Eigen::Ref<Jet> out) const {
  if (out.rows() != joints_ || out.cols() < 1 || out.cols() > 6)
    throw std::invalid_argument("joint reference: the jet needs " + std::to_string(joints_) + " rows and 1..6 columns");
  for (int j = 0; j < joints_; ++j)
    for (Eigen::Index k = 0; k < out.cols(); ++k) out(j, k) = derivative(j, t, static_cast<int>(k));
}

Jet JointReference::jet(double t, int orders) const {
  Jet out(joints_, orders);
  jetInto(t, out);
  return out;
}

}  // namespace flatsos::planner
