#pragma once
// Where every client finds the platform when no flag or environment variable gives an
// address (pnpctl, the robot gateway, the dashboard; the Python package reads the same
// file): an endpoints file, a JSON object of service name to host:port. `--endpoints FILE`
// or PNP_ENDPOINTS names one (it must exist); else runs/platform/endpoints.json, which
// scripts/run writes while its services run and removes when they stop, is read when it
// exists. A flag, then its variable, still win over the file.

#include <CLI/CLI.hpp>
#include <map>
#include <span>
#include <string>
#include <utility>

namespace pnp::services {

inline constexpr const char* kDefaultEndpointsFile = "runs/platform/endpoints.json";

// The service names a file may hold, as scripts/run and the Python package write them.
inline constexpr const char* kEndpointsFileKeys[] = {
    "sim", "approach",  "manipulate",       "retract", "hlc",
    "e2e", "inference", "robot_controller", "store"};

// Adds --endpoints (and $PNP_ENDPOINTS) into `path`.
void add_endpoints_file_option(CLI::App& app, std::string& path);

// One address option the file may fill: its flag (as added to the app) and its variable.
struct FileAddress {
  const char* key;   // in the file
  const char* flag;  // e.g. "--inference"
  std::string* address;
};

// After parsing: reads the file `path` names, or the default one when it exists, and sets
// each address whose flag and variable were not given. Returns the file read, or "" for
// none. INVALID_ARGUMENT naming the file and the key for a key that is no service or a
// value that is no address; NOT_FOUND for a named file that cannot be read.
std::string apply_endpoints_file(const CLI::App& app, const std::string& path,
                                 std::span<const FileAddress> addresses);

// `message` with a hint naming `file` (when not empty): its platform may have stopped.
std::string with_endpoints_file_hint(const std::string& file, const std::string& message);

}  // namespace pnp::services
