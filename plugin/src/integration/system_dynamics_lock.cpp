#include "system_dynamics_lock.hpp"

#include <memory>
#include <unordered_map>

namespace flatsos::plugin::detail {

std::unique_lock<std::recursive_mutex> lock_system_dynamics(const SimTK::System& system) {
  static std::mutex registry_mutex;
  static std::unordered_map<const SimTK::System*, std::unique_ptr<std::recursive_mutex>> registry;
  std::recursive_mutex* lock = nullptr;
  {
    const std::lock_guard<std::mutex> guard(registry_mutex);
    auto& entry = registry[&system];
    if (!entry) entry = std::make_unique<std::recursive_mutex>();
    lock = entry.get();
  }
  return std::unique_lock<std::recursive_mutex>(*lock);
}

}  // namespace flatsos::plugin::detail
