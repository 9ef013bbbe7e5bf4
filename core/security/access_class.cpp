#include "security/access_class.h"

namespace pnp::security {

std::string_view access_class_name(AccessClass c) {
  switch (c) {
    case AccessClass::kReader:
      return "reader";
    case AccessClass::kAgent:
      return "agent";
    case AccessClass::kOperator:
      return "operator";
    case AccessClass::kRobot:
      return "robot";
    case AccessClass::kService:
      return "service";
    case AccessClass::kDelegate:
      return "delegate";
  }
  return "unknown";
}

std::optional<AccessClass> parse_access_class(std::string_view name) {
  for (const AccessClass c : kAllAccessClasses)
    if (access_class_name(c) == name) return c;
  return std::nullopt;
}

}  // namespace pnp::security
