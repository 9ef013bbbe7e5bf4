#include "services/common/endpoints_file.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>

#include "common/error.h"

namespace pnp::services {
namespace {

constexpr std::uintmax_t kMaxEndpointsFileBytes = 64 * 1024;

nlohmann::json read_endpoints_file(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  if (error) throw Error(ErrorCode::kNotFound, "--endpoints: cannot read " + path);
  if (size > kMaxEndpointsFileBytes) {
    throw_invalid_argument("--endpoints", "a file of at most 64 KiB",
                           path + " of " + std::to_string(size) + " bytes");
  }
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json doc = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!doc.is_object())
    throw_invalid_argument("--endpoints", "a JSON object of service addresses", path);
  return doc;
}

void check_key(const std::string& path, const std::string& key, const nlohmann::json& value) {
  const bool known = std::find(std::begin(kEndpointsFileKeys), std::end(kEndpointsFileKeys), key) !=
                     std::end(kEndpointsFileKeys);
  if (!known) {
    throw_invalid_argument(path + ": " + key,
                           "one of sim, approach, manipulate, retract, hlc, e2e, inference, "
                           "robot_controller, store",
                           "an unknown key");
  }
  if (!value.is_string() || value.get<std::string>().empty())
    throw_invalid_argument(path + ": " + key, "a host:port string", value.dump());
}

}  // namespace

void add_endpoints_file_option(CLI::App& app, std::string& path) {
  app.add_option("--endpoints", path,
                 std::string("JSON file of service addresses, for those no flag or variable "
                             "gives (scripts/run writes ") +
                     kDefaultEndpointsFile + ", read when it exists)")
      ->envname("PNP_ENDPOINTS");
}

std::string apply_endpoints_file(const CLI::App& app, const std::string& path,
                                 std::span<const FileAddress> addresses) {
  std::string file = path;
  if (file.empty()) {
    if (!std::filesystem::exists(kDefaultEndpointsFile)) return {};
    file = kDefaultEndpointsFile;
  }
  const nlohmann::json doc = read_endpoints_file(file);
  for (const auto& [key, value] : doc.items()) {
    check_key(file, key, value);
    for (const FileAddress& a : addresses)
      if (key == a.key && app.get_option(a.flag)->count() == 0) *a.address = value;
  }
  return file;
}

std::string with_endpoints_file_hint(const std::string& file, const std::string& message) {
  if (file.empty()) return message;
  return message + "\n(the addresses came from " + file +
         ": if the platform that wrote it has stopped, start it again with scripts/run, or "
         "give the addresses with flags or PNP_*_ADDRESS)";
}

}  // namespace pnp::services
