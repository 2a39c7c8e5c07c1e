#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "scanstop_common/ros/msg_conversion.h"

namespace scanstop {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(MsgConversion, OrganizedCloudRoundTripKeepsLayoutNaNAndIndices) {
  PointCloud c;
  c.width = 5;
  c.height = 2;
  for (int i = 0; i < 10; ++i) {
    c.points.emplace_back(i, -i, 0.5f * i);
    c.ranges.push_back(static_cast<float>(i));
  }
  c.points[3] = Eigen::Vector3f::Constant(kNaN);
  c.ranges[3] = kNaN;
  const sensor_msgs::PointCloud2 msg = ros_conv::toMsg(c, "base_link", ros::Time(12.5));
  EXPECT_EQ(msg.width, 5u);
  EXPECT_EQ(msg.height, 2u);
  EXPECT_FALSE(msg.is_dense);
  EXPECT_EQ(msg.header.frame_id, "base_link");
  ASSERT_EQ(msg.fields.size(), 6u);
  EXPECT_EQ(msg.fields[4].name, "plane");
  EXPECT_EQ(msg.fields[5].name, "beam");
  // plane/beam of point 7 = row 1, column 2
  uint16_t plane = 0, beam = 0;
  std::memcpy(&plane, &msg.data[7 * msg.point_step + msg.fields[4].offset], 2);
  std::memcpy(&beam, &msg.data[7 * msg.point_step + msg.fields[5].offset], 2);
  EXPECT_EQ(plane, 1);
  EXPECT_EQ(beam, 2);

  const PointCloud back = ros_conv::fromMsg(msg);
  EXPECT_EQ(back.width, 5u);
  EXPECT_EQ(back.height, 2u);
  ASSERT_EQ(back.size(), 10u);
  EXPECT_FALSE(back.points[3].allFinite());
  EXPECT_TRUE(std::isnan(back.ranges[3]));
  EXPECT_TRUE(back.points[9].isApprox(c.points[9]));
  EXPECT_FLOAT_EQ(back.ranges[9], 9.0f);
}

TEST(MsgConversion, DenseUnorganizedCloud) {
  PointCloud c;
  c.push_back({1, 2, 3});
  const sensor_msgs::PointCloud2 msg = ros_conv::toMsg(c, "map", ros::Time(0));
  EXPECT_TRUE(msg.is_dense);
  EXPECT_EQ(msg.fields.size(), 3u);
  EXPECT_EQ(ros_conv::fromMsg(msg).points[0], Eigen::Vector3f(1, 2, 3));
}

TEST(MsgConversion, MalformedCloudsAreRejected) {
  sensor_msgs::PointCloud2 msg;
  EXPECT_THROW(ros_conv::fromMsg(msg), std::invalid_argument);  // no fields
  PointCloud c;
  c.push_back({1, 2, 3});
  c.push_back({4, 5, 6});
  msg = ros_conv::toMsg(c, "map", ros::Time(0));
  msg.data.resize(msg.data.size() - 1);
  EXPECT_THROW(ros_conv::fromMsg(msg), std::invalid_argument);  // data shorter than the layout
  msg = ros_conv::toMsg(c, "map", ros::Time(0));
  msg.fields[0].datatype = sensor_msgs::PointField::UINT8;
  EXPECT_THROW(ros_conv::fromMsg(msg), std::invalid_argument);
}

TEST(MsgConversion, PoseRoundTripAndTransform) {
  const Pose2D p(1.0, -2.0, 2.5);
  const Pose2D q = ros_conv::fromPoseMsg(ros_conv::toPoseMsg(p));
  EXPECT_NEAR(q.x, 1.0, 1e-12);
  EXPECT_NEAR(q.y, -2.0, 1e-12);
  EXPECT_NEAR(q.yaw, 2.5, 1e-12);
  const auto tf = ros_conv::toTransformMsg(p, "odom", "base_link", ros::Time(1));
  EXPECT_EQ(tf.header.frame_id, "odom");
  EXPECT_EQ(tf.child_frame_id, "base_link");
  EXPECT_NEAR(tf.transform.rotation.z, std::sin(1.25), 1e-12);
  geometry_msgs::Pose bad;
  bad.orientation.w = 0.0;
  EXPECT_THROW(ros_conv::fromPoseMsg(bad), std::invalid_argument);
}

}  // namespace
}  // namespace scanstop
