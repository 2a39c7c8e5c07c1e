#pragma once
/// Ending the roslaunch that started a node (issue #22 class 4): a node whose start-up fails the same
/// way on every respawn (a map_dir that is a regular file, a missing world) ends the launch at once
/// with its FATAL line instead of being respawned forever; a mission that ends normally ends the
/// launch calmly (SIGINT, as Ctrl-C) instead of as a required process that died.

#include <ros/node_handle.h>

#include <string>

namespace scanstop {

/// Whether this process was started by roslaunch (its parent's command line names it).
bool parentIsRoslaunch();

/// Sends SIGINT to the parent roslaunch; false (nothing sent) when the parent is not roslaunch.
bool interruptParentLaunch();

/// After a start-up error (its FATAL already logged): when the node's private parameter
/// `end_launch_on_setup_error` is true and roslaunch started it, logs "<node>: ending the launch: every
/// restart would fail the same way", waits 3 s (roslaunch interrupted while it still starts the other
/// nodes hangs ~20 s in its shutdown, measured) and interrupts the launch. Returns whether it did.
bool endLaunchOnSetupError(const ros::NodeHandle& pnh, const std::string& node);

}  // namespace scanstop
