// Files: .sto round trips and atomic writes, excitation CSV schedules and their errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "flatsos/plugin/io/excitation_file.hpp"
#include "flatsos/plugin/io/sto_file.hpp"

namespace fp = flatsos::plugin;
namespace fs = std::filesystem;

namespace {
fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("flatsos_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}
void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }
const std::vector<std::string> kMuscles = {"a", "b"};
}  // namespace

TEST(StoFile, RoundTripIsExactAndHeaderIsOpenSimStyle) {
  const auto dir = temp_dir("sto");
  fp::StoTable t;
  t.name = "states";
  t.metadata = {{"status", "solved"}, {"objective", "1.5"}};
  t.columns = {"time", "/jointset/shoulder/shoulder/value", "/forceset/biceps/activation"};
  t.rows = {{0.0, 0.1, 1.0 / 3.0}, {0.01, -2.5e-17, 0.404}};
  const auto path = (dir / "s.sto").string();
  fp::write_sto(path, t);
  std::ifstream in(path);
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "states");
  EXPECT_EQ(second, "version=1");
  const auto back = fp::read_sto(path);
  EXPECT_EQ(back.name, "states");
  EXPECT_EQ(back.columns, t.columns);
  EXPECT_EQ(back.rows, t.rows);  // max_digits10: bit-exact
  EXPECT_EQ(back.metadataValue("status"), "solved");
  EXPECT_EQ(back.column("/forceset/biceps/activation")[1], 0.404);
  EXPECT_THROW(back.column("/nope"), std::runtime_error);
  // Nothing but the result is left in the folder.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(StoFile, BadRowsAndUnwritableFoldersFailWithoutLeavingAFile) {
  const auto dir = temp_dir("sto_bad");
  fp::StoTable t;
  t.columns = {"time", "x"};
  t.rows = {{0.0}};
  EXPECT_THROW(fp::write_sto((dir / "bad.sto").string(), t), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "bad.sto"));
  t.rows = {{0.0, 1.0}};
  EXPECT_THROW(fp::write_sto("/nonexistent_dir_flatsos/x.sto", t), std::runtime_error);
  // A previous result survives a failed rewrite.
  fp::write_sto((dir / "keep.sto").string(), t);
  t.rows = {{0.0, 1.0, 2.0}};
  EXPECT_THROW(fp::write_sto((dir / "keep.sto").string(), t), std::runtime_error);
  EXPECT_EQ(fp::read_sto((dir / "keep.sto").string()).rows.size(), 1u);
}

TEST(ExcitationCsv, InterpolatesLinearlyHoldsAfterTheLastRowAndReordersColumns) {
  const auto dir = temp_dir("csv");
  write_text(dir / "n.csv", "time, b, a\n0, 0.1, 0.2\n1.0, 0.3, 0.6\n");
  const auto sig = fp::read_excitation_csv((dir / "n.csv").string(), kMuscles);
  ASSERT_EQ(sig.size(), 2u);
  EXPECT_NEAR(sig[0]->value(0.5), 0.4, 1e-15);   // muscle "a"
  EXPECT_NEAR(sig[1]->value(0.25), 0.15, 1e-15);  // muscle "b"
  EXPECT_EQ(sig[0]->value(7.0), 0.6);
  EXPECT_EQ(sig[0]->value(-1.0), 0.2);
}

TEST(ExcitationCsv, BadFilesNameTheProblem) {
  const auto dir = temp_dir("csv_bad");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "empty file"},
      {"t,a,b\n0,0,0\n", "'time'"},
      {"time,a\n0,0\n", "no column for muscle 'b'"},
      {"time,a,b,c\n0,0,0,0\n", "unknown muscle column 'c'"},
      {"time,a,a,b\n0,0,0,0\n", "duplicate column 'a'"},
      {"time,a,b\n0,0.1,x\n", "'x' in column 'b' is not a number"},
      {"time,a,b\n0,0.1,nan\n", "not finite"},
      {"time,a,b\n0,0.1,1.2\n", "outside [0, 1]"},
      {"time,a,b\n0,0.1,0.1\n0,0.2,0.2\n", "increase strictly"},
      {"time,a,b\n0,0.1\n", "2 cells for 3 columns"},
      {"time,a,b\n", "no data rows"},
  };
  for (const auto& [text, expected] : cases) {
    write_text(dir / "bad.csv", text);
    try {
      fp::read_excitation_csv((dir / "bad.csv").string(), kMuscles);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(fp::read_excitation_csv((dir / "missing.csv").string(), kMuscles), std::runtime_error);
}

TEST(ExcitationSto, ReadsMocoControlsByActuatorPathInAnyColumnOrder) {
  const auto dir = temp_dir("sto");
  fp::StoTable controls;
  controls.name = "controls";
  controls.columns = {"time", "/forceset/b", "a"};  // Moco's path, or the bare name
  controls.rows = {{0.0, 0.1, 0.2}, {1.0, 0.3, 0.6}};
  fp::write_sto((dir / "c.sto").string(), controls);
  const auto sig = fp::read_excitation_file((dir / "c.sto").string(), kMuscles);
  ASSERT_EQ(sig.size(), 2u);
  EXPECT_NEAR(sig[0]->value(0.5), 0.4, 1e-15);
  EXPECT_NEAR(sig[1]->value(0.25), 0.15, 1e-15);
  const std::vector<std::pair<std::vector<std::vector<double>>, std::string>> bad_rows = {
      {{{0.0, 0.1, 1.5}}, "data row 1: excitation 1.5"},
      {{{0.0, 0.1, 0.1}, {0.0, 0.2, 0.2}}, "data row 2: times must increase strictly"},
      {{}, "no data rows"},
  };
  for (const auto& [rows, expected] : bad_rows) {
    controls.rows = rows;
    fp::write_sto((dir / "bad.sto").string(), controls);
    try {
      fp::read_excitation_sto((dir / "bad.sto").string(), kMuscles);
      ADD_FAILURE() << "accepted: " << expected;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.sto"), std::string::npos) << e.what();
    }
  }
  controls.columns = {"time", "/forceset/b", "/forceset/c"};
  controls.rows = {{0.0, 0.1, 0.2}};
  fp::write_sto((dir / "unknown.sto").string(), controls);
  EXPECT_THROW(fp::read_excitation_sto((dir / "unknown.sto").string(), kMuscles), std::runtime_error);
  EXPECT_THROW(fp::read_excitation_sto((dir / "missing.sto").string(), kMuscles), std::runtime_error);
}

TEST(PiecewiseLinearSignal, RejectsBadSamples) {
  EXPECT_THROW(fp::PiecewiseLinearSignal({}, {}), std::invalid_argument);
  EXPECT_THROW(fp::PiecewiseLinearSignal({0.0, 1.0}, {0.0}), std::invalid_argument);
  EXPECT_THROW(fp::PiecewiseLinearSignal({1.0, 0.0}, {0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(fp::PiecewiseLinearSignal({0.0, std::nan("")}, {0.0, 1.0}), std::invalid_argument);
  const fp::PiecewiseLinearSignal one({2.0}, {0.3});
  EXPECT_EQ(one.value(0.0), 0.3);
  EXPECT_EQ(one.value(5.0), 0.3);
}
