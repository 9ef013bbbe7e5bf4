#include "clients/robot_gateway/gateway_metrics.h"

#include <string>
#include <vector>

namespace pnp::gateway {
namespace {

constexpr std::string_view kEpisodes = "pnp_gateway_episodes_total";
constexpr std::string_view kEpisodesHelp = "Gateway episodes finished, by how they ended.";

// Around the 40 ms policy period: a cycle above it is a missed period.
const std::vector<double>& cycle_bounds() {
  static const std::vector<double> bounds = {0.5e-3, 1e-3,  2e-3,  5e-3, 10e-3,
                                             20e-3,  40e-3, 80e-3, 0.16};
  return bounds;
}

}  // namespace

GatewayMetrics::GatewayMetrics(services::MetricsRegistry& registry)
    : registry_(registry),
      cycle_seconds_(registry.histogram(
          "pnp_gateway_cycle_seconds",
          "Gateway cycle time: state, inference, transform and send, in seconds.", cycle_bounds())),
      missed_periods_(registry.counter("pnp_gateway_missed_periods_total",
                                       "Gateway cycles that overran the policy period.")),
      refused_targets_(
          registry.counter("pnp_gateway_refused_targets_total",
                           "Targets the gateway's safety check refused (the arm held instead).")),
      controller_refusals_(
          registry.counter("pnp_gateway_controller_refusals_total",
                           "Targets the controller answered with a status other than OK.")) {
  for (const EpisodeEnd end : {EpisodeEnd::kSuccess, EpisodeEnd::kStepCap, EpisodeEnd::kDeadman})
    registry_.counter(kEpisodes, kEpisodesHelp, {{"end", std::string(episode_end_name(end))}});
}

void GatewayMetrics::record(const EpisodeReport& report) {
  registry_.counter(kEpisodes, kEpisodesHelp, {{"end", std::string(episode_end_name(report.end))}})
      .Increment();
  for (const double us : report.cycle_us) cycle_seconds_.Observe(us * 1e-6);
  missed_periods_.Increment(report.missed_periods);
  refused_targets_.Increment(report.refused);
  controller_refusals_.Increment(report.controller_refused);
}

}  // namespace pnp::gateway
