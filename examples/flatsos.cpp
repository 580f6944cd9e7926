// flatsos <subcommand> [options]: one command for every program. The C++ programs are compiled
// into this executable; their old names (arm_open_loop, ...) are links to it that run the program
// of that name. The Python subcommands run a module of the package, and `bench` runs flatsos_bench
// beside this program. `flatsos <subcommand> --help` prints that program's help.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "programs.hpp"

namespace {

namespace fs = std::filesystem;

namespace programs = flatsos::programs;

struct Subcommand {
  const char* name;
  const char*
      program;  // its old name, a module of the Python package ("flatsos.study"), or a script
  const char* what;
  int (*run_in_process)(int argc, char** argv) = nullptr;  // a program compiled into this one
};

constexpr Subcommand kSubcommands[] = {
    {"plan", "arm_open_loop", "an open-loop minimum-effort plan, replayed by Simbody",
     programs::arm_open_loop::run},
    {"control", "arm_receding_horizon",
     "the receding-horizon controller to a target, on a Simbody plant",
     programs::arm_receding_horizon::run},
    {"track", "track_motion", "the controller following a measured motion (as OpenSim's CMC)",
     programs::track_motion::run},
    {"static-optimization", "static_optimization",
     "OpenSim's static optimization along a measured motion", programs::static_optimization::run},
    {"simulate", "arm_forward",
     "a forward simulation under excitations from a controls .sto or a CSV",
     programs::arm_forward::run},
    {"import", "opensim_to_model",
     "an OpenSim model with your choice of coordinates, as a model file",
     programs::opensim_to_model::run},
    {"process-motion", "process_motion",
     "a measured motion filtered and differentiated as the tasks use it",
     programs::process_motion::run},
    {"bench", "flatsos_bench", "the benchmarks, as JSON"},
    {"study", "flatsos.study", "a batch study of plans or tracking runs on Dask"},
    {"animate", "flatsos.animation",
     "a GIF or MP4 of a run's motion, each muscle coloured by its activation"},
    {"motion", "flatsos.sto", "an OpenSim motion file (.mot) of a run, for the original .osim"},
    {"plot", "plot_results.py", "PNG figures of any program's output folders"},
};

void print_help(std::ostream& out) {
  out << "flatsos: minimum-effort muscle excitations by differential flatness and SOS "
         "programming.\n"
         "Usage: flatsos <subcommand> [options]    (flatsos <subcommand> --help for its "
         "options)\n\n"
         "Subcommands:\n";
  for (const Subcommand& s : kSubcommands) {
    std::string name = s.name;
    name.resize(21, ' ');
    out << "  " << name << s.what << "\n";
  }
  out << "\nThe C++ ones also answer to their old names (flatsos plan is arm_open_loop, ...), with "
         "the "
         "same options.\n";
}

bool is_python_module(const Subcommand& s) { return std::strncmp(s.program, "flatsos.", 8) == 0; }
bool is_python_script(const Subcommand& s) { return fs::path(s.program).extension() == ".py"; }

fs::path this_programs_folder() {
  std::error_code error;
  const fs::path exe = fs::canonical("/proc/self/exe", error);
  return error ? fs::current_path() : exe.parent_path();
}

// The folder holding the Python package beside this program: the build tree's python/, or an
// install prefix's dist-packages.
fs::path python_package_folder(const fs::path& bin) {
  for (const fs::path& candidate :
       {bin.parent_path() / "python", bin.parent_path() / FLATSOS_PYTHON_INSTALL_DIR})
    if (fs::exists(candidate / "flatsos" / "__init__.py")) return candidate;
  return {};
}

// A script of the project's: installed in share/flatsos/, or in the source tree of this build.
fs::path script_path(const fs::path& bin, const char* name) {
  for (const fs::path& candidate : {bin.parent_path() / "share" / "flatsos" / name,
                                    fs::path(FLATSOS_SOURCE_DIR) / "scripts" / name})
    if (fs::exists(candidate)) return candidate;
  return {};
}

// `flatsos <name> args...` as `head... args...`.
std::vector<std::string> with_arguments(std::vector<std::string> head, int argc, char** argv) {
  for (int i = 2; i < argc; ++i) head.emplace_back(argv[i]);
  return head;
}

std::vector<char*> pointers_to(std::vector<std::string>& args) {
  std::vector<char*> pointers;
  for (std::string& a : args) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  return pointers;
}

int run_elsewhere(const Subcommand& s, int argc, char** argv) {
  const fs::path bin = this_programs_folder();
  std::vector<std::string> args;
  std::string executable;
  if (is_python_module(s)) {
    const fs::path package = python_package_folder(bin);
    if (package.empty()) {
      std::cerr << "flatsos " << s.name << ": the Python package is not beside " << bin.string()
                << " (built with -DFLATSOS_BUILD_PYTHON=OFF?)\n";
      return 1;
    }
    const char* old = std::getenv("PYTHONPATH");
    const std::string path =
        package.string() + (old && *old ? std::string(":") + old : std::string());
    setenv("PYTHONPATH", path.c_str(), 1);
    executable = FLATSOS_PYTHON_EXECUTABLE;
    args = {executable, "-m", s.program};
  } else if (is_python_script(s)) {
    const fs::path script = script_path(bin, s.program);
    if (script.empty()) {
      std::cerr << "flatsos " << s.name << ": " << s.program
                << " is neither installed nor in the source tree\n";
      return 1;
    }
    executable = FLATSOS_PYTHON_EXECUTABLE;
    args = {executable, script.string()};
  } else {
    executable = (bin / s.program).string();
    if (!fs::exists(executable)) {
      std::cerr << "flatsos " << s.name << ": " << s.program << " is not built beside this program"
                << (std::strcmp(s.name, "bench") == 0 ? " (configure with -DFLATSOS_BUILD_BENCH=ON)"
                                                      : "")
                << "\n";
      return 1;
    }
    args = {std::string("flatsos ") + s.name};
  }
  args = with_arguments(args, argc, argv);
  std::vector<char*> pointers = pointers_to(args);
  execv(executable.c_str(), pointers.data());
  std::cerr << "flatsos " << s.name << ": cannot run " << executable << ": " << std::strerror(errno)
            << "\n";
  return 1;
}

int run(const Subcommand& s, int argc, char** argv) {
  if (!s.run_in_process) return run_elsewhere(s, argc, argv);
  // argv[0] is the name the program's help shows.
  std::vector<std::string> args = with_arguments({std::string("flatsos ") + s.name}, argc, argv);
  std::vector<char*> pointers = pointers_to(args);
  return s.run_in_process(static_cast<int>(args.size()), pointers.data());
}

// Called by an old name (a link to this executable): that program, with argv as given.
const Subcommand* program_called(const char* argv0) {
  const std::string called = fs::path(argv0).filename().string();
  for (const Subcommand& s : kSubcommands)
    if (s.run_in_process && called == s.program) return &s;
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  if (const Subcommand* program = program_called(argv[0]))
    return program->run_in_process(argc, argv);
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    print_help(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  for (const Subcommand& s : kSubcommands)
    if (s.name == std::string(argv[1])) return run(s, argc, argv);
  std::cerr << "flatsos: unknown subcommand '" << argv[1] << "'\n\n";
  print_help(std::cerr);
  return 2;
}
