// flatsos <subcommand> [options]: one command for every program. Each subcommand runs the program
// of that name beside this one in bin/ (its old name, which keeps working) or the Python module of
// the package, with the same options; `flatsos <subcommand> --help` prints that program's help.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

struct Subcommand {
  const char* name;
  const char* program;  // a program in bin/, or a module of the Python package ("flatsos.study")
  const char* what;
};

constexpr Subcommand kSubcommands[] = {
    {"plan", "arm_open_loop", "an open-loop minimum-effort plan, replayed by Simbody"},
    {"control", "arm_receding_horizon",
     "the receding-horizon controller to a target, on a Simbody plant"},
    {"track", "track_motion", "the controller following a measured motion (as OpenSim's CMC)"},
    {"static-optimization", "static_optimization",
     "OpenSim's static optimization along a measured motion"},
    {"simulate", "arm_forward",
     "a forward simulation under excitations from a controls .sto or a CSV"},
    {"import", "opensim_to_model",
     "an OpenSim model with your choice of coordinates, as a model file"},
    {"process-motion", "process_motion",
     "a measured motion filtered and differentiated as the tasks use it"},
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
  out << "\nEach is also a program of its own (flatsos plan is arm_open_loop, ...), with the same "
         "options.\n";
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

int run(const Subcommand& s, int argc, char** argv) {
  const fs::path bin = this_programs_folder();
  const std::string display =
      std::string("flatsos ") + s.name;  // the name the program's help shows
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
                << (std::strcmp(s.name, "bench") == 0 ? " (configure with -DFLATSOS_BUILD_BENCH=ON)" : "")
                << "\n";
      return 1;
    }
    args = {display};
  }
  for (int i = 2; i < argc; ++i) args.emplace_back(argv[i]);
  std::vector<char*> pointers;
  for (std::string& a : args) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  execv(executable.c_str(), pointers.data());
  std::cerr << "flatsos " << s.name << ": cannot run " << executable << ": " << std::strerror(errno)
            << "\n";
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
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
