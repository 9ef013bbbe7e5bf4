#include "sim/object_shape.h"

#include <string>

#include "common/enum_names.h"
#include "common/error.h"

namespace pnp::sim {
namespace {

// Hardwood-like density (~800 kg/m^3): light enough for a 10-25 N grasp, heavy enough
// that contact stays well conditioned at 2 ms.
constexpr ObjectSpec kBlockSpec{false, 0.025, 0.025, 0.100};
constexpr ObjectSpec kSmallBlockSpec{false, 0.015, 0.015, 0.030};
constexpr ObjectSpec kCylinderSpec{true, 0.010, 0.030, 0.020};

}  // namespace

std::string_view object_name(ObjectShape shape) {
  switch (shape) {
    case ObjectShape::kBlock:
      return "block";
    case ObjectShape::kSmallBlock:
      return "small_block";
    case ObjectShape::kCylinder:
      return "cylinder";
  }
  throw_internal("object_name: unknown ObjectShape value");
}

const ObjectSpec& object_spec(ObjectShape shape) {
  switch (shape) {
    case ObjectShape::kBlock:
      return kBlockSpec;
    case ObjectShape::kSmallBlock:
      return kSmallBlockSpec;
    case ObjectShape::kCylinder:
      return kCylinderSpec;
  }
  throw_internal("object_spec: unknown ObjectShape value");
}

ObjectShape parse_object(std::string_view name, std::string_view field) {
  return parse_enum<ObjectShape>(name, kAllObjectShapes, &object_name, field);
}

}  // namespace pnp::sim
