// The command-line programs, each a function of its own arguments, all in the one executable
// `flatsos`: `flatsos plan ...` and the old name `arm_open_loop ...` (a link to flatsos) both
// call arm_open_loop::run. argv[0] is the name the program's help and messages show.
#pragma once

namespace flatsos::programs {

namespace arm_forward {
int run(int argc, char** argv);
}
namespace arm_open_loop {
int run(int argc, char** argv);
}
namespace arm_receding_horizon {
int run(int argc, char** argv);
}
namespace opensim_to_model {
int run(int argc, char** argv);
}
namespace process_motion {
int run(int argc, char** argv);
}
namespace static_optimization {
int run(int argc, char** argv);
}
namespace track_motion {
int run(int argc, char** argv);
}

}  // namespace flatsos::programs
