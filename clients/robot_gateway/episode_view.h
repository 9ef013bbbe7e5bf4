#pragma once
// An episode the gateway played, drawn as the dashboard's episode viewer draws one
// (plot::episode_view_svg): top and side views of the grip point's path coloured by
// subtask, the object's path and the goal, in the simulation frame. What an operator
// looks at after a dry run, before letting the arm move (pnp-robot-gateway --view DIR).

#include <filesystem>

#include "clients/robot_gateway/gateway_episode.h"

namespace pnp::gateway {

// Writes <dir>/episode_<seed>.svg (creating `dir`); returns its path. UNAVAILABLE if it
// cannot be written.
std::filesystem::path write_episode_view(const std::filesystem::path& dir,
                                         const EpisodeReport& report, bool dry_run);

}  // namespace pnp::gateway
