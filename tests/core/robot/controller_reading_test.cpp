#include "robot/controller_reading.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pnp::robot {
namespace {

ControllerReading whole() {
  const Eigen::Quaterniond down(0, 1, 0, 0);
  ControllerReading r;
  r.frame_id = "panda_link0";
  r.measured_base = {{0.45, 0.0, 0.2}, down};
  r.commanded_base = {{0.45, 0.0, 0.2}, down};
  r.gripper_width_m = 0.04;
  r.object_base = geometry::Pose{{0.5, 0.1, 0.025}, Eigen::Quaterniond::Identity()};
  return r;
}

std::string error_of(const ControllerReading& r) {
  return reading_error(r, "panda_link0", 1e-3).value_or("none");
}

TEST(ControllerReading, AWholeReadingPasses) {
  EXPECT_EQ(error_of(whole()), "none");
}

TEST(ControllerReading, EachBrokenPartIsNamed) {
  ControllerReading r = whole();
  r.frame_id = "world";
  EXPECT_EQ(error_of(r), "frame_id: expected \"panda_link0\", got \"world\"");
  r = whole();
  r.commanded_base.position_m.y() = std::nan("");
  EXPECT_EQ(error_of(r).rfind("commanded.position: expected finite coordinates", 0), 0u);
  r = whole();
  r.measured_base.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_EQ(
      error_of(r),
      "measured.orientation: expected a unit quaternion (norm within 0.001 of 1), got norm 0");
  r = whole();
  r.gripper_width_m = INFINITY;
  EXPECT_EQ(error_of(r).rfind("gripper_width_m", 0), 0u);
  r = whole();
  r.object_base.reset();
  EXPECT_EQ(error_of(r).rfind("object: the controller reports no perception", 0), 0u);
  r = whole();
  r.object_base->orientation = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_EQ(error_of(r).rfind("object.pose.orientation", 0), 0u);
}

}  // namespace
}  // namespace pnp::robot
