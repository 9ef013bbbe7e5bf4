#pragma once
// Child processes for the integration tests: the real binaries, started with fork/exec,
// their stdout and stderr captured to files, killed (SIGKILL) and reaped if still running
// when their owner goes away, so a failing test never leaves a server behind.
//
// A server started with `--address 127.0.0.1:0` prints its port as stdout's first line:
// port() waits for it.

#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace pnp::integration {

using namespace std::chrono_literals;

// How a child ended: exited with `code`, or killed by `signal`.
struct ExitStatus {
  bool exited = false;
  int code = -1;
  int signal = 0;

  bool ok() const { return exited && code == 0; }
  std::string describe() const;  // "exit 0", "signal 9"
};

class ChildProcess {
 public:
  // Starts args[0] (a path) with `args`, in the parent's environment plus `env`
  // (NAME, VALUE; these win), in `working_dir` (empty: the parent's). stdout and stderr go
  // to <log_dir>/<name>.stdout and .stderr. Throws std::runtime_error if the program cannot
  // be started.
  ChildProcess(std::string name, std::vector<std::string> args,
               const std::filesystem::path& log_dir,
               const std::vector<std::pair<std::string, std::string>>& env = {},
               const std::filesystem::path& working_dir = {});
  // SIGKILL and reap if still running.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  const std::string& name() const { return name_; }
  pid_t pid() const { return pid_; }

  // The port printed as stdout's first line; 0 if the child exits or prints none within
  // `timeout` (a failure guard, not an expectation).
  int port(std::chrono::milliseconds timeout = 60s);

  // Sends `sig` (nothing if the child has already been reaped).
  void send_signal(int sig);
  void terminate() { send_signal(SIGTERM); }
  void kill() { send_signal(SIGKILL); }

  // Waits up to `timeout` for the child to end; empty if it is still running then.
  std::optional<ExitStatus> wait(std::chrono::milliseconds timeout);
  // SIGTERM, then wait(timeout); SIGKILL if it is still running then (the result is
  // then empty).
  std::optional<ExitStatus> terminate_and_wait(std::chrono::milliseconds timeout = 60s);
  // Whether it is still running (reaps it if it has ended).
  bool running();

  const std::filesystem::path& stdout_path() const { return stdout_path_; }
  const std::filesystem::path& stderr_path() const { return stderr_path_; }
  std::string stdout_text() const;
  std::string stderr_text() const;
  // Name, pid, state and the end of its stderr, for failure messages.
  std::string diagnostics() const;

 private:
  bool reap(bool block);

  std::string name_;
  pid_t pid_ = -1;
  std::optional<ExitStatus> status_;
  std::filesystem::path stdout_path_, stderr_path_;
};

// A fresh directory under the system's temporary directory, removed with everything in
// it when destroyed (kept when $PNP_KEEP_TEST_DIRS is set, to read the logs).
class TempDir {
 public:
  explicit TempDir(const std::string& name);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// "127.0.0.1:PORT".
std::string loopback(int port);

// Calls `done` every `poll` until it holds or `timeout` has passed; returns its last
// value. The timeout only guards against a hang.
bool wait_until(const std::function<bool()>& done, std::chrono::milliseconds timeout,
                std::chrono::milliseconds poll = 20ms);

// The whole of a (small) file; empty if it cannot be read.
std::string read_file(const std::filesystem::path& path);

}  // namespace pnp::integration
