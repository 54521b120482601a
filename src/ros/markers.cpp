#include "spinning_top/ros/markers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "spinning_top/ros/conversions.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

std_msgs::ColorRGBA color(float r, float g, float b, float a = 1.0f) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

/// The body drawn by rviz: a solid cone with its apex at the tip. With a rim (rim_radius b > 0)
/// it is the body the core knows (HYBRID.md, "fallen"): its base circle is the rim, radius b at
/// distance a = rim_distance from the tip along the axis, so a fallen top lies on the floor
/// where the core says its rim touches it. Without one (a needle to the core), the cone whose
/// centroid is at G (height H = 4h/3, since a cone's centroid lies 3/4 of the way from the apex), whose
/// inertia ratio C/A about G is the top's: for a cone C = 3/10 m R^2 and
/// A = 3/20 m R^2 + 3/80 m H^2, so C/A = rho gives R^2 = rho H^2 / (4 (2 - rho)).
/// A real top is denser at the rim, so this is the shape, not the mass distribution.
/// rho -> 2 (a flat disc) or h = 0 has no such cone: the radius is then capped at 2H, and
/// for h = 0 it is the radius of the uniform cylinder with the same m and C, sqrt(2C/m).
struct BodyShape {
  double height, radius;
};

BodyShape body_shape(const TopParameters& top) {
  if (top.rim_radius > 0.0) return {top.rim_distance, top.rim_radius};  // validated: a > 0 with b > 0
  const double height = 4.0 * top.tip_distance / 3.0;
  const double rho = top.inertia_axial / top.inertia_transverse;
  double radius = rho < 2.0 ? 0.5 * height * std::sqrt(rho / (2.0 - rho)) : 2.0 * height;
  radius = std::min(radius, 2.0 * height);
  if (!(radius > 0.0)) radius = std::sqrt(2.0 * top.inertia_axial / top.mass);
  return {std::max(height, 1e-3), radius};
}

double label_height(const BodyShape& shape) { return std::max(0.4 * shape.height, 0.005); }

}  // namespace

visualization_msgs::MarkerArray top_markers(const TopParameters& top, const Vector3& contact_point,
                                            const Vector3& force, const std::deque<Vector3>& trace_points,
                                            const MarkerFrames& frames, double force_scale, const ros::Time& stamp) {
  const BodyShape shape = body_shape(top);
  visualization_msgs::MarkerArray array;

  // The body: the cone from the tip (z = -h in the body frame) to its base, in coloured
  // sectors so that the spin is visible; frame-locked, so rviz moves it with the tf.
  visualization_msgs::Marker body;
  body.header.stamp = stamp;
  body.header.frame_id = frames.body;
  body.frame_locked = true;
  body.ns = "body";
  body.id = 0;
  body.type = visualization_msgs::Marker::TRIANGLE_LIST;
  body.action = visualization_msgs::Marker::ADD;
  body.pose.orientation.w = 1.0;
  body.scale.x = body.scale.y = body.scale.z = 1.0;
  body.color = color(1.0f, 1.0f, 1.0f);
  const int sectors = 48;
  const double base_z = shape.height - top.tip_distance;
  const Vector3 apex(0.0, 0.0, -top.tip_distance), centre(0.0, 0.0, base_z);
  auto rim = [&](int i) {
    const double angle = 2.0 * M_PI * i / sectors;
    return Vector3(shape.radius * std::cos(angle), shape.radius * std::sin(angle), base_z);
  };
  for (int i = 0; i < sectors; ++i) {
    const std_msgs::ColorRGBA c = (i / 4) % 2 == 0 ? color(0.9f, 0.35f, 0.1f, 0.7f) : color(0.95f, 0.85f, 0.6f, 0.7f);
    // Both windings of every triangle: rviz culls back faces.
    for (const Vector3& v : {apex, rim(i), rim(i + 1), apex, rim(i + 1), rim(i), centre, rim(i + 1), rim(i),
                             centre, rim(i), rim(i + 1)}) {
      body.points.push_back(to_point(v));
      body.colors.push_back(c);
    }
  }
  array.markers.push_back(body);
  // A short handle on top, as on a toy top.
  visualization_msgs::Marker handle = body;
  handle.id = 1;
  handle.type = visualization_msgs::Marker::CYLINDER;
  handle.points.clear();
  handle.colors.clear();
  handle.scale.x = handle.scale.y = 0.15 * shape.radius;
  handle.scale.z = 0.4 * shape.height;
  handle.pose.position.z = base_z + 0.5 * handle.scale.z;
  handle.color = color(0.3f, 0.3f, 0.35f);
  array.markers.push_back(handle);
  // The top's label: its body frame's name ("top", "slow/top", ...) above the handle, outside the
  // cone (the TF display's name sat at G, inside it). Capitals 0.4 body heights tall (11 mm for
  // the shipped top: about 14 px for the far top of two_tops.rviz's view, where the TF names
  // were 8 px), at least 5 mm so that a small top's label still reads.
  visualization_msgs::Marker label = handle;
  label.ns = "label";
  label.id = 0;
  label.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
  label.text = frames.body;
  label.scale.x = label.scale.y = 0.0;  // unused by text
  label.scale.z = label_height(shape);
  label.pose.position.z = base_z + handle.scale.z + label.scale.z;
  label.color = color(1.0f, 1.0f, 1.0f);
  array.markers.push_back(label);

  // The tip's trace on the floor (world frame, bounded).
  visualization_msgs::Marker trace;
  trace.header.stamp = stamp;
  trace.header.frame_id = frames.world;
  trace.ns = "trace";
  trace.id = 0;
  trace.type = visualization_msgs::Marker::LINE_STRIP;
  trace.action = visualization_msgs::Marker::ADD;
  trace.pose.orientation.w = 1.0;
  trace.scale.x = 0.0005;  // line width [m]
  trace.color = color(0.1f, 0.5f, 0.9f);
  for (const Vector3& p : trace_points) trace.points.push_back(to_point(p));
  trace.points.push_back(to_point(contact_point));
  if (trace.points.size() < 2) trace.points.push_back(trace.points.back());
  array.markers.push_back(trace);

  // The floor's force on the tip, from the tip (world frame, force_scale m/N); none in flight
  // or at rest (rviz would draw a zero-length arrow as a stray head).
  visualization_msgs::Marker arrow = trace;
  arrow.ns = "force";
  if (force == Vector3::Zero()) arrow.action = visualization_msgs::Marker::DELETE;
  arrow.type = visualization_msgs::Marker::ARROW;
  arrow.points.clear();
  arrow.points.push_back(to_point(contact_point));
  arrow.points.push_back(to_point(contact_point + force_scale * force));
  arrow.scale.x = 0.002;  // shaft diameter
  arrow.scale.y = 0.004;  // head diameter
  arrow.scale.z = 0.006;  // head length
  arrow.color = color(0.2f, 0.8f, 0.2f);
  array.markers.push_back(arrow);
  return array;
}

