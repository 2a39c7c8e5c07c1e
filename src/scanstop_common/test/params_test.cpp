// closestName(): the "did you mean" hint of ParamReader::rejectUnknown() (the reader itself needs a
// ROS master: every node's bad-parameter rostest checks it, one unknown parameter each).
#include <gtest/gtest.h>

#include "scanstop_common/ros/params.h"

namespace scanstop {
namespace {

using ros_params::closestName;

TEST(ClosestName, AMissingUnitSuffixFindsTheNameWithIt) {
  // "k_r" is as far from "k0" as from "k_r_m": the longer common prefix wins.
  EXPECT_EQ(closestName("k_r", {"c0", "d_max_m", "k0", "k_r_m", "resolution_m"}), "k_r_m");
  EXPECT_EQ(closestName("d_max", {"d_max_m", "k_r_m"}), "d_max_m");
}

TEST(ClosestName, ATypoInANestedNameFindsIt) {
  EXPECT_EQ(closestName("motion/linear_sped", {"motion/angular_speed", "motion/linear_speed", "port"}),
            "motion/linear_speed");
  EXPECT_EQ(closestName("plannes", {"planes", "max_scans"}), "planes");
}

TEST(ClosestName, NothingCloseGivesNoHint) {
  EXPECT_EQ(closestName("completely_different", {"planes", "max_scans"}), "");
  EXPECT_EQ(closestName("xyz", {"planes"}), "");
  EXPECT_EQ(closestName("planes", {}), "");
}

}  // namespace
}  // namespace scanstop
