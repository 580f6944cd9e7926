#include "bindings.hpp"

PYBIND11_MODULE(_flatsos, m) {
  m.doc() = "flatsos: minimum-effort muscle excitations by differential flatness and SOS programming (C++ core)";
  flatsos::python::register_model(m);
  flatsos::python::register_open_loop(m);
  flatsos::python::register_simulation(m);
  flatsos::python::register_receding_horizon(m);
  flatsos::python::register_static_optimization(m);
  flatsos::python::register_inverse_problem(m);
  flatsos::python::register_tracking(m);
}
