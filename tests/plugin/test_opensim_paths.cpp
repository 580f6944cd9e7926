// Reading OpenSim's fitted muscle paths (FunctionBasedPathSet): the fields as written, every bad
// document named by file and muscle, and, where OpenSim's example files are present beside the
// repository (../shared/opensim, not part of a clone), the real file: 80 muscles, and moment
// arms whose signs are anatomy's when the coefficients are read in OpenSim's order.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "flatsos/muscles/length_polynomial.hpp"
#include "flatsos/plugin/io/opensim_paths.hpp"

namespace fp = flatsos::plugin;
using flatsos::muscles::LengthPolynomial;

namespace {

std::string document(const std::string& objects) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<OpenSimDocument Version=\"40600\"><Set_FunctionBasedPath_><objects>" +
         objects + "</objects></Set_FunctionBasedPath_></OpenSimDocument>";
}

std::string path(const std::string& name, const std::string& coordinates, const std::string& coefficients,
                 const std::string& dimension, const std::string& order) {
  return "<FunctionBasedPath name=\"/forceset/" + name + "\"><coordinate_paths>" + coordinates +
         "</coordinate_paths><length_function><MultivariatePolynomialFunction><coefficients>" + coefficients +
         "</coefficients><dimension>" + dimension + "</dimension><order>" + order +
         "</order></MultivariatePolynomialFunction></length_function></FunctionBasedPath>";
}

const std::string kKnee = "/jointset/walker_knee_r/knee_angle_r";
const std::string kHipKnee = "/jointset/hip_r/hip_flexion_r /jointset/walker_knee_r/knee_angle_r";

std::string error_of(const std::string& xml) {
  try {
    fp::parse_opensim_function_based_paths(xml, "paths.xml");
  } catch (const fp::OpenSimFileError& e) {
    return e.what();
  }
  return "accepted";
}

std::string shared_file(const std::string& name) { return std::string(FLATSOS_SOURCE_DIR) + "/../shared/opensim/" + name; }

}  // namespace

TEST(OpenSimPaths, TheFieldsAreReadAsWritten) {
  const auto paths = fp::parse_opensim_function_based_paths(
      document(path("vasint_r", kKnee, "0.2 0.03", "1", "1") + path("recfem_r", kHipKnee, "0.4 0.01 -0.02 0.003 0 0", "2", "2")),
      "paths.xml");
  ASSERT_EQ(paths.size(), 2u);
  EXPECT_EQ(paths[0].muscle, "vasint_r");
  EXPECT_EQ(paths[0].force_path, "/forceset/vasint_r");
  EXPECT_EQ(paths[1].coordinate_paths, (std::vector<std::string>{"/jointset/hip_r/hip_flexion_r", kKnee}));
  EXPECT_EQ(paths[1].coordinates, (std::vector<std::string>{"hip_flexion_r", "knee_angle_r"}));
  EXPECT_EQ(paths[1].order, 2);
  EXPECT_EQ(paths[1].coefficients, (std::vector<double>{0.4, 0.01, -0.02, 0.003, 0.0, 0.0}));
  // OpenSim's order for (hip, knee), order 2: 1, knee, knee^2, hip, hip knee, hip^2.
  const LengthPolynomial p(2, paths[1].order, paths[1].coefficients);
  const double x[2] = {0.5, 1.5};
  EXPECT_DOUBLE_EQ(p.value(x), 0.4 + 0.01 * 1.5 - 0.02 * 1.5 * 1.5 + 0.003 * 0.5);
}

