#include "clients/robot_gateway/target_record.h"

#include <nlohmann/json.hpp>

#include "common/error.h"

namespace pnp::gateway {

TargetRecord::TargetRecord(const std::string& path) : path_(path), file_(path, std::ios::trunc) {
  if (!file_) throw Error(ErrorCode::kUnavailable, "--record: could not open " + path);
}

void TargetRecord::add(std::uint64_t seed, int step, const robot::PoseTarget& target) {
  const auto& p = target.pose.position_m;
  const auto& q = target.pose.orientation;
  const nlohmann::json line{{"seed", seed},
                            {"step", step},
                            {"position_base_m", {p.x(), p.y(), p.z()}},
                            {"orientation_base_wxyz", {q.w(), q.x(), q.y(), q.z()}},
                            {"gripper_width_m", target.gripper_width_m}};
  file_ << line.dump() << '\n';
  if (!file_.flush()) throw Error(ErrorCode::kUnavailable, "--record: could not write " + path_);
}

}  // namespace pnp::gateway
