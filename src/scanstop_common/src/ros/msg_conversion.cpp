#include "scanstop_common/ros/msg_conversion.h"

#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace scanstop {
namespace ros_conv {

sensor_msgs::PointCloud2 toMsg(const PointCloud& cloud, const std::string& frame_id, const ros::Time& stamp) {
  const std::string problem = cloud.layoutProblem();
  if (!problem.empty()) throw std::invalid_argument("cannot convert cloud: " + problem);
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  sensor_msgs::PointCloud2Modifier modifier(msg);
  const bool organized = cloud.isOrganized();
  using PF = sensor_msgs::PointField;
  if (cloud.hasRanges() && organized) {
    modifier.setPointCloud2Fields(6, "x", 1, PF::FLOAT32, "y", 1, PF::FLOAT32, "z", 1, PF::FLOAT32, "range", 1,
                                  PF::FLOAT32, "plane", 1, PF::UINT16, "beam", 1, PF::UINT16);
  } else if (cloud.hasRanges()) {
    modifier.setPointCloud2Fields(4, "x", 1, PF::FLOAT32, "y", 1, PF::FLOAT32, "z", 1, PF::FLOAT32, "range", 1,
                                  PF::FLOAT32);
  } else if (organized) {
    modifier.setPointCloud2Fields(5, "x", 1, PF::FLOAT32, "y", 1, PF::FLOAT32, "z", 1, PF::FLOAT32, "plane", 1,
                                  PF::UINT16, "beam", 1, PF::UINT16);
  } else {
    modifier.setPointCloud2Fields(3, "x", 1, PF::FLOAT32, "y", 1, PF::FLOAT32, "z", 1, PF::FLOAT32);
  }
  modifier.resize(cloud.size());
  msg.width = cloud.width;
  msg.height = cloud.height;
  msg.row_step = msg.width * msg.point_step;
  msg.is_dense = cloud.countFinite() == cloud.size();
  if (cloud.empty()) return msg;
  sensor_msgs::PointCloud2Iterator<float> x(msg, "x");
  for (size_t i = 0; i < cloud.size(); ++i, ++x) {
    x[0] = cloud.points[i].x();
    x[1] = cloud.points[i].y();
    x[2] = cloud.points[i].z();
  }
  if (cloud.hasRanges()) {
    sensor_msgs::PointCloud2Iterator<float> r(msg, "range");
    for (size_t i = 0; i < cloud.size(); ++i, ++r) *r = cloud.ranges[i];
  }
  if (organized) {
    sensor_msgs::PointCloud2Iterator<uint16_t> plane(msg, "plane");
    sensor_msgs::PointCloud2Iterator<uint16_t> beam(msg, "beam");
    for (size_t i = 0; i < cloud.size(); ++i, ++plane, ++beam) {
      *plane = static_cast<uint16_t>(i / cloud.width);
      *beam = static_cast<uint16_t>(i % cloud.width);
    }
  }
  return msg;
}

namespace {

const sensor_msgs::PointField* findField(const sensor_msgs::PointCloud2& msg, const std::string& name) {
  for (const auto& f : msg.fields)
    if (f.name == name) return &f;
  return nullptr;
}

float readValue(const uint8_t* p, uint8_t datatype) {
  if (datatype == sensor_msgs::PointField::FLOAT64) {
    double d;
    std::memcpy(&d, p, 8);
    return static_cast<float>(d);
  }
  float f;
  std::memcpy(&f, p, 4);
  return f;
}

void checkFloatField(const sensor_msgs::PointCloud2& msg, const sensor_msgs::PointField& f) {
  if (f.datatype != sensor_msgs::PointField::FLOAT32 && f.datatype != sensor_msgs::PointField::FLOAT64)
    throw std::invalid_argument("PointCloud2 field '" + f.name + "' is not float32 or float64");
  const uint32_t size = f.datatype == sensor_msgs::PointField::FLOAT64 ? 8 : 4;
  if (f.offset + size > msg.point_step)
    throw std::invalid_argument("PointCloud2 field '" + f.name + "' lies outside point_step");
}

}  // namespace

PointCloud fromMsg(const sensor_msgs::PointCloud2& msg) {
  const sensor_msgs::PointField* fx = findField(msg, "x");
  const sensor_msgs::PointField* fy = findField(msg, "y");
  const sensor_msgs::PointField* fz = findField(msg, "z");
  if (!fx || !fy || !fz) throw std::invalid_argument("PointCloud2 has no x, y and z fields");
  checkFloatField(msg, *fx);
  checkFloatField(msg, *fy);
  checkFloatField(msg, *fz);
  const sensor_msgs::PointField* fr = findField(msg, "range");
  if (fr) checkFloatField(msg, *fr);
  if (msg.is_bigendian) throw std::invalid_argument("big-endian PointCloud2 is not supported");
  const size_t n = static_cast<size_t>(msg.width) * msg.height;
  if (msg.row_step < static_cast<size_t>(msg.width) * msg.point_step)
    throw std::invalid_argument("PointCloud2 row_step " + std::to_string(msg.row_step) +
                                " is smaller than width x point_step");
  if (msg.data.size() < static_cast<size_t>(msg.row_step) * msg.height)
    throw std::invalid_argument("PointCloud2 data has " + std::to_string(msg.data.size()) +
                                " bytes, the layout needs " +
                                std::to_string(static_cast<size_t>(msg.row_step) * msg.height));
  PointCloud cloud;
  cloud.points.resize(n);
  if (fr) cloud.ranges.resize(n);
  for (uint32_t row = 0; row < msg.height; ++row) {
    for (uint32_t col = 0; col < msg.width; ++col) {
      const uint8_t* p =
          msg.data.data() + static_cast<size_t>(row) * msg.row_step + static_cast<size_t>(col) * msg.point_step;
      const size_t i = static_cast<size_t>(row) * msg.width + col;
      cloud.points[i] =
          Eigen::Vector3f(readValue(p + fx->offset, fx->datatype), readValue(p + fy->offset, fy->datatype),
                          readValue(p + fz->offset, fz->datatype));
      if (fr) cloud.ranges[i] = readValue(p + fr->offset, fr->datatype);
    }
  }
  cloud.width = msg.width;
  cloud.height = msg.height;
  return cloud;
}

geometry_msgs::Pose toPoseMsg(const Pose2D& pose) {
  geometry_msgs::Pose msg;
  msg.position.x = pose.x;
  msg.position.y = pose.y;
  msg.position.z = 0.0;
  msg.orientation.w = std::cos(pose.yaw / 2.0);
  msg.orientation.z = std::sin(pose.yaw / 2.0);
  return msg;
}

Pose2D fromPoseMsg(const geometry_msgs::Pose& pose) {
  const auto& q = pose.orientation;
  Eigen::Quaterniond quat(q.w, q.x, q.y, q.z);
  const double norm = quat.norm();
  if (!std::isfinite(norm) || norm < 1e-6) throw std::invalid_argument("pose orientation is not a valid quaternion");
  if (!std::isfinite(pose.position.x) || !std::isfinite(pose.position.y))
    throw std::invalid_argument("pose position is not finite");
  quat.normalize();
  return Pose2D(pose.position.x, pose.position.y, yawOf(quat.toRotationMatrix()));
}

geometry_msgs::PoseStamped toPoseStamped(const Pose2D& pose, const std::string& frame_id, const ros::Time& stamp) {
  geometry_msgs::PoseStamped msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.pose = toPoseMsg(pose);
  return msg;
}

geometry_msgs::TransformStamped toTransformMsg(const Pose2D& T_parent_child, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp) {
  return toTransformMsg(T_parent_child.toIsometry3d(), parent, child, stamp);
}

geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& T_parent_child, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped msg;
  msg.header.frame_id = parent;
  msg.header.stamp = stamp;
  msg.child_frame_id = child;
  msg.transform.translation.x = T_parent_child.translation().x();
  msg.transform.translation.y = T_parent_child.translation().y();
  msg.transform.translation.z = T_parent_child.translation().z();
  const Eigen::Quaterniond q(T_parent_child.linear());
  msg.transform.rotation.x = q.x();
  msg.transform.rotation.y = q.y();
  msg.transform.rotation.z = q.z();
  msg.transform.rotation.w = q.w();
  return msg;
}

}  // namespace ros_conv
}  // namespace scanstop
