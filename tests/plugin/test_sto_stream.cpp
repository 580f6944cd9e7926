// Storage files written row by row (long runs): the same file write_sto writes for the same table,
// nothing in place until finish(), and nothing left behind by a stream that never finished.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "flatsos/plugin/io/sto_stream.hpp"

namespace fp = flatsos::plugin;
namespace fs = std::filesystem;

namespace {

// A folder of its own, removed with everything in it when the test ends.
struct TempFolder {
  explicit TempFolder(const std::string& name)
      : path(fs::temp_directory_path() /
             ("flatsos_test_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempFolder() { fs::remove_all(path); }
  long files() const {
    return std::distance(fs::directory_iterator(path), fs::directory_iterator());
  }
  fs::path path;
};

std::string text_of(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

fp::StoTable example_table() {
  fp::StoTable t;
  t.name = "simulation";
  t.metadata = {{"integrator_accuracy", "1e-05"}};
  t.columns = {"time", "/jointset/elbow/r_elbow_flex/value", "/forceset/BIClong/activation"};
  t.rows = {{0.0, 0.1, 1.0 / 3.0}, {0.01, -2.5e-17, 0.404}, {0.02, 1e300, 5e-324}};
  return t;
}

}  // namespace

TEST(StoStream, WritesTheFileWriteStoWritesForTheSameRows) {
  const TempFolder dir("sto_stream");
  const fp::StoTable table = example_table();
  fp::write_sto((dir.path / "whole.sto").string(), table);
  {
    fp::StoStream stream((dir.path / "streamed.sto").string(), table);  // its rows are ignored
    for (const auto& row : table.rows) stream.append(row);
    EXPECT_FALSE(fs::exists(dir.path / "streamed.sto"));  // nothing in place before finish()
    stream.header().metadata.emplace_back("interrupted", "false");
    stream.finish();
  }
  fp::StoTable with_flag = table;
  with_flag.metadata.emplace_back("interrupted", "false");
  fp::write_sto((dir.path / "whole_with_flag.sto").string(), with_flag);
  EXPECT_EQ(text_of(dir.path / "streamed.sto"), text_of(dir.path / "whole_with_flag.sto"));
  EXPECT_EQ(fp::read_sto((dir.path / "streamed.sto").string()).rows, table.rows);
  EXPECT_EQ(dir.files(), 3);  // no temporary file left
}

TEST(StoStream, AStreamNeverFinishedLeavesThePreviousFileAndNoTemporary) {
  const TempFolder dir("sto_stream_unfinished");
  const fp::StoTable table = example_table();
  const std::string path = (dir.path / "run.sto").string();
  fp::write_sto(path, table);
  {
    fp::StoStream stream(path, table);
    stream.append(table.rows[0]);
  }
  EXPECT_EQ(fp::read_sto(path).rows.size(), 3u);
  EXPECT_EQ(dir.files(), 1);
}

TEST(StoStream, ARowOfTheWrongWidthOrAnUnwritableFolderIsAnErrorNamingTheFile) {
  const TempFolder dir("sto_stream_bad");
  fp::StoStream stream((dir.path / "bad.sto").string(), example_table());
  try {
    stream.append({0.0, 1.0});
    FAIL() << "accepted a row of 2 values for 3 columns";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.sto"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fp::StoStream("/nonexistent_dir_flatsos/x.sto", example_table()),
               std::runtime_error);
  stream.finish();
  EXPECT_THROW(stream.finish(), std::runtime_error);
  EXPECT_EQ(fp::read_sto((dir.path / "bad.sto").string()).rows.size(), 0u);
}
