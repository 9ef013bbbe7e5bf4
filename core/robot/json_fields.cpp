#include "robot/json_fields.h"

#include <fmt/format.h>

#include <fstream>
#include <limits>

#include "common/error.h"

namespace pnp::robot::json_fields {

using nlohmann::json;

std::string key_path(std::string_view prefix, std::string_view key) {
  return prefix.empty() ? std::string(key) : fmt::format("{}.{}", prefix, key);
}

// The keys of an object, each one known: a misspelt key would otherwise be ignored and its
// setting silently left at the default.
void require_object(const json& j, std::string_view path,
                    std::initializer_list<std::string_view> known) {
  if (!j.is_object()) {
    throw_invalid_argument(path.empty() ? "gateway config" : path, "a JSON object", j.dump());
  }
  for (const auto& item : j.items()) {
    bool found = false;
    for (const std::string_view k : known) found = found || item.key() == k;
    if (found) continue;
    std::string expected;
    for (const std::string_view k : known) expected.append(expected.empty() ? "" : ", ").append(k);
    throw Error(ErrorCode::kInvalidArgument, fmt::format("{}: unknown key (expected one of {})",
                                                         key_path(path, item.key()), expected));
  }
}

void read_number(const json& object, std::string_view key, std::string_view prefix, double& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  if (!it->is_number()) throw_invalid_argument(key_path(prefix, key), "a number", it->dump());
  out = it->get<double>();
}

void read_int(const json& object, std::string_view key, std::string_view prefix, int& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  // Unsigned and signed JSON integers are stored apart; either must fit an int.
  constexpr auto kMax = static_cast<unsigned long long>(std::numeric_limits<int>::max());
  const bool fits = it->is_number_unsigned()
                        ? it->get<unsigned long long>() <= kMax
                        : it->is_number_integer() &&
                              it->get<long long>() >= std::numeric_limits<int>::min() &&
                              it->get<long long>() <= std::numeric_limits<int>::max();
  if (!fits) throw_invalid_argument(key_path(prefix, key), "an integer", it->dump());
  out = it->get<int>();
}

void read_string(const json& object, std::string_view key, std::string_view prefix,
                 std::string& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  if (!it->is_string()) throw_invalid_argument(key_path(prefix, key), "a string", it->dump());
  out = it->get<std::string>();
}

void read_vector3(const json& object, std::string_view key, std::string_view prefix,
                  Eigen::Vector3d& out) {
  const auto it = object.find(key);
  if (it == object.end()) return;
  const std::string path = key_path(prefix, key);
  if (!it->is_array() || it->size() != 3) {
    throw_invalid_argument(path, "an array of 3 numbers [x, y, z]", it->dump());
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const json& v = (*it)[i];
    if (!v.is_number())
      throw_invalid_argument(fmt::format("{}[{}]", path, i), "a number", v.dump());
    out(static_cast<Eigen::Index>(i)) = v.get<double>();
  }
}

json vector3_json(const Eigen::Vector3d& v) {
  return json::array({v.x(), v.y(), v.z()});
}

json read_file(const std::filesystem::path& path, std::string_view what) {
  std::ifstream in(path);
  if (!in) {
    throw Error(ErrorCode::kNotFound, fmt::format("{}: cannot open the {}", path.string(), what));
  }
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw Error(ErrorCode::kInvalidArgument,
                fmt::format("{}: not valid JSON ({})", path.string(), e.what()));
  }
}

}  // namespace pnp::robot::json_fields
