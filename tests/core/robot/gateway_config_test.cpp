#include "robot/gateway_config.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "common/error.h"
#include "sim/panda_hand.h"
#include "sim_mjcf.h"

namespace pnp::robot {
namespace {

std::string refusal(const std::function<void()>& fn, ErrorCode code = ErrorCode::kInvalidArgument) {
  try {
    fn();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code);
    return e.what();
  }
  ADD_FAILURE() << "expected an error";
  return "";
}

nlohmann::json minimal() {
  return {{"base_from_sim", geometry::RigidTransform::identity().to_json()}};
}

std::string refusal_for(const nlohmann::json& j) {
  return refusal([&] { GatewayConfig::from_json(j); });
}

TEST(GatewayConfig, MissingKeysTakeDefaults) {
  const GatewayConfig c = GatewayConfig::from_json(minimal());
  EXPECT_EQ(c.base_frame_id, "panda_link0");
  EXPECT_EQ(c.policy_period_s, 0.04);
  EXPECT_EQ(c.deadman_timeout_s, 0.1);
  EXPECT_EQ(c.max_episode_steps, 75);
  EXPECT_EQ(c.action_scale_m, 0.05);
  EXPECT_EQ(c.arrival_tolerance_m, 0.005);
  EXPECT_EQ(c.max_arrival_wait_periods, 0);
  EXPECT_EQ(c.limits.max_speed_m_per_s, 1.7);
  EXPECT_EQ(c.limits.workspace.min_m, SafetyLimits{}.workspace.min_m);
  // A partial limits object keeps the other limits' defaults.
  nlohmann::json j = minimal();
  j["limits"] = {{"max_step_m", 0.06}, {"workspace", {{"max_m", {0.6, 0.3, 0.4}}}}};
  const GatewayConfig d = GatewayConfig::from_json(j);
  EXPECT_EQ(d.limits.max_step_m, 0.06);
  EXPECT_EQ(d.limits.workspace.max_m, Eigen::Vector3d(0.6, 0.3, 0.4));
  EXPECT_EQ(d.limits.workspace.min_m, SafetyLimits{}.workspace.min_m);
  EXPECT_EQ(d.limits.gripper_max_width_m, 0.08);
}

TEST(GatewayConfig, JsonRoundTrip) {
  nlohmann::json j = minimal();
  j["base_from_sim"] =
      geometry::RigidTransform::from_translation_rpy({-0.88, -0.75, -0.4}, 0, 0, 0.5, "t")
          .to_json();
  j["base_frame_id"] = "fr3_link0";
  j["max_episode_steps"] = 80;
  j["deadman_timeout_s"] = 0.25;
  j["arrival_tolerance_m"] = 0.02;
  j["max_arrival_wait_periods"] = 4;
  const GatewayConfig c = GatewayConfig::from_json(j);
  const nlohmann::json out = c.to_json();
  EXPECT_EQ(GatewayConfig::from_json(out).to_json(), out);
  EXPECT_EQ(out["base_frame_id"], "fr3_link0");
  EXPECT_EQ(out["max_episode_steps"], 80);
  EXPECT_EQ(out["arrival_tolerance_m"], 0.02);
  EXPECT_EQ(out["max_arrival_wait_periods"], 4);
  const geometry::RigidTransform back = GatewayConfig::from_json(out).base_from_sim;
  EXPECT_TRUE(back.rotation().isApprox(c.base_from_sim.rotation(), 1e-15));
  EXPECT_EQ(back.translation_m(), c.base_from_sim.translation_m());
}

TEST(GatewayConfig, BaseFromSimIsRequired) {
  EXPECT_EQ(refusal_for(nlohmann::json::object()),
            "base_from_sim: missing (required, a row-major 4x4 matrix: the frame calibration has "
            "no default)");
  EXPECT_EQ(refusal_for(nlohmann::json::array()), "gateway config: expected a JSON object, got []");
}

TEST(GatewayConfig, UnknownKeysAreRefusedWithTheirPath) {
  nlohmann::json j = minimal();
  j["max_speed"] = 1;
  EXPECT_EQ(refusal_for(j),
            "max_speed: unknown key (expected one of base_from_sim, base_frame_id, limits, "
            "policy_period_s, deadman_timeout_s, lease_timeout_s, max_episode_steps, "
            "action_scale_m, arrival_tolerance_m, max_arrival_wait_periods)");
  j = minimal();
  j["limits"] = {{"max_step", 0.1}};
  EXPECT_EQ(refusal_for(j),
            "limits.max_step: unknown key (expected one of workspace, table_top_z_m, max_step_m, "
            "max_speed_m_per_s, max_rotation_step_rad, gripper_min_width_m, gripper_max_width_m, "
            "quaternion_norm_tolerance)");
  j = minimal();
  j["limits"] = {{"workspace", {{"min", {0, 0, 0}}}}};
  EXPECT_EQ(refusal_for(j), "limits.workspace.min: unknown key (expected one of min_m, max_m)");
}

TEST(GatewayConfig, TypeErrorsNameTheKeyPath) {
  nlohmann::json j = minimal();
  j["limits"] = {{"workspace", {{"min_m", {0.1, "a", 0.0}}}}};
  EXPECT_EQ(refusal_for(j), "limits.workspace.min_m[1]: expected a number, got \"a\"");
  j["limits"] = {{"workspace", {{"max_m", {0.1, 0.2}}}}};
  EXPECT_EQ(refusal_for(j),
            "limits.workspace.max_m: expected an array of 3 numbers [x, y, z], got [0.1,0.2]");
  j["limits"] = {{"max_speed_m_per_s", "fast"}};
  EXPECT_EQ(refusal_for(j), "limits.max_speed_m_per_s: expected a number, got \"fast\"");
  j["limits"] = 3;
  EXPECT_EQ(refusal_for(j), "limits: expected a JSON object, got 3");
  j = minimal();
  j["max_episode_steps"] = 12.5;
  EXPECT_EQ(refusal_for(j), "max_episode_steps: expected an integer, got 12.5");
  j["max_episode_steps"] = 4294967296ULL;
  EXPECT_EQ(refusal_for(j), "max_episode_steps: expected an integer, got 4294967296");
  j["max_episode_steps"] = 18446744073709551615ULL;  // would wrap to -1 as a long long
  EXPECT_EQ(refusal_for(j), "max_episode_steps: expected an integer, got 18446744073709551615");
  j["max_episode_steps"] = 10001;  // what a policy session may declare is bounded too
  EXPECT_EQ(refusal_for(j), "max_episode_steps: expected 1 to 10000 steps, got 10001");
  j = minimal();
  j["base_frame_id"] = 7;
  EXPECT_EQ(refusal_for(j), "base_frame_id: expected a string, got 7");
  j = minimal();
  j["base_from_sim"][2][3] = true;
  EXPECT_EQ(refusal_for(j), "base_from_sim[2][3]: expected a number, got true");
  j["base_from_sim"] = geometry::RigidTransform::identity().to_json();
  j["base_from_sim"][2][2] = -1.0;
  EXPECT_EQ(refusal_for(j),
            "base_from_sim: rotation part has det = -1, expected +1 (a reflection is not a "
            "rotation)");
}

TEST(GatewayConfig, ValidatesAfterParsing) {
  nlohmann::json j = minimal();
  j["limits"] = {{"workspace", {{"min_m", {0.8, 0.0, 0.0}}}}};
  EXPECT_EQ(refusal_for(j),
            "limits.workspace.min_m[0]: expected less than limits.workspace.max_m[0] (0.7 m, the "
            "x axis), got 0.8");
  j = minimal();
  j["limits"] = {{"gripper_max_width_m", -0.08}};
  EXPECT_EQ(refusal_for(j),
            "limits.gripper_max_width_m: expected a finite width greater than "
            "limits.gripper_min_width_m (0 m), got -0.08");
  j = minimal();
  j["policy_period_s"] = 0;
  EXPECT_EQ(refusal_for(j), "policy_period_s: expected a positive finite number (s), got 0");
  j = minimal();
  j["deadman_timeout_s"] = 0.03;
  EXPECT_EQ(refusal_for(j),
            "deadman_timeout_s: expected more than policy_period_s (0.04 s), or it trips every "
            "cycle, got 0.03");
  j = minimal();
  j["max_episode_steps"] = 0;
  EXPECT_EQ(refusal_for(j), "max_episode_steps: expected 1 to 10000 steps, got 0");
  j = minimal();
  j["action_scale_m"] = 0.2;
  EXPECT_EQ(refusal_for(j),
            "action_scale_m: expected at most limits.max_step_m (0.1 m), or a full action is "
            "refused, got 0.2");
  j = minimal();
  j["base_frame_id"] = "";
  EXPECT_EQ(refusal_for(j), "base_frame_id: expected a frame name, got \"\"");
  // The arrival wait: a tolerance in (0, 0.1] m, at most a second of waiting.
  const auto refusal_with = [](const char* key, const nlohmann::json& value) {
    nlohmann::json k = minimal();
    k[key] = value;
    return refusal_for(k);
  };
  const std::string tolerance = "arrival_tolerance_m: expected a distance in (0, 0.1] m, got ";
  EXPECT_EQ(refusal_with("arrival_tolerance_m", 0), tolerance + "0");
  EXPECT_EQ(refusal_with("arrival_tolerance_m", 0.5), tolerance + "0.5");
  const std::string waits = "max_arrival_wait_periods: expected an integer in [0, 25], got ";
  EXPECT_EQ(refusal_with("max_arrival_wait_periods", 26), waits + "26");
  EXPECT_EQ(refusal_with("max_arrival_wait_periods", -1), waits + "-1");
}

TEST(GatewayConfig, LoadReportsThePath) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path();
  const std::filesystem::path missing = dir / "pnp_gateway_config_test_missing.json";
  std::filesystem::remove(missing);
  EXPECT_EQ(refusal([&] { GatewayConfig::load(missing); }, ErrorCode::kNotFound),
            missing.string() + ": cannot open the gateway config");

