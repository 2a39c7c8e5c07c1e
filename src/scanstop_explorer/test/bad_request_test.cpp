// planRequestProblem: every bad explorer/plan_next request is named before anything is applied.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_explorer/explorer_ros.h"

using namespace scanstop;
using namespace scanstop::explorer;

namespace {

scanstop_msgs::PlanNext::Request goodRequest() {
  scanstop_msgs::PlanNext::Request req;
  req.map_pose = ros_conv::toPoseStamped(Pose2D(1.0, 2.0, 0.5), "map", ros::Time(1.0));
  geometry_msgs::Point u;
  u.x = 3.0;
  u.y = -1.0;
  req.unreachable.push_back(u);
  return req;
}

std::string problem(const scanstop_msgs::PlanNext::Request& req) { return planRequestProblem(req, NodeConfig()); }

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

TEST(PlanRequestProblem, AcceptsAGoodRequestAndAnEmptyFrame) {
  EXPECT_EQ(problem(goodRequest()), "");
  auto req = goodRequest();
  req.map_pose.header.frame_id = "";
  EXPECT_EQ(problem(req), "");
}

TEST(PlanRequestProblem, WrongFrame) {
  auto req = goodRequest();
  req.map_pose.header.frame_id = "odom";
  EXPECT_TRUE(has(problem(req), "map_pose is in frame 'odom', expected 'map'")) << problem(req);
}

TEST(PlanRequestProblem, NonFinitePose) {
  auto req = goodRequest();
  req.map_pose.pose.position.y = kNaN;
  EXPECT_TRUE(has(problem(req), "map_pose.position")) << problem(req);
  req = goodRequest();
  req.map_pose.pose.position.z = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(has(problem(req), "not finite")) << problem(req);
  req = goodRequest();
  req.map_pose.pose.orientation.z = kNaN;
  EXPECT_TRUE(has(problem(req), "map_pose.orientation")) << problem(req);
}

TEST(PlanRequestProblem, BadGoalOnlyWhenAsked) {
  auto req = goodRequest();
  req.goal.x = kNaN;
  EXPECT_EQ(problem(req), "");  // to_goal false: the goal is not used
  req.to_goal = true;
  EXPECT_TRUE(has(problem(req), "goal (nan, 0) is not finite")) << problem(req);
  req.goal.x = 1e9;
  EXPECT_TRUE(has(problem(req), "beyond max_coordinate_m")) << problem(req);
  req.goal.x = 2.0;
  EXPECT_EQ(problem(req), "");
}

TEST(PlanRequestProblem, NonUnitQuaternion) {
  auto req = goodRequest();
  req.map_pose.pose.orientation.w = 3.0;
  EXPECT_TRUE(has(problem(req), "not a unit quaternion")) << problem(req);
  req.map_pose.pose.orientation = geometry_msgs::Quaternion();
  EXPECT_TRUE(has(problem(req), "norm 0")) << problem(req);
}

TEST(PlanRequestProblem, AbsurdPosition) {
  auto req = goodRequest();
  req.map_pose.pose.position.x = 5e4;
  EXPECT_TRUE(has(problem(req), "beyond max_coordinate_m 1000 m")) << problem(req);
}

TEST(PlanRequestProblem, BadUnreachablePoints) {
  auto req = goodRequest();
  req.unreachable.push_back(req.unreachable[0]);
  req.unreachable[1].x = kNaN;
  EXPECT_TRUE(has(problem(req), "unreachable[1]")) << problem(req);
  EXPECT_TRUE(has(problem(req), "not finite")) << problem(req);
  req.unreachable[1].x = -2e6;
  EXPECT_TRUE(has(problem(req), "unreachable[1] (-2e+06, -1) is beyond max_coordinate_m")) << problem(req);
  req = goodRequest();
  req.unreachable.resize(10001);
  EXPECT_TRUE(has(problem(req), "more than max_unreachable 10000")) << problem(req);
}
