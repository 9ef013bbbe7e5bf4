#include "clients/robot_gateway/gateway_summary.h"

#include <algorithm>
#include <map>
#include <string>

#include "common/percentile.h"

namespace pnp::gateway {

nlohmann::json summarize(const std::vector<EpisodeReport>& episodes) {
  std::vector<double> cycles, state, inference, send;
  int successes = 0, missed = 0, refused = 0, controller_refused = 0, rate_limited = 0;
  int clamped = 0, held_without_target = 0, decisions = 0, arrival_waits = 0;
  std::map<std::string, int> ends, arm_left, controller_refusals_by_reason;
  nlohmann::json seeds = nlohmann::json::array();
  for (const EpisodeReport& e : episodes) {
    cycles.insert(cycles.end(), e.cycle_us.begin(), e.cycle_us.end());
    state.insert(state.end(), e.state_us.begin(), e.state_us.end());
    inference.insert(inference.end(), e.inference_us.begin(), e.inference_us.end());
    send.insert(send.end(), e.send_us.begin(), e.send_us.end());
    successes += e.success ? 1 : 0;
    missed += e.missed_periods;
    refused += e.refused;
    controller_refused += e.controller_refused;
    rate_limited += e.rate_limited;
    clamped += e.clamped;
    held_without_target += e.held_without_target;
    decisions += e.decisions;
    arrival_waits += e.arrival_waits;
    for (const auto& [reason, n] : e.controller_refusals_by_reason) {
      controller_refusals_by_reason[reason] += n;
    }
    ++ends[std::string(episode_end_name(e.end))];
    ++arm_left[e.arm_left.rfind("stop not delivered", 0) == 0 ? "stop_not_delivered" : e.arm_left];
    seeds.push_back(e.seed);
  }
  const auto n = static_cast<double>(std::max<std::size_t>(1, episodes.size()));
  return {{"episodes", episodes.size()},
          {"successes", successes},
          {"success_rate", successes / n},
          {"cycles", cycles.size()},
          {"decisions", decisions},
          {"arrival_waits", arrival_waits},
          {"cycle_p50_us", percentile(cycles, 0.5)},
          {"cycle_p99_us", percentile(cycles, 0.99)},
          {"cycle_max_us", percentile(cycles, 1.0)},
          {"state_p50_us", percentile(state, 0.5)},
          {"state_p99_us", percentile(state, 0.99)},
          {"inference_p50_us", percentile(inference, 0.5)},
          {"inference_p99_us", percentile(inference, 0.99)},
          {"send_p50_us", percentile(send, 0.5)},
          {"send_p99_us", percentile(send, 0.99)},
          {"missed_periods", missed},
          {"refused_targets", refused},
          {"rate_limited_targets", rate_limited},
          {"clamped_targets", clamped},
          {"held_without_target", held_without_target},
          {"controller_refusals", controller_refused},
          {"controller_refusals_by_reason", controller_refusals_by_reason},
          {"ends", ends},
          {"arm_left", arm_left},
          {"seeds", seeds}};
}

}  // namespace pnp::gateway
