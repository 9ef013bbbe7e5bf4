#include "store/records.h"

#include <algorithm>
#include <array>

#include "common/enum_names.h"
#include "common/error.h"

namespace pnp::store {
namespace {

constexpr std::array<std::pair<RunState, std::string_view>, 5> kStateNames{{
    {RunState::kPending, "pending"},
    {RunState::kRunning, "running"},
    {RunState::kSucceeded, "succeeded"},
    {RunState::kFailed, "failed"},
    {RunState::kCancelled, "cancelled"},
}};

}  // namespace

std::string_view run_state_name(RunState state) {
  for (const auto& [value, name] : kStateNames)
    if (value == state) return name;
  throw_internal("run_state_name: unknown state");
}

RunState parse_run_state(std::string_view name, std::string_view field) {
  static constexpr std::array<RunState, 5> kStates{RunState::kPending, RunState::kRunning,
                                                   RunState::kSucceeded, RunState::kFailed,
                                                   RunState::kCancelled};
  return parse_enum<RunState>(name, kStates, run_state_name, field);
}

bool is_terminal(RunState state) {
  return state == RunState::kSucceeded || state == RunState::kFailed ||
         state == RunState::kCancelled;
}

std::string_view run_outcome(RunState state, bool reached) {
  if (state != RunState::kSucceeded) return run_state_name(state);
  return reached ? "reached" : "not-reached";
}

}  // namespace pnp::store
