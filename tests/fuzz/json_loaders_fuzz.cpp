// Every JSON document a user hands the platform, on arbitrary text: the gateway config,
// the controller's limits, a training spec, a rigid transform and an authorization policy.
// The first byte picks the loader, the rest is the document.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string_view>

#include "geometry/rigid_transform.h"
#include "robot/controller_limits.h"
#include "robot/gateway_config.h"
#include "security/auth_policy.h"
#include "tests/fuzz/fuzz_contract.h"
#include "training/training_spec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const int loader = data[0] % 5;
  if (loader == 4) {  // parses its own text, refusing what is not JSON
    pnp::fuzz::refuse_or_accept([&] { pnp::security::AuthPolicy::parse(text, "policy.json"); });
    return 0;
  }
  // The loaders take parsed JSON: what is not JSON is refused before them.
  const auto json = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) return 0;
  pnp::fuzz::refuse_or_accept([&] {
    switch (loader) {
      case 0:
        pnp::robot::GatewayConfig::from_json(json);
        break;
      case 1:
        pnp::robot::ControllerLimits::from_json(json);
        break;
      case 2:
        pnp::training::spec_from_json(json).validate();
        break;
      default:
        pnp::geometry::RigidTransform::from_json(json, "transform");
        break;
    }
  });
  return 0;
}
