#pragma once
// The dashboard's HTML pages and JSON, rendered from store records and the inference
// service's status: no templates, no scripts or styles from elsewhere (nothing outside the
// machine need be reachable). The run page draws its learning curve with the small script
// of live_curve_script(), which polls the JSON and redraws as the run trains.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "clients/dashboard/episode_player.h"
#include "store/records.h"

namespace pnp::dashboard {

// What the inference service says it serves (empty roles and an error when unreachable).
struct ServingView {
  bool ready = false;
  std::vector<std::pair<std::string, std::int64_t>> roles;  // role, checkpoint id
  std::string world;                                        // "gym/panda/block"
  std::string error;                                        // why it could not be asked
};

std::string overview_page(const std::vector<store::RunRecord>& runs,
                          const std::vector<store::Promotion>& promotions,
                          const ServingView& serving);
std::string run_page(const store::RunRecord& run,
                     const std::vector<store::CheckpointInfo>& checkpoints);
std::string episodes_page(const PlayedEpisodes& played);
std::string error_page(int status, const std::string& message);
// 401/403 with what is needed and a link to /login; the login form with an error, if any.
std::string access_page(int status, const std::string& message);
// `nonce`: the one-time value the form posts back (SessionBook::issue_login_nonce).
std::string login_page(const std::string& error, const std::string& nonce);

// /api/runs/ID: the run's state and every evaluation, what the curve script draws.
nlohmann::json run_json(const store::RunRecord& run,
                        const std::vector<store::MetricPoint>& metrics);

// The run page's script: fetches /api/runs/ID every `poll_ms` and redraws the curve (task
// success, subtask success and the stop score against training steps) and the state line
// (state, training steps, wall time at the last evaluation).
std::string live_curve_script(int poll_ms);

}  // namespace pnp::dashboard
