// OpenSim GeometryPaths as the simulation's path geometry (opensim_path_geometry.hpp).

#include "flatsos/plugin/paths/opensim_path_geometry.hpp"

#include "flatsos/plugin/paths/path_evaluation.hpp"

namespace flatsos::plugin {

namespace {

class OpenSimPathGeometry final : public PathGeometry {
 public:
  OpenSimPathGeometry(std::shared_ptr<const OpenSimModel> osim, std::shared_ptr<const OpenSimGeometryPaths> geometry,
                      const std::string& muscle, std::vector<std::string> arguments, const std::map<std::string, double>& held)
      : osim_(std::move(osim)), geometry_(std::move(geometry)), path_(*osim_, *geometry_, muscle),
        arguments_(std::move(arguments)), held_(held) {
    for (const OpenSimCoordinate& c : osim_->coordinates) {
      const auto h = held_.find(c.name);
      base_[c.name] = h == held_.end() ? 0.0 : h->second;
    }
  }

  double length_m(const double* x) const override { return path_.length(posture(x)); }

  void momentArms(const double* x, double* out) const override {
    const OpenSimCoordinateValues q = posture(x);
    for (std::size_t k = 0; k < arguments_.size(); ++k) out[k] = arguments_[k].empty() ? 0.0 : path_.momentArm(q, arguments_[k]);
  }

  // Central differences of the length (the geometry gives no derivative of it in closed form).
  void lengthGradient(const double* x, double* out) const override {
    constexpr double kStep = 1e-6;  // rad or m
    std::vector<double> moved(x, x + arguments_.size());
    for (std::size_t k = 0; k < arguments_.size(); ++k) {
      if (arguments_[k].empty()) {
        out[k] = 0.0;
        continue;
      }
      moved[k] = x[k] + kStep;
      const double up = path_.length(posture(moved.data()));
      moved[k] = x[k] - kStep;
      out[k] = (up - path_.length(posture(moved.data()))) / (2.0 * kStep);
      moved[k] = x[k];
    }
  }

 private:
  // The OpenSim posture of the arguments: held coordinates at their values, coupled ones
  // following their independent coordinate (unless held), as the import reduced the model.
  OpenSimCoordinateValues posture(const double* x) const {
    OpenSimCoordinateValues q = base_;
    for (std::size_t k = 0; k < arguments_.size(); ++k)
      if (!arguments_[k].empty()) q[arguments_[k]] = x[k];
    for (const OpenSimCoupler& c : osim_->couplers)
      if (!held_.count(c.dependent)) q[c.dependent] = c.scale * c.function.value(q.at(c.independent));
    return q;
  }

  std::shared_ptr<const OpenSimModel> osim_;
  std::shared_ptr<const OpenSimGeometryPaths> geometry_;
  GeometryPathEvaluator path_;      // refers to *osim_ and *geometry_, kept alive above
  std::vector<std::string> arguments_;  // "" for an argument the import held
  std::map<std::string, double> held_;
  OpenSimCoordinateValues base_;
};

}  // namespace

void attach_geometry_paths(ModelDescription& model, std::shared_ptr<const OpenSimModel> osim,
                           std::shared_ptr<const OpenSimGeometryPaths> geometry, const std::map<std::string, double>& held) {
  for (int j = 0; j < model.numMuscles(); ++j) {
    std::vector<std::string> arguments;
    const muscles::MusculotendonPath path = model.musclePath(j);
    for (const muscles::PathCoordinate& c : path.coordinates())
      arguments.push_back(c.held() ? std::string() : model.joints[static_cast<std::size_t>(c.joint)].coordinateName());
    MuscleDescription& muscle = model.muscles[static_cast<std::size_t>(j)];
    muscle.path_geometry =
        std::make_shared<OpenSimPathGeometry>(osim, geometry, muscle.parameters.name, std::move(arguments), held);
  }
}

}  // namespace flatsos::plugin
