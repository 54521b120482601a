// What rviz draws of a top: its body (a cone from the tip to the rim, or with the top's C/A
// without a rim), a handle, its label, the tip's trace and the floor's force as an arrow.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <deque>
#include <string>

#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace ros_front_end {

struct MarkerFrames {
  std::string world, body;
};

/// `contact_point` (the tip, in the air too) and `force` (horizontal x, y and R as z) in the
/// world frame; `trace` holds earlier tip positions (world). A zero force deletes the arrow.
/// Namespaces: body (the cone, id 0, and the handle, id 1, in the body frame), label (the body
/// frame's name as text above the handle, in the body frame), trace and force (world frame).
visualization_msgs::MarkerArray top_markers(const TopParameters& top, const Vector3& contact_point,
                                            const Vector3& force, const std::deque<Vector3>& trace,
                                            const MarkerFrames& frames, double force_scale, const ros::Time& stamp);

/// A URDF of the top (for rviz's RobotModel display, as `robot_description`): one link named
/// `link` (the body frame: origin at G, z along the axis) with the top's mass and inertia and
/// the marker's cone as stacked cylinders (URDF has no cone).
std::string top_urdf(const TopParameters& top, const std::string& link);

}  // namespace ros_front_end
}  // namespace spinning_top