  const std::filesystem::path bad = dir / "pnp_gateway_config_test_bad.json";
  std::ofstream(bad) << "{\"base_from_sim\": ";
  EXPECT_EQ(
      refusal([&] { GatewayConfig::load(bad); }).rfind(bad.string() + ": not valid JSON (", 0), 0u);
  std::ofstream(bad)
      << R"({"base_from_sim": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
                          "limits": {"max_step_m": -1}})";
  EXPECT_EQ(refusal([&] { GatewayConfig::load(bad); }),
            bad.string() + ": limits.max_step_m: expected a positive finite number (m), got -1");
  std::filesystem::remove(bad);
}

// The checked-in deployment config: it loads, and it matches the simulated Panda.
TEST(GatewayConfig, DeployedConfigLoadsAndMatchesTheSimulatedPanda) {
  const GatewayConfig c = GatewayConfig::load(PNP_GATEWAY_CONFIG);
  EXPECT_EQ(c.base_frame_id, "panda_link0");

  // base_from_sim undoes panda_link0's placement in panda.xml (a position, no rotation).
  const std::string xml(sim::mjcf::kpandaXml);
  std::smatch m;
  ASSERT_TRUE(
      std::regex_search(xml, m, std::regex(R"re(<body name="panda_link0" pos="([^"]*)">)re")));
  std::istringstream pos(m[1].str());
  Eigen::Vector3d link0;
  pos >> link0.x() >> link0.y() >> link0.z();
  EXPECT_TRUE(c.base_from_sim.apply(link0).isZero(1e-12));
  EXPECT_TRUE(c.base_from_sim.rotation().isIdentity(0));

  // The workspace holds the simulation's whole gripper box and start, seen from the base,
  // and the policy's timing is the simulation's.
  // (its floor raised to keep the finger pads above the table)
  const double floor_sim = c.base_from_sim.inverse().apply(c.limits.workspace.min_m).z();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p(
        (corner & 1) ? sim::layout::kWorkspaceMax.x() : sim::layout::kWorkspaceMin.x(),
        (corner & 2) ? sim::layout::kWorkspaceMax.y() : sim::layout::kWorkspaceMin.y(),
        (corner & 4) ? sim::layout::kWorkspaceMax.z() : floor_sim);
    EXPECT_TRUE(c.limits.workspace.contains(c.base_from_sim.apply(p))) << p.transpose();
  }
  EXPECT_TRUE(c.limits.workspace.contains(c.base_from_sim.apply(sim::layout::kGripperStart)));
  // ... but nothing that puts the pads into the table top (base z = 0).
  EXPECT_GE(c.limits.workspace.min_m.z(), sim::lowest_grip_point_z(c.limits.table_top_z_m));
  EXPECT_EQ(c.lease_timeout_s, GatewayConfig{}.lease_timeout_s);
  EXPECT_EQ(c.policy_period_s, sim::layout::kStepDuration_s);
  EXPECT_EQ(c.max_episode_steps, sim::layout::kArmEpisodeSteps);
  EXPECT_EQ(c.action_scale_m, sim::layout::kActionPositionScale);
  // The file says what the defaults say: one source of truth for both.
  EXPECT_EQ(c.limits.workspace.min_m, SafetyLimits{}.workspace.min_m);
  EXPECT_EQ(c.limits.workspace.max_m, SafetyLimits{}.workspace.max_m);
}

}  // namespace
}  // namespace pnp::robot
