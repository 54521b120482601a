// The core's Eigen vectors as geometry_msgs (world frame, SI units).
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Vector3.h>

#include "spinning_top/kinematics.hpp"

namespace spinning_top {
namespace ros_front_end {

template <class Message>
Message to_message(const Vector3& v) {
  Message m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}

inline geometry_msgs::Point to_point(const Vector3& v) { return to_message<geometry_msgs::Point>(v); }
inline geometry_msgs::Vector3 to_vector(const Vector3& v) { return to_message<geometry_msgs::Vector3>(v); }

}  // namespace ros_front_end
}  // namespace spinning_top
