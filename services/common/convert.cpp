#include "services/common/convert.h"

#include <cmath>

#include "common/error.h"

namespace pnp::services {
namespace {

[[noreturn]] void bad_enum(std::string_view field, std::string_view expected, int got) {
  throw_invalid_argument(field, expected, std::to_string(got) + (got == 0 ? " (unspecified)" : ""));
}

void require_finite(double v, std::string_view field) {
  if (!std::isfinite(v)) throw_invalid_argument(field, "a finite number", std::to_string(v));
}

}  // namespace

sim::Robot from_proto(common::v1::Robot robot, std::string_view field) {
  switch (robot) {
    case common::v1::ROBOT_FETCH:
      return sim::Robot::kFetch;
    case common::v1::ROBOT_PANDA:
      return sim::Robot::kPanda;
    default:
      bad_enum(field, "ROBOT_FETCH or ROBOT_PANDA", robot);
  }
}

sim::ObjectShape from_proto(common::v1::ObjectShape object, std::string_view field) {
  switch (object) {
    case common::v1::OBJECT_SHAPE_BLOCK:
      return sim::ObjectShape::kBlock;
    case common::v1::OBJECT_SHAPE_SMALL_BLOCK:
      return sim::ObjectShape::kSmallBlock;
    case common::v1::OBJECT_SHAPE_CYLINDER:
      return sim::ObjectShape::kCylinder;
    default:
      bad_enum(field, "OBJECT_SHAPE_BLOCK, OBJECT_SHAPE_SMALL_BLOCK or OBJECT_SHAPE_CYLINDER",
               object);
  }
}

sim::WorldProfile from_proto(common::v1::World world, std::string_view field) {
  switch (world) {
    case common::v1::WORLD_UNSPECIFIED:
      return sim::kDefaultWorldProfile;
    case common::v1::WORLD_PAPER:
      return sim::WorldProfile::kPaper;
    case common::v1::WORLD_GYM:
      return sim::WorldProfile::kGym;
    default:
      throw_invalid_argument(field, "WORLD_PAPER or WORLD_GYM (unset: gym)", std::to_string(world));
  }
}

sim::Actuation from_proto(common::v1::Actuation actuation, sim::Robot robot,
                          std::string_view field) {
  sim::Actuation out = sim::default_actuation(robot);
  switch (actuation) {
    case common::v1::ACTUATION_UNSPECIFIED:
      break;
    case common::v1::ACTUATION_MOCAP:
      out = sim::Actuation::kMocap;
      break;
    case common::v1::ACTUATION_ARM:
      out = sim::Actuation::kArm;
      break;
    default:
      throw_invalid_argument(field, "ACTUATION_MOCAP or ACTUATION_ARM (unset: the robot's default)",
                             std::to_string(actuation));
  }
  sim::require_supported(robot, out, field);
  return out;
}

common::v1::Actuation to_proto(sim::Actuation actuation) {
  return actuation == sim::Actuation::kArm ? common::v1::ACTUATION_ARM
                                           : common::v1::ACTUATION_MOCAP;
}

common::v1::World to_proto(sim::WorldProfile world) {
  return world == sim::WorldProfile::kGym ? common::v1::WORLD_GYM : common::v1::WORLD_PAPER;
}

common::v1::Robot to_proto(sim::Robot robot) {
  return robot == sim::Robot::kFetch ? common::v1::ROBOT_FETCH : common::v1::ROBOT_PANDA;
}

common::v1::ObjectShape to_proto(sim::ObjectShape object) {
  switch (object) {
    case sim::ObjectShape::kBlock:
      return common::v1::OBJECT_SHAPE_BLOCK;
    case sim::ObjectShape::kSmallBlock:
      return common::v1::OBJECT_SHAPE_SMALL_BLOCK;
    case sim::ObjectShape::kCylinder:
      return common::v1::OBJECT_SHAPE_CYLINDER;
  }
  return common::v1::OBJECT_SHAPE_UNSPECIFIED;
}

common::v1::Subtask to_proto(sim::Subtask subtask) {
  switch (subtask) {
    case sim::Subtask::kApproach:
      return common::v1::SUBTASK_APPROACH;
    case sim::Subtask::kManipulate:
      return common::v1::SUBTASK_MANIPULATE;
    case sim::Subtask::kRetract:
      return common::v1::SUBTASK_RETRACT;
  }
  return common::v1::SUBTASK_UNSPECIFIED;
}

int subtask_index(common::v1::Subtask subtask) {
  for (const sim::Subtask s : sim::kAllSubtasks)
    if (to_proto(s) == subtask) return static_cast<int>(s);
  return -1;
}

std::string role_name(common::v1::Role role, std::string_view field) {
  switch (role) {
    case common::v1::ROLE_APPROACH:
      return "approach";
    case common::v1::ROLE_MANIPULATE:
      return "manipulate";
    case common::v1::ROLE_RETRACT:
      return "retract";
    case common::v1::ROLE_HLC:
      return "hlc";
    case common::v1::ROLE_E2E:
      return "e2e";
    default:
      bad_enum(field, "one of ROLE_APPROACH, ROLE_MANIPULATE, ROLE_RETRACT, ROLE_HLC, ROLE_E2E",
               role);
  }
}

common::v1::Role role_from_name(std::string_view name) {
  if (name == "approach") return common::v1::ROLE_APPROACH;
  if (name == "manipulate") return common::v1::ROLE_MANIPULATE;
  if (name == "retract") return common::v1::ROLE_RETRACT;
  if (name == "hlc") return common::v1::ROLE_HLC;
  if (name == "e2e") return common::v1::ROLE_E2E;
  return common::v1::ROLE_UNSPECIFIED;
}

sim::Observation from_proto(const common::v1::Observation& o, std::string_view field) {
  const std::string values = std::string(field) + ".values";
  if (o.values_size() != sim::kObservationSize) {
    throw_invalid_argument(values, std::to_string(sim::kObservationSize) + " values",
                           std::to_string(o.values_size()));
  }
  sim::Observation out;
  for (int k = 0; k < sim::kObservationSize; ++k) {
    require_finite(o.values(k), values + "[" + std::to_string(k) + "]");
    out(k) = o.values(k);
  }
  return out;
}

sim::Goal from_proto(const common::v1::Vector3& v, std::string_view field) {
  const std::string f(field);
  require_finite(v.x_m(), f + ".x_m");
  require_finite(v.y_m(), f + ".y_m");
  require_finite(v.z_m(), f + ".z_m");
  return {v.x_m(), v.y_m(), v.z_m()};
}

void to_proto(const sim::Observation& o, common::v1::Observation& out) {
  out.clear_values();
  for (int k = 0; k < sim::kObservationSize; ++k) out.add_values(o(k));
}

void to_proto(const Eigen::Vector3d& v, common::v1::Vector3& out) {
  out.set_x_m(v.x());
  out.set_y_m(v.y());
  out.set_z_m(v.z());
}

void to_proto(const sim::Action& a, common::v1::Action& out) {
  out.set_dx(a(0));
  out.set_dy(a(1));
  out.set_dz(a(2));
  out.set_gripper(a(3));
}

void to_proto(const WallBreakdown& wall, common::v1::WallBreakdown& out) {
  out.set_rollout_s(wall.rollout_s);
  out.set_update_s(wall.update_s);
  out.set_eval_s(wall.eval_s);
  out.set_report_s(wall.report_s);
  out.set_other_s(wall.other_s);
  out.set_total_s(wall.total_s);
}

WallBreakdown from_proto(const common::v1::WallBreakdown& wall) {
  WallBreakdown out;
  out.rollout_s = wall.rollout_s();
  out.update_s = wall.update_s();
  out.eval_s = wall.eval_s();
  out.report_s = wall.report_s();
  out.other_s = wall.other_s();
  out.total_s = out.phases_sum();
  return out;
}

}  // namespace pnp::services
