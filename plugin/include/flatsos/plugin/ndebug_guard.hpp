#pragma once
// Debian's Simbody 3.7 changes the layout of SimTK::State with NDEBUG (Simbody issue 701): a
// State made in code compiled with -DNDEBUG and used by flatsos (compiled without) crashes, e.g.
// in realizeTopology. Every flatsos header that includes Simbody includes this one first, so
// such code stops here instead.
// IF THE #error BELOW FIRES: compile without NDEBUG. With CMake, link flatsos::plugin (or
// flatsos::planner): it adds -UNDEBUG to your compile lines. Otherwise remove -DNDEBUG or add
// -UNDEBUG after it.
#ifdef NDEBUG
#error "flatsos: compile code that uses Simbody without NDEBUG (Debian's Simbody changes SimTK::State with it); link flatsos::plugin in CMake, or add -UNDEBUG. See flatsos/plugin/ndebug_guard.hpp"
#endif
