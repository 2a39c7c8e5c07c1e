#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <limits>
#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/robot_body.h"

#ifndef SCANSTOP_CONFIG_DIR
#error "SCANSTOP_CONFIG_DIR (the workspace's config/) must be defined"
#endif

namespace scanstop {
namespace {

// The one description is config/robot_body.yaml; the struct's defaults (used by a node started
// without it, e.g. in a unit test) must be the same numbers.
TEST(RobotBody, DefaultsAreTheNumbersOfConfigRobotBodyYaml) {
  const YAML::Node y = YAML::LoadFile(std::string(SCANSTOP_CONFIG_DIR) + "/robot_body.yaml")["robot_body"];
  ASSERT_TRUE(y.IsMap());
  const RobotBody d;
  EXPECT_DOUBLE_EQ(y["radius"].as<double>(), d.radius_m);
  EXPECT_DOUBLE_EQ(y["height"].as<double>(), d.height_m);
  EXPECT_DOUBLE_EQ(y["length"].as<double>(), d.length_m);
  EXPECT_DOUBLE_EQ(y["width"].as<double>(), d.width_m);
  EXPECT_DOUBLE_EQ(y["body_height"].as<double>(), d.body_height_m);
  EXPECT_DOUBLE_EQ(y["mast_x"].as<double>(), d.mast_x_m);
  EXPECT_EQ(y.size(), 6u) << "a new field in robot_body.yaml needs its RobotBody member and this test";
  EXPECT_NO_THROW(d.validate());
}

TEST(RobotBody, BadValuesNameTheParameter) {
  RobotBody b;
  b.radius_m = 0.0;
  try {
    b.validate("/robot_body/");
    FAIL() << "radius 0 accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/robot_body/radius"), std::string::npos) << e.what();
  }
  b = RobotBody();
  b.body_height_m = b.height_m + 0.1;  // the box cannot stand above the whole body
  EXPECT_THROW(b.validate(), ConfigError);
  b = RobotBody();
  b.height_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(b.validate(), ConfigError);
}

}  // namespace
}  // namespace scanstop
