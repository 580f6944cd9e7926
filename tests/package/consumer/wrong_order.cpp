// `using namespace SimTK;` before a flatsos header that includes Eigen: cannot compile (Eigen's
// constant expressions meet SimTK's catch-all operator!=); the first error must be flatsos'
// guard, which says what to do.
#include <Simbody.h>
using namespace SimTK;
#include "flatsos/planner/slp.hpp"

int main() { return 0; }
