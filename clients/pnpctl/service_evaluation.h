#pragma once
// Held-out evaluation through the platform itself: episodes are run on the simulation
// service and every decision comes from the inference service's session stream, exactly
// as a client would drive a robot. Success is the task's (object within 0.05 m of the goal
// when the 50-step episode ends).

#include <cstdint>
#include <string>
#include <vector>

#include "clients/pnpctl/endpoints.h"
#include "pnp/common/v1/common.pb.h"

namespace pnp::pnpctl {

struct ServiceEvaluation {
  int episodes = 0;
  int successes = 0;
  long long env_steps = 0;
  // Subtask sequences the choreographer chose ("AMR"), most frequent first.
  std::vector<std::pair<std::string, int>> sequences;
  double success_rate() const { return episodes ? static_cast<double>(successes) / episodes : 0; }
};

// Episodes are the simulation service's episodes 0..n-1 of one environment created with
// `seed`: pick a seed no training run used.
// INVALID_ARGUMENT naming --episodes unless it is positive.
void require_evaluation_episodes(int episodes);

// Where the episodes are played.
struct ServiceWorld {
  common::v1::Robot robot = common::v1::ROBOT_FETCH;
  common::v1::ObjectShape object = common::v1::OBJECT_SHAPE_BLOCK;
  common::v1::World world = common::v1::WORLD_UNSPECIFIED;  // the platform's default, gym
  common::v1::Actuation actuation = common::v1::ACTUATION_UNSPECIFIED;  // the robot's default
};

ServiceEvaluation evaluate_through_services(const Endpoints& endpoints, const ServiceWorld& world,
                                            int episodes, std::uint64_t seed);

}  // namespace pnp::pnpctl
