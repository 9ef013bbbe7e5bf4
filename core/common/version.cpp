#include "common/version.h"

#include "build_info.h"

namespace pnp {

std::string_view release_version() {
  return kReleaseVersion;
}

std::string_view build_commit() {
  return kCodeCommit;
}

std::string version_text(std::string_view program) {
  return std::string(program) + " " + std::string(release_version()) + " (commit " +
         std::string(build_commit()) + ")";
}

void add_version_flag(CLI::App& app) {
  app.set_version_flag("--version", version_text(app.get_name()),
                       "print the release and the commit this program was built from");
}

}  // namespace pnp
