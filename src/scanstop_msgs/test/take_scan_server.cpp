// Test fixture node: serves scanner/take_scan with a synthetic organized cloud whose NaN pattern
// the client can predict (point (plane, beam) is NaN when (plane + beam) % 7 == 0).
#include <ros/ros.h>
#include <scanstop_msgs/TakeScan.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <limits>

namespace {

bool takeScan(scanstop_msgs::TakeScan::Request& req, scanstop_msgs::TakeScan::Response& res) {
  if (req.planes != 50 && req.planes != 100 && req.planes != 200 && req.planes != 400) {
    res.success = false;
    res.message = "planes must be 50, 100, 200 or 400, got " + std::to_string(req.planes);
    return true;
  }
  const uint32_t beams = 682;
  sensor_msgs::PointCloud2& cloud = res.cloud;
  cloud.header.frame_id = "base_link";
  cloud.header.stamp = ros::Time::now();
  sensor_msgs::PointCloud2Modifier mod(cloud);
  using PF = sensor_msgs::PointField;
  mod.setPointCloud2Fields(6, "x", 1, PF::FLOAT32, "y", 1, PF::FLOAT32, "z", 1, PF::FLOAT32, "range", 1, PF::FLOAT32,
                           "plane", 1, PF::UINT16, "beam", 1, PF::UINT16);
  mod.resize(req.planes * beams);
  cloud.height = req.planes;
  cloud.width = beams;
  cloud.row_step = cloud.width * cloud.point_step;
  cloud.is_dense = false;
  sensor_msgs::PointCloud2Iterator<float> x(cloud, "x"), r(cloud, "range");
  sensor_msgs::PointCloud2Iterator<uint16_t> plane(cloud, "plane"), beam(cloud, "beam");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (uint32_t p = 0; p < req.planes; ++p) {
    for (uint32_t b = 0; b < beams; ++b, ++x, ++r, ++plane, ++beam) {
      const bool invalid = (p + b) % 7 == 0;
      x[0] = invalid ? nan : 0.001f * b;
      x[1] = invalid ? nan : 0.002f * p;
      x[2] = invalid ? nan : 1.0f;
      *r = invalid ? nan : std::sqrt(x[0] * x[0] + x[1] * x[1] + 1.0f);
      *plane = static_cast<uint16_t>(p);
      *beam = static_cast<uint16_t>(b);
    }
  }
  res.odom_pose.header.frame_id = "odom";
  res.odom_pose.pose.orientation.w = 1.0;
  res.counts.raw_points = req.planes * beams;
  res.success = true;
  res.duration_s = req.planes * 0.1;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "take_scan_server");
  ros::NodeHandle nh;
  ros::ServiceServer server = nh.advertiseService("scanner/take_scan", takeScan);
  ros::spin();
  return 0;
}
