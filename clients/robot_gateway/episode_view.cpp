#include "clients/robot_gateway/episode_view.h"

#include <fstream>

#include "common/error.h"
#include "plot/episode_view_svg.h"
#include "sim/world_layout.h"

namespace pnp::gateway {

std::filesystem::path write_episode_view(const std::filesystem::path& dir,
                                         const EpisodeReport& report, bool dry_run) {
  plot::EpisodeTrace trace;
  trace.title = "seed " + std::to_string(report.seed) + ": " +
                std::string(episode_end_name(report.end)) +
                (dry_run ? " (dry run: the shadow arm's motion; the arm did not move)" : "");
  trace.goal = report.goal_sim;
  trace.frames = report.path;
  trace.success = report.success;
  trace.success_radius_m = sim::layout::kTaskSuccessDistance;
  trace.table_top_z = sim::layout::kTableTop_z;
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  const std::filesystem::path path = dir / ("episode_" + std::to_string(report.seed) + ".svg");
  std::ofstream file(path);
  file << plot::episode_view_svg(trace);
  if (!file.flush())
    throw Error(ErrorCode::kUnavailable, "--view: could not write " + path.string());
  return path;
}

}  // namespace pnp::gateway
