#pragma once
// One pick-and-place episode as a standalone SVG: a top view (x, y) and a side view (x, z)
// of the gripper's path, coloured by the subtask the choreographer had chosen at each
// step, the object's path and the goal with its success radius. For the dashboard's
// episode viewer; no dependency beyond formatting.

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace pnp::plot {

// One step's state: positions in metres in the simulation's world frame.
struct EpisodeFrame {
  std::array<double, 3> gripper{};
  std::array<double, 3> object{};
  int subtask = -1;  // 0 approach, 1 manipulate, 2 retract; -1 none (an end-to-end policy)
};

struct EpisodeTrace {
  std::string title;
  std::array<double, 3> goal{};
  std::vector<EpisodeFrame> frames;  // the first is the reset state
  bool success = false;
  double success_radius_m = 0.05;
  std::optional<double> table_top_z;  // drawn in the side view when known
};

// Elements carry classes a page or a test can select: the svg "episode" with data-steps
// and data-success, each view "view top" / "view side", gripper segments "gripper
// subtask-NAME", "object-path", "goal".
std::string episode_view_svg(const EpisodeTrace& trace);

// The subtask colours the view uses (approach, manipulate, retract; other: grey).
std::string subtask_colour(int subtask);
std::string subtask_name(int subtask);

}  // namespace pnp::plot
