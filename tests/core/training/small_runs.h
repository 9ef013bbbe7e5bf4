#pragma once
// Training specs small enough for tests (a second or two each) and a scratch store.

#include <unistd.h>

#include <filesystem>
#include <string>

#include "training/training_spec.h"

namespace pnp::training::testing {

// An approach expert with small networks, evaluated every 200 steps on 10 episodes.
inline TrainingSpec small_spec(const std::string& role = "approach", long long max_steps = 600) {
  TrainingSpec spec;
  spec.role = role;
  spec.algorithm = role == "hlc" ? "a3c" : "ddpg_her";
  spec.seed = 3;
  spec.stop.max_steps = max_steps;
  spec.stop.eval_interval_steps = 200;
  spec.stop.eval_episodes = 10;
  spec.stop.target_success = 1.0;  // rarely reached twice: the run goes to its cap
  spec.ddpg.hidden = {32, 32};
  spec.ddpg.batch_size = 32;
  spec.ddpg.buffer_size = 20'000;
  spec.ddpg.demo_episodes = 2;
  spec.ddpg.demo_pretrain_updates = 20;
  spec.ddpg.updates_per_transition = 0.25;
  spec.a3c.network = {{16}, 8};
  return spec;
}

// A fresh directory per test, removed at the end.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("pnp_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() { std::filesystem::remove_all(path_); }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace pnp::training::testing
