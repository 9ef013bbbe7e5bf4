#pragma once
// What a gateway session reports after its episodes: success rate and how the cycles
// went (latency percentiles, missed periods, refusals), as one JSON object. Shared by
// pnp-robot-gateway and pnp-bench-gateway.

#include <nlohmann/json.hpp>
#include <vector>

#include "clients/robot_gateway/gateway_episode.h"

namespace pnp::gateway {

nlohmann::json summarize(const std::vector<EpisodeReport>& episodes);

}  // namespace pnp::gateway