TEST(OpenSimPaths, EachBadDocumentIsNamedByFileAndMuscle) {
  EXPECT_NE(error_of("<not xml").find("'paths.xml': not an XML document"), std::string::npos) << error_of("<not xml");
  EXPECT_NE(error_of("<OpenSimDocument><Model/></OpenSimDocument>").find("not a FunctionBasedPathSet"), std::string::npos);
  EXPECT_NE(error_of(document("")).find("no FunctionBasedPath"), std::string::npos);
  const struct {
    std::string xml, expected;
  } cases[] = {
      {path("vasint_r", kHipKnee, "0.2 0.03", "1", "1"), "FunctionBasedPath '/forceset/vasint_r': dimension 1 but 2 coordinate_paths"},
      {path("vasint_r", kKnee, "0.2 0.03 0.1", "1", "1"), "coefficients: 3 given, dimension 1 and order 1 need 2"},
      {path("vasint_r", kKnee, "0.2 zero", "1", "1"), "coefficients: 'zero' is not a finite number"},
      {path("vasint_r", kKnee, "0.2 nan", "1", "1"), "coefficients: 'nan' is not a finite number"},
      {path("vasint_r", kKnee, "0.2 0.03", "one", "1"), "length_function.dimension: must be one integer >= 0"},
      {path("vasint_r", kKnee, "0.2 0.03", "1", "-1"), "length_function.order: must be one integer >= 0"},
      {path("vasint_r", kKnee, "0.2 0.03", "1", "1") + path("vasint_r", kKnee, "0.2 0.03", "1", "1"),
       "muscle 'vasint_r' has two FunctionBasedPaths"},
      {"<FunctionBasedPath name=\"/forceset/soleus_r\"><coordinate_paths>" + kKnee +
           "</coordinate_paths><length_function><LinearFunction/></length_function></FunctionBasedPath>",
       "'/forceset/soleus_r'.length_function: not a MultivariatePolynomialFunction"},
  };
  for (const auto& c : cases) {
    const std::string what = error_of(document(c.xml));
    EXPECT_NE(what.find(c.expected), std::string::npos) << what;
    EXPECT_NE(what.find("'paths.xml'"), std::string::npos) << what;
  }
  try {
    fp::read_opensim_function_based_paths("/nonexistent/paths.xml");
    ADD_FAILURE() << "read a missing file";
  } catch (const fp::OpenSimFileError& e) {
    EXPECT_NE(std::string(e.what()).find("'/nonexistent/paths.xml': cannot open"), std::string::npos) << e.what();
  }
}

TEST(OpenSimPaths, OpenSimsExampleLegHasAnatomysSigns) {
  const std::string file = shared_file("subject_walk_scaled_FunctionBasedPathSet.xml");
  if (!std::ifstream(file)) GTEST_SKIP() << "OpenSim's example files are not beside the repository (" << file << ")";
  const auto paths = fp::read_opensim_function_based_paths(file);
  EXPECT_EQ(paths.size(), 80u);
  int right = 0;
  for (const auto& p : paths) right += p.muscle.size() > 2 && p.muscle.compare(p.muscle.size() - 2, 2, "_r") == 0;
  EXPECT_EQ(right, 40);
  auto find = [&](const std::string& muscle) -> const fp::OpenSimPolynomialPath& {
    for (const auto& p : paths)
      if (p.muscle == muscle) return p;
    throw std::runtime_error("no " + muscle);
  };
  // Moment arm about coordinate k = -dL/dq_k, all other coordinates at the given values.
  auto moment_arm = [&](const std::string& muscle, const std::string& coordinate, double q_rad) {
    const fp::OpenSimPolynomialPath& p = find(muscle);
    const LengthPolynomial length(static_cast<int>(p.coordinates.size()), p.order, p.coefficients);
    std::vector<double> x(p.coordinates.size(), 0.0);
    int k = -1;
    for (std::size_t i = 0; i < p.coordinates.size(); ++i)
      if (p.coordinates[i] == coordinate) k = static_cast<int>(i);
    if (k < 0) throw std::runtime_error(muscle + " does not depend on " + coordinate);
    x[static_cast<std::size_t>(k)] = q_rad;
    return -length.derivative(k).value(x.data());
  };
  EXPECT_EQ(find("vasint_r").coordinates, std::vector<std::string>{"knee_angle_r"});
  for (double knee : {0.2, 0.8, 1.4}) {  // knee flexion is positive: the vasti extend the knee
    EXPECT_LT(moment_arm("vasint_r", "knee_angle_r", knee), 0.0) << knee;
    EXPECT_LT(moment_arm("vaslat_r", "knee_angle_r", knee), 0.0) << knee;
    EXPECT_GT(moment_arm("bfsh_r", "knee_angle_r", knee), 0.0) << knee;  // the short biceps femoris flexes it
  }
  for (double ankle : {-0.4, 0.0, 0.4}) EXPECT_LT(moment_arm("soleus_r", "ankle_angle_r", ankle), 0.0) << ankle;
  for (double hip : {-0.3, 0.5, 1.2}) EXPECT_GT(moment_arm("iliacus_r", "hip_flexion_r", hip), 0.0) << hip;
}
