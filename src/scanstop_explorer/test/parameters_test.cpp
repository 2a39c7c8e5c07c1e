// The explorer's one parameter list (parameters.h): the offline tools read config/explorer.yaml
// with it as explorer_node reads its ROS parameters, so that a tool plans like a mission.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <unistd.h>
#include <cstdlib>
#include <set>
#include <string>
#include <type_traits>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_explorer/parameters.h"

using namespace scanstop;
using namespace scanstop::explorer;

namespace {
std::string tempFile(const std::string& text) {
  char tmpl[] = "/tmp/explorer_params_test_XXXXXX";
  const int fd = mkstemp(tmpl);
  if (fd < 0) throw std::runtime_error("mkstemp failed");
  close(fd);
  writeFileAtomic(tmpl, text);
  return tmpl;
}
std::string errorOf(const std::string& text) {
  const std::string path = tempFile(text);
  ExplorerConfig c;
  std::string what;
  try {
    readParameterFile(path, c);
  } catch (const std::exception& e) {
    what = e.what();
  }
  std::remove(path.c_str());
  return what;
}
}  // namespace

TEST(ExplorerParameters, NamesAreUniqueAndCarryTheirFields) {
  ExplorerConfig c;
  std::set<std::string> names;
  std::set<const void*> fields;
  int n = 0;
  forEachParameter(c, [&](const char* name, auto& value) {
    names.insert(name);
    fields.insert(&value);
    ++n;
  });
  EXPECT_EQ(static_cast<int>(names.size()), n);
  EXPECT_EQ(static_cast<int>(fields.size()), n);
  EXPECT_TRUE(names.count("k_r_m") && names.count("min_obstacle_scans") && names.count("contact_radius_m"));
}

TEST(ExplorerParameters, TheMissionsExplorerYamlIsReadAsTheNodeReadsIt) {
  const std::string path = std::string(SCANSTOP_CONFIG_DIR) + "/explorer.yaml";
  ExplorerConfig c;
  ASSERT_NO_THROW(readParameterFile(path, c));
  // Every value of the file landed in its field (compared through the same list).
  const YAML::Node file = YAML::LoadFile(path);
  int checked = 0;
  forEachParameter(c, [&](const char* name, auto& value) {
    if (!file[name]) return;
    using T = std::decay_t<decltype(value)>;
    EXPECT_EQ(value, file[name].as<T>()) << name;
    ++checked;
  });
  EXPECT_GE(checked, 5);
  EXPECT_DOUBLE_EQ(c.planner.k_r_m, file["k_r_m"].as<double>());
  // The body (0.26 m, config/robot_body.yaml) plus the file's inflation margin.
  EXPECT_NEAR(c.planner.robot_radius_m, RobotBody().radius_m + file["inflation_margin_m"].as<double>(), 1e-12);
  // Not in the file: the built-in default.
  EXPECT_EQ(c.floor.min_obstacle_scans, ExplorerConfig().floor.min_obstacle_scans);
}

TEST(ExplorerParameters, BadFilesAreNamedWithTheParameter) {
  EXPECT_NE(errorOf("k_r_m: 2.0\nkr_m: 1.0\n").find("unknown explorer parameter 'kr_m'"), std::string::npos);
  EXPECT_NE(errorOf("min_obstacle_scans: 2.5\n").find("min_obstacle_scans = '2.5' is not an integer"),
            std::string::npos);
  EXPECT_NE(errorOf("d_max_m: far\n").find("d_max_m = 'far' is not a number"), std::string::npos);
  EXPECT_NE(errorOf("ignore_wall_base_frontier: maybe\n").find("is not true or false"), std::string::npos);
  EXPECT_NE(errorOf("d_max_m: -1\n").find("d_max_m"), std::string::npos);  // out of range
  EXPECT_NE(errorOf("inflation_margin_m: 3\n").find("inflation_margin_m"), std::string::npos);
  EXPECT_NE(errorOf("- 1\n- 2\n").find("expected a map"), std::string::npos);
  EXPECT_NE(errorOf("a: [\n").find("not a YAML file"), std::string::npos);
  EXPECT_EQ(errorOf(""), "");  // empty: the defaults
  ExplorerConfig c;
  EXPECT_THROW(readParameterFile("/nonexistent/explorer.yaml", c), IoError);
  // Explicit robot_radius_m overrides the body.
  const std::string path = tempFile("inflation_margin_m: 0.1\nrobot_radius_m: 0.5\n");
  readParameterFile(path, c);
  std::remove(path.c_str());
  EXPECT_DOUBLE_EQ(c.planner.robot_radius_m, 0.5);
}

// explorer_node writes its configuration into its run directory (config.yaml): read back, it is the
// same configuration, body-derived radius and height included, also when they differ from the body.
TEST(ExplorerParameters, TheRunsConfigurationFileReadsBackToTheSameConfiguration) {
  ExplorerConfig c;
  c.planner.k_r_m = 2.5;
  c.planner.knowledge_model = "visibility";
  c.planner.ignore_wall_base_frontier = !c.planner.ignore_wall_base_frontier;
  c.floor.resolution_m = 0.1;
  c.floor.min_obstacle_scans = 3;
  c.known_free_radius_m = 1.0 / 3.0;  // all 17 digits survive
  c.planner.robot_radius_m = 0.41;
  c.floor.robot_height_m = 0.77;
  const std::string text = parameterFileText(c, "a comment\nof two lines");
  EXPECT_EQ(text.rfind("# a comment\n# of two lines\n", 0), 0u) << text;
  const std::string path = tempFile(text);
  ExplorerConfig back;
  ASSERT_NO_THROW(readParameterFile(path, back)) << text;
  std::remove(path.c_str());
  EXPECT_EQ(parameterFileText(back), parameterFileText(c));
  EXPECT_EQ(back.known_free_radius_m, c.known_free_radius_m);
  EXPECT_EQ(back.planner.robot_radius_m, 0.41);
  EXPECT_EQ(back.floor.robot_height_m, 0.77);
  EXPECT_EQ(back.planner.knowledge_model, "visibility");
  EXPECT_EQ(back.floor.min_obstacle_scans, 3);
}
