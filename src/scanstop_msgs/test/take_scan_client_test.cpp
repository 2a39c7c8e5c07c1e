// rostest: a C++ client calls TakeScan over ROS and checks that the organized cloud's size and its
// NaN points survive the trip.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <scanstop_msgs/TakeScan.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>

TEST(TakeScanContract, OrganizedCloudWithNaNSurvivesTheServiceCall) {
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::TakeScan>("scanner/take_scan");
  ASSERT_TRUE(client.waitForExistence(ros::Duration(20.0))) << "scanner/take_scan never appeared";
  scanstop_msgs::TakeScan srv;
  srv.request.planes = 100;
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  const sensor_msgs::PointCloud2& c = srv.response.cloud;
  EXPECT_EQ(c.height, 100u);
  EXPECT_EQ(c.width, 682u);
  EXPECT_FALSE(c.is_dense);
  EXPECT_EQ(c.header.frame_id, "base_link");
  ASSERT_EQ(c.data.size(), static_cast<size_t>(c.row_step) * c.height);
  sensor_msgs::PointCloud2ConstIterator<float> x(c, "x"), r(c, "range");
  sensor_msgs::PointCloud2ConstIterator<uint16_t> plane(c, "plane"), beam(c, "beam");
  size_t nan_count = 0, checked = 0;
  for (; x != x.end(); ++x, ++r, ++plane, ++beam, ++checked) {
    const bool expect_nan = (*plane + *beam) % 7 == 0;
    EXPECT_EQ(std::isnan(x[0]), expect_nan);
    EXPECT_EQ(std::isnan(*r), expect_nan);
    if (!expect_nan) EXPECT_FLOAT_EQ(x[0], 0.001f * *beam);
    nan_count += std::isnan(x[2]) ? 1 : 0;
  }
  EXPECT_EQ(checked, 100u * 682u);
  size_t expected_nan = 0;
  for (uint32_t p = 0; p < 100; ++p)
    for (uint32_t b = 0; b < 682; ++b) expected_nan += (p + b) % 7 == 0 ? 1 : 0;
  EXPECT_EQ(nan_count, expected_nan);
  EXPECT_EQ(srv.response.counts.raw_points, 68200u);
}

TEST(TakeScanContract, BadPlaneCountIsRefusedWithAReason) {
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::TakeScan>("scanner/take_scan");
  ASSERT_TRUE(client.waitForExistence(ros::Duration(20.0)));
  scanstop_msgs::TakeScan srv;
  srv.request.planes = 123;
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("123"), std::string::npos);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "take_scan_client_test");
  return RUN_ALL_TESTS();
}
