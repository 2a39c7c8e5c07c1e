#pragma once
/// Checks of slam/register_scan requests at the message level, before any conversion: each returns
/// "" when the part is usable, else what is wrong (for the response's message). scanProblem() and
/// IcpSlam::odomProblem() (icp_slam.h) check the converted scan and pose.

#include <geometry_msgs/Pose.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>

namespace scanstop {
namespace slam {

/// The layout of a scan cloud: x, y, z fields present once each as one float32 (a "range" field,
/// when present, too), inside point_step and not overlapping; little-endian; width x height points
/// (at least one, at most max_points); row_step >= width x point_step; data holding exactly
/// row_step x height bytes.
std::string cloudLayoutProblem(const sensor_msgs::PointCloud2& msg, size_t max_points);

/// A pose message: finite position and orientation, and a unit quaternion (|q| within
/// quaternion_tolerance of 1: a non-normalized one is a bug upstream, not something to guess at).
/// `what` names the pose in the message, e.g. "odom_pose".
std::string poseProblem(const geometry_msgs::Pose& pose, const std::string& what, double quaternion_tolerance = 1e-3);

/// A frame id: "" when it equals `expected` (or is empty and empty_ok), else the mismatch.
std::string frameProblem(const std::string& frame_id, const std::string& expected, const std::string& what,
                         bool empty_ok = true);

}  // namespace slam
}  // namespace scanstop
