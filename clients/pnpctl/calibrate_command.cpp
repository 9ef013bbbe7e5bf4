// pnpctl robot calibrate: the simulation-to-base transform from touched points, written into
// a copy of the gateway's config. A lab touches >= 3 table points with the fingertips and
// reads O_T_EE's position for each; the fit (geometry/point_fit.h) prints each point's
// residual and refuses to write a calibration with a point off by more than the bound.
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/table.h"
#include "common/error.h"
#include "geometry/point_fit.h"
#include "robot/gateway_config.h"
#include "robot/json_fields.h"

namespace pnp::pnpctl {
namespace {

Eigen::Vector3d point(const nlohmann::json& pair, const char* key, const std::string& field) {
  const std::string where = field + "." + key;
  if (!pair.contains(key) || !pair.at(key).is_array() || pair.at(key).size() != 3)
    throw_invalid_argument(where, "[x, y, z] in metres", pair.value(key, nlohmann::json()).dump());
  Eigen::Vector3d p;
  for (int i = 0; i < 3; ++i) {
    const auto& v = pair.at(key)[static_cast<std::size_t>(i)];
    if (!v.is_number()) throw_invalid_argument(where, "[x, y, z] in metres", pair.at(key).dump());
    p(i) = v.get<double>();
  }
  return p;
}

// {"pairs": [{"sim_m": [x, y, z], "base_m": [x, y, z]}, ...]}
std::vector<geometry::PointPair> read_pairs(const std::string& path) {
  const nlohmann::json doc = robot::json_fields::read_file(path, "touched points (--pairs)");
  if (!doc.is_object() || !doc.contains("pairs") || !doc.at("pairs").is_array())
    throw_invalid_argument("--pairs", "{\"pairs\": [{\"sim_m\": [...], \"base_m\": [...]}, ...]}",
                           path);
  std::vector<geometry::PointPair> pairs;
  for (std::size_t i = 0; i < doc.at("pairs").size(); ++i) {
    const auto& pair = doc.at("pairs")[i];
    const std::string field = "pairs[" + std::to_string(i) + "]";
    if (!pair.is_object() || pair.size() != 2)
      throw_invalid_argument(field, "an object of sim_m and base_m", pair.dump());
    pairs.push_back({point(pair, "sim_m", field), point(pair, "base_m", field)});
  }
  return pairs;
}

}  // namespace

int calibrate_command(const CalibrateArgs& args) {
  const std::vector<geometry::PointPair> pairs = read_pairs(args.pairs);
  const geometry::PointFit fit = geometry::fit_rigid_transform(pairs, "pairs");
  Table table({"pair", "sim_m", "base_m", "residual_mm"});
  double worst = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const auto text = [](const Eigen::Vector3d& p) {
      return fixed(p.x(), 3) + " " + fixed(p.y(), 3) + " " + fixed(p.z(), 3);
    };
    table.add({std::to_string(i), text(pairs[i].child_m), text(pairs[i].parent_m),
               fixed(fit.residuals_m[i] * 1000, 1)});
    worst = std::max(worst, fit.residuals_m[i]);
  }
  table.print(stdout);
  std::printf("rms %.1f mm over %zu points; base_from_sim:\n%s\n", fit.rms_m * 1000, pairs.size(),
              fit.parent_from_child.to_json().dump().c_str());
  if (args.out.empty()) return 0;
  if (worst * 1000 > args.max_residual_mm) {
    throw Error(ErrorCode::kFailedPrecondition,
                "a point is " + fixed(worst * 1000, 1) +
                    " mm off the fit, over --max-residual-mm " + fixed(args.max_residual_mm, 1) +
                    ": touch it again (or check the pair); nothing written");
  }
  nlohmann::json config = robot::json_fields::read_file(args.config, "gateway config (--config)");
  config["base_from_sim"] = fit.parent_from_child.to_json();
  robot::GatewayConfig::from_json(config);  // the whole file still loads
  std::ofstream out(args.out);
  out << config.dump(2) << "\n";
  if (!out.flush()) throw Error(ErrorCode::kUnavailable, "--out: could not write " + args.out);
  std::printf("wrote %s (%s with this calibration)\n", args.out.c_str(), args.config.c_str());
  return 0;
}

}  // namespace pnp::pnpctl
