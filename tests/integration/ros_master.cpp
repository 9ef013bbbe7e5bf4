#include "tests/integration/ros_master.h"

#include <regex>
#include <stdexcept>

namespace pnp::integration {
namespace {

std::vector<std::pair<std::string, std::string>> env_for(const std::filesystem::path& dir,
                                                         const std::string& uri) {
  return {{"ROS_MASTER_URI", uri},
          {"ROS_IP", "127.0.0.1"},
          {"ROS_HOSTNAME", "127.0.0.1"},
          {"ROS_HOME", dir.string()},
          {"ROS_LOG_DIR", (dir / "ros_log").string()}};
}

}  // namespace

RosMaster::RosMaster(const std::filesystem::path& dir)
    : dir_(dir),
      process_("rosmaster", {"/usr/bin/rosmaster", "--core", "-p", "0"}, dir,
               env_for(dir, "http://127.0.0.1:0/")) {
  // rosmaster on port 0 names the port it took in its log.
  const std::regex uri(R"(uri\[(http://127\.0\.0\.1:[0-9]+/)\])");
  const bool found = wait_until(
      [&] {
        const std::string log = read_file(dir_ / "ros_log" / "master.log");
        std::smatch match;
        if (!std::regex_search(log, match, uri)) return false;
        uri_ = match[1];
        return true;
      },
      std::chrono::seconds(30));
  if (!found) throw std::runtime_error("rosmaster named no URI within 30 s: " + diagnostics());
}

std::vector<std::pair<std::string, std::string>> RosMaster::node_env() const {
  return env_for(dir_, uri_);
}

}  // namespace pnp::integration
