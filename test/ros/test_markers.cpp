// Issue 20, item 12: the label rviz shows for each top (the markers' "label" namespace): the
// body frame's name, above the body (the TF display's name sat at G, inside the cone), in text
// large enough to read in the shipped views. No master: top_markers() alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>

#include "spinning_top/ros/markers.hpp"

namespace {

using spinning_top::TopParameters;
using spinning_top::Vector3;
using spinning_top::ros_front_end::MarkerFrames;
using spinning_top::ros_front_end::top_markers;

const visualization_msgs::Marker* find(const visualization_msgs::MarkerArray& array, const std::string& ns, int id) {
  for (const auto& m : array.markers)
    if (m.ns == ns && m.id == id) return &m;
  return nullptr;
}

/// The highest point of the body and handle, along the body frame's z.
double body_top(const visualization_msgs::MarkerArray& array) {
  double top = -1e9;
  for (const auto& p : find(array, "body", 0)->points) top = std::max(top, p.z);
  const auto* handle = find(array, "body", 1);
  return std::max(top, handle->pose.position.z + 0.5 * handle->scale.z);
}

void expect_label_above(const TopParameters& top, const std::string& frame) {
  const auto array = top_markers(top, Vector3(0.0, 0.0, 0.0), Vector3(0.0, 0.0, 1.0), std::deque<Vector3>{},
                                 MarkerFrames{"world", frame}, 0.05, ros::Time(1.0));
  const auto* label = find(array, "label", 0);
  ASSERT_NE(label, nullptr);
  EXPECT_EQ(label->type, visualization_msgs::Marker::TEXT_VIEW_FACING);
  EXPECT_EQ(label->action, visualization_msgs::Marker::ADD);
  EXPECT_EQ(label->text, frame);
  EXPECT_EQ(label->header.frame_id, frame);
  EXPECT_TRUE(label->frame_locked);
  EXPECT_GT(label->color.a, 0.0f);
  // Legible: at least 5 mm high (the height of a capital, rviz's scale.z), 11 px at the two
  // tops' view (0.4 m, field of view 0.785 rad, about 700 px high) where the TF names were 8 px.
  EXPECT_GE(label->scale.z, 0.005);
  // Outside the body: the text's lower edge (half its height below the anchor) above the handle.
  EXPECT_GT(label->pose.position.z - 0.5 * label->scale.z, body_top(array)) << frame;
}

TEST(Markers, TheShippedTopsLabelIsAboveItsBodyAndLegible) {
  TopParameters top;  // the shipped scenes' top: m 0.1 kg, h 2 cm, rim a 2.67 cm, b 2.31 cm
  top.rim_distance = 0.0266666667;
  top.rim_radius = 0.0230940108;
  expect_label_above(top, "top");
  expect_label_above(top, "slow/top");
}

TEST(Markers, ANeedleAndASmallTopAreLabelledToo) {
  TopParameters needle;
  needle.rim_radius = needle.rim_distance = 0.0;
  expect_label_above(needle, "top");
  TopParameters small;
  small.tip_distance = 0.002;
  small.rim_distance = small.rim_radius = 0.0;
  expect_label_above(small, "r1/top");
}

}  // namespace
