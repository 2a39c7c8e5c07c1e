#pragma once
/// Conversions between the ROS-free core types and ROS messages; the only place that knows both.

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"

namespace scanstop {
namespace ros_conv {

/// Cloud -> PointCloud2 with float32 x y z (+ "range" when the cloud has ranges, + "plane" and
/// "beam" uint16 row/column indices when it is organized). Keeps width x height and NaN points;
/// is_dense is true only when every point is finite.
sensor_msgs::PointCloud2 toMsg(const PointCloud& cloud, const std::string& frame_id, const ros::Time& stamp);

/// PointCloud2 -> cloud. Needs float32 x y z fields (float64 accepted too); reads "range" when
/// present. Throws std::invalid_argument describing a malformed layout (sizes, missing fields).
PointCloud fromMsg(const sensor_msgs::PointCloud2& msg);

geometry_msgs::Pose toPoseMsg(const Pose2D& pose);
/// Planar projection of a pose message; throws std::invalid_argument on a non-finite or
/// non-normalizable quaternion.
Pose2D fromPoseMsg(const geometry_msgs::Pose& pose);
geometry_msgs::PoseStamped toPoseStamped(const Pose2D& pose, const std::string& frame_id, const ros::Time& stamp);

/// T_parent_child as a tf2 transform message.
geometry_msgs::TransformStamped toTransformMsg(const Pose2D& T_parent_child, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp);
geometry_msgs::TransformStamped toTransformMsg(const Eigen::Isometry3d& T_parent_child, const std::string& parent,
                                               const std::string& child, const ros::Time& stamp);

}  // namespace ros_conv
}  // namespace scanstop
