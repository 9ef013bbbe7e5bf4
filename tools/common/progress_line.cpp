#include "tools/common/progress_line.h"

namespace pnp::tools {

void print_progress(std::FILE* out, const std::string& role, const rl::CurvePoint& p) {
  std::fprintf(out, "%-10s steps %7lld  episodes %6lld  score %.2f  success %.2f  ", role.c_str(),
               p.env_steps, p.episodes, p.stop_score, p.task_success);
  if (p.detail.empty()) {  // a subtask expert or end-to-end policy
    std::fprintf(out, "subtask %.2f (%4.1f steps)  critic %.4f", p.subtask_success,
                 p.subtask_mean_steps, p.critic_loss);
  } else {  // the choreographer
    std::fprintf(out, "sampled %.2f  greedy %s", p.sampled_success, p.detail.c_str());
  }
  std::fprintf(out, "  wall %6.1fs\n", p.wall_s);
}

}  // namespace pnp::tools
