#pragma once
// The gateway's Prometheus metrics, updated once per finished episode (never inside the
// cycle): how episodes end, how long cycles take against the policy period, and how many
// periods were missed or targets refused -- what an operator alerts on while an arm runs.
//   pnp_gateway_episodes_total{end}             counter (success, step_cap, deadman, ...)
//   pnp_gateway_cycle_seconds                   histogram, 0.5 ms to 160 ms
//   pnp_gateway_missed_periods_total            counter
//   pnp_gateway_refused_targets_total           counter (the gateway's own safety check)
//   pnp_gateway_controller_refusals_total       counter (feedback other than OK)

#include "clients/robot_gateway/gateway_episode.h"
#include "services/common/metrics_registry.h"

namespace pnp::gateway {

class GatewayMetrics {
 public:
  // Registers every family (so each scrapes as 0 before the first episode); `registry`
  // must outlive this.
  explicit GatewayMetrics(services::MetricsRegistry& registry);

  void record(const EpisodeReport& report);

 private:
  services::MetricsRegistry& registry_;
  services::Histogram& cycle_seconds_;
  services::Counter& missed_periods_;
  services::Counter& refused_targets_;
  services::Counter& controller_refusals_;
};

}  // namespace pnp::gateway
