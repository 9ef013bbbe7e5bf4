#include "tools/common/cli.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <system_error>

#include "common/error.h"
#include "common/version.h"

namespace pnp::tools {

int run_tool(CLI::App& app, int argc, char** argv, const std::function<void()>& body) {
  add_version_flag(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is a parse "error" that exits 0
  }
  try {
    body();
    return 0;
  } catch (const pnp::Error& e) {
    std::fprintf(stderr, "%s: error: %s\n", app.get_name().c_str(), e.what());
    return e.code() == ErrorCode::kInvalidArgument ? 2 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", app.get_name().c_str(), e.what());
    return 1;
  }
}

void require_writable_directory(const std::string& dir, const std::string& flag) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error)
    throw_invalid_argument(flag, "a directory this user can write",
                           dir + " (" + error.message() + ")");
  // The only sure test of writing is to write: a file made and removed at once.
  const std::string probe = dir + "/.pnp-write-check-" + std::to_string(::getpid());
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw_invalid_argument(flag, "a directory this user can write",
                           dir + " (" + std::generic_category().message(errno) + ")");
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

}  // namespace pnp::tools
