#pragma once
// Reading the robot side's JSON config files (the gateway's, the controller stand-in's)
// strictly: every key known, every value of the expected type, each error naming the key
// path ("limits.workspace.min_m[1]: expected a number, got \"a\""). A key left out keeps
// the caller's default.

#include <Eigen/Core>
#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace pnp::robot::json_fields {

std::string key_path(std::string_view prefix, std::string_view key);

// INVALID_ARGUMENT unless `j` is an object whose keys are all in `known`: a misspelt key
// would otherwise be ignored and its setting silently left at the default.
void require_object(const nlohmann::json& j, std::string_view path,
                    std::initializer_list<std::string_view> known);

void read_number(const nlohmann::json& object, std::string_view key, std::string_view prefix,
                 double& out);
void read_int(const nlohmann::json& object, std::string_view key, std::string_view prefix,
              int& out);
void read_string(const nlohmann::json& object, std::string_view key, std::string_view prefix,
                 std::string& out);
void read_vector3(const nlohmann::json& object, std::string_view key, std::string_view prefix,
                  Eigen::Vector3d& out);
nlohmann::json vector3_json(const Eigen::Vector3d& v);

// The file's JSON: NOT_FOUND when it cannot be read, INVALID_ARGUMENT when it is not JSON
// (`what` names the kind of file in the message).
nlohmann::json read_file(const std::filesystem::path& path, std::string_view what);

}  // namespace pnp::robot::json_fields
