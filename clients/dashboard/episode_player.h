#pragma once
// Plays held-out episodes of the hierarchy the inference service serves, through the
// simulation service, and keeps each step's gripper, object and chosen subtask: what the
// dashboard's episode viewer draws. The same episodes as `pnpctl evaluate --seed`.

#include <grpcpp/grpcpp.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plot/episode_view_svg.h"

namespace pnp::dashboard {

struct ServedWorld {
  std::string robot = "fetch", object = "block", world = "gym";  // the choreographer's
  std::string actuation = "mocap";  // how its hand followed actions in training
};

struct PlayedEpisodes {
  ServedWorld world;
  std::uint64_t seed = 0;
  std::vector<plot::EpisodeTrace> episodes;
  int successes = 0;
};

class EpisodePlayer {
 public:
  // Channels to the simulation and inference services (with the platform's credentials).
  EpisodePlayer(std::shared_ptr<grpc::Channel> sim, std::shared_ptr<grpc::Channel> inference);

  // The robot, object and world the served choreographer was trained on. UNAVAILABLE or
  // FAILED_PRECONDITION (nothing served) as pnp::Error.
  ServedWorld served_world();

  // `count` episodes of `seed` (1..kMaxEpisodes; INVALID_ARGUMENT naming "count" otherwise).
  PlayedEpisodes play(int count, std::uint64_t seed);

  static constexpr int kMaxEpisodes = 20;

 private:
  std::shared_ptr<grpc::Channel> sim_, inference_;
};

}  // namespace pnp::dashboard