std::string top_urdf(const TopParameters& top, const std::string& link) {
  const BodyShape shape = body_shape(top);
  char buffer[512];
  std::string urdf = "<?xml version=\"1.0\"?>\n<robot name=\"spinning_top\">\n";
  urdf += "  <material name=\"rim\"><color rgba=\"0.9 0.35 0.1 1\"/></material>\n";
  urdf += "  <material name=\"handle\"><color rgba=\"0.3 0.3 0.35 1\"/></material>\n";
  urdf += "  <link name=\"" + link + "\">\n";
  std::snprintf(buffer, sizeof buffer,
                "    <inertial><origin xyz=\"0 0 0\"/><mass value=\"%.17g\"/>"
                "<inertia ixx=\"%.17g\" iyy=\"%.17g\" izz=\"%.17g\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n",
                top.mass, top.inertia_transverse, top.inertia_transverse, top.inertia_axial);
  urdf += buffer;
  // The cone from the tip (z = -h) to its base, as 8 cylinders of the mean radius of each slice.
  const int slices = 8;
  const double slice = shape.height / slices;
  for (int i = 0; i < slices; ++i) {
    std::snprintf(buffer, sizeof buffer,
                  "    <visual><origin xyz=\"0 0 %.9g\"/><geometry><cylinder radius=\"%.9g\" length=\"%.9g\"/>"
                  "</geometry><material name=\"rim\"/></visual>\n",
                  -top.tip_distance + (i + 0.5) * slice, shape.radius * (i + 0.5) / slices, slice);
    urdf += buffer;
  }
  const double base_z = shape.height - top.tip_distance;
  std::snprintf(buffer, sizeof buffer,
                "    <visual><origin xyz=\"0 0 %.9g\"/><geometry><cylinder radius=\"%.9g\" length=\"%.9g\"/>"
                "</geometry><material name=\"handle\"/></visual>\n",
                base_z + 0.2 * shape.height, 0.075 * shape.radius, 0.4 * shape.height);
  urdf += buffer;
  urdf += "  </link>\n</robot>\n";
  return urdf;
}

}  // namespace ros_front_end
}  // namespace spinning_top
