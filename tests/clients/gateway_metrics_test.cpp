// The gateway's Prometheus metrics: every family scrapes before the first episode, and an
// episode's report adds its end, its cycles, missed periods and refusals.
#include "clients/robot_gateway/gateway_metrics.h"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace pnp::gateway {
namespace {

bool has_line(const std::string& text, const std::string& line) {
  return ("\n" + text).find("\n" + line + "\n") != std::string::npos;
}

TEST(GatewayMetrics, EveryFamilyScrapesBeforeTheFirstEpisode) {
  services::MetricsRegistry registry;
  const GatewayMetrics metrics(registry);
  const std::string text = registry.render();
  for (const char* line :
       {"pnp_gateway_episodes_total{end=\"success\"} 0", "pnp_gateway_missed_periods_total 0",
        "pnp_gateway_refused_targets_total 0", "pnp_gateway_controller_refusals_total 0",
        "pnp_gateway_cycle_seconds_count 0"})
    EXPECT_TRUE(has_line(text, line)) << line << "\n" << text;
}

TEST(GatewayMetrics, AnEpisodeAddsItsEndCyclesAndMisses) {
  services::MetricsRegistry registry;
  GatewayMetrics metrics(registry);
  EpisodeReport report;
  report.end = EpisodeEnd::kDeadman;
  report.cycle_us = {900, 1500, 45'000};
  report.missed_periods = 1;
  report.refused = 2;
  report.controller_refused = 3;
  metrics.record(report);
  report.end = EpisodeEnd::kSuccess;
  report.cycle_us = {1200};
  report.missed_periods = 0;
  metrics.record(report);
  const std::string text = registry.render();
  for (const char* line :
       {"pnp_gateway_episodes_total{end=\"deadman\"} 1",
        "pnp_gateway_episodes_total{end=\"success\"} 1", "pnp_gateway_missed_periods_total 1",
        "pnp_gateway_refused_targets_total 4", "pnp_gateway_controller_refusals_total 6",
        "pnp_gateway_cycle_seconds_count 4", "pnp_gateway_cycle_seconds_bucket{le=\"0.001\"} 1",
        "pnp_gateway_cycle_seconds_bucket{le=\"0.04\"} 3",
        "pnp_gateway_cycle_seconds_bucket{le=\"0.08\"} 4"})
    EXPECT_TRUE(has_line(text, line)) << line << "\n" << text;
}

// The dashboard and the alert rules query only gateway series this code exports (the
// other services' names are checked against a real Prometheus in integration.Monitoring).
TEST(GatewayMetrics, TheDashboardAndAlertsNameOnlySeriesItExports) {
  services::MetricsRegistry registry;
  const GatewayMetrics metrics(registry);
  const std::string exported = registry.render();
  int names = 0;
  for (const char* file : {"grafana-dashboard.json", "alerts.yml"}) {
    std::ifstream in(std::string(PNP_SOURCE_DIR) + "/deploy/monitoring/" + file);
    ASSERT_TRUE(in) << file;
    std::stringstream contents;
    contents << in.rdbuf();
    const std::string text = contents.str();
    const std::regex name(R"(pnp_gateway_[a-z_]+)");
    for (std::sregex_iterator m(text.begin(), text.end(), name), end; m != end; ++m, ++names)
      EXPECT_NE(exported.find("\n" + m->str() + (m->str().ends_with("_bucket") ? "{" : "")),
                std::string::npos)
          << file << " names " << m->str();
  }
  EXPECT_GT(names, 4);
}

}  // namespace
}  // namespace pnp::gateway
