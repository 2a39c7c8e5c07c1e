#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace {

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, RangeErrorNamesParameterValueAndRange) {
  EXPECT_NO_THROW(requireInRange("c_max", 0.1, 0.0, 1.0, "m"));
  const std::string m = messageOf([] { requireInRange("c_max", 2.5, 0.0, 1.0, "m"); });
  EXPECT_NE(m.find("c_max"), std::string::npos) << m;
  EXPECT_NE(m.find("2.5"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 1 m]"), std::string::npos) << m;
  EXPECT_THROW(requireInRange("x", std::nan(""), 0.0, 1.0), ConfigError);
}

TEST(Config, PositiveAndNonNegative) {
  EXPECT_NO_THROW(requirePositive("r", 0.2));
  EXPECT_THROW(requirePositive("r", 0.0), ConfigError);
  EXPECT_THROW(requirePositive("r", INFINITY), ConfigError);
  EXPECT_NO_THROW(requireNonNegative("r", 0.0));
  EXPECT_THROW(requireNonNegative("r", -1e-9), ConfigError);
}

TEST(Config, OneOf) {
  EXPECT_NO_THROW(requireOneOf("planes", 400, {50, 100, 200, 400}));
  const std::string m = messageOf([] { requireOneOf("planes", 123, {50, 100, 200, 400}); });
  EXPECT_NE(m.find("planes"), std::string::npos);
  EXPECT_NE(m.find("50, 100, 200, 400"), std::string::npos) << m;
  EXPECT_NO_THROW(requireOneOf("mode", std::string("3dof"), {"3dof", "6dof"}));
  EXPECT_THROW(requireOneOf("mode", std::string("2dof"), {"3dof", "6dof"}), ConfigError);
}

}  // namespace
}  // namespace scanstop
