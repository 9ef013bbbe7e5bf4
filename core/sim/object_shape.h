#pragma once
// The three objects to pick and place. Their sizes are defined here once and feed the
// MJCF, the goal heights and the grasp predicate.

#include <array>
#include <string_view>

namespace pnp::sim {

enum class ObjectShape { kBlock, kSmallBlock, kCylinder };

inline constexpr std::array<ObjectShape, 3> kAllObjectShapes{
    ObjectShape::kBlock, ObjectShape::kSmallBlock, ObjectShape::kCylinder};

struct ObjectSpec {
  bool is_cylinder = false;
  double half_width_m = 0;   // half the extent the fingers close on (box half side, radius)
  double half_height_m = 0;  // half the vertical extent: resting centre height above table
  double mass_kg = 0;
};

std::string_view object_name(ObjectShape shape);
const ObjectSpec& object_spec(ObjectShape shape);

// Parses "block", "small_block" or "cylinder"; anything else is an INVALID_ARGUMENT.
ObjectShape parse_object(std::string_view name, std::string_view field = "object");

}  // namespace pnp::sim
