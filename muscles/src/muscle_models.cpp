// The registry of muscle models by the names model files use.

#include <stdexcept>

#include "flatsos/muscles/degroote_fregly2016_muscle.hpp"
#include "flatsos/muscles/millard2012_muscle.hpp"
#include "flatsos/muscles/muscle_model.hpp"
#include "flatsos/muscles/richter_warner_muscle.hpp"
#include "flatsos/muscles/thelen2003_muscle.hpp"
#include "flatsos/muscles/thelen2003_opensim2_muscle.hpp"

namespace flatsos::muscles {

std::shared_ptr<const MuscleModel> default_muscle_model() {
  static const std::shared_ptr<const MuscleModel> model = std::make_shared<RichterWarnerMuscle>();
  return model;
}

namespace {
std::shared_ptr<const MuscleModel> thelen2003() {
  static const std::shared_ptr<const MuscleModel> model = std::make_shared<Thelen2003Muscle>();
  return model;
}
std::shared_ptr<const MuscleModel> thelen2003_opensim2() {
  static const std::shared_ptr<const MuscleModel> model = std::make_shared<Thelen2003OpenSim2Muscle>();
  return model;
}
std::shared_ptr<const MuscleModel> degroote_fregly2016() {
  static const std::shared_ptr<const MuscleModel> model = std::make_shared<DeGrooteFregly2016Muscle>();
  return model;
}
// OpenSim's default Millard muscle (damped, default curves); muscles with other curves are
// their own Millard2012Muscle instances.
std::shared_ptr<const MuscleModel> millard2012() {
  static const std::shared_ptr<const MuscleModel> model = std::make_shared<Millard2012Muscle>();
  return model;
}
}  // namespace

OwnFiberVelocity MuscleModel::ownFiberVelocity(const MuscleParameters&, double, double, double) const {
  throw std::logic_error("muscle model '" + name() + "' has no velocity law of its own");
}

std::vector<std::string> muscle_model_names() {
  return {RichterWarnerMuscle::kName, Thelen2003Muscle::kName, Thelen2003OpenSim2Muscle::kName,
          DeGrooteFregly2016Muscle::kName, Millard2012Muscle::kName};
}

std::shared_ptr<const MuscleModel> muscle_model_named(const std::string& name) {
  if (name == RichterWarnerMuscle::kName) return default_muscle_model();
  if (name == Thelen2003Muscle::kName) return thelen2003();
  if (name == Thelen2003OpenSim2Muscle::kName) return thelen2003_opensim2();
  if (name == DeGrooteFregly2016Muscle::kName) return degroote_fregly2016();
  if (name == Millard2012Muscle::kName) return millard2012();
  std::string known;
  for (const std::string& n : muscle_model_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown muscle model '" + name + "' (known: " + known + ")");
}

}  // namespace flatsos::muscles
