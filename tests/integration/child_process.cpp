#include "tests/integration/child_process.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <thread>

extern char** environ;

namespace pnp::integration {
namespace {

using Clock = std::chrono::steady_clock;

// A file descriptor, closed when it goes out of scope.
class UniqueFd {
 public:
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd() { reset(); }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;
  int get() const { return fd_; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

UniqueFd open_for_child(const std::filesystem::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw std::system_error(errno, std::generic_category(), "cannot open " + path.string());
  }
  return UniqueFd(fd);
}

// The parent's environment with `overrides` replacing or adding entries.
std::vector<std::string> child_environment(
    const std::vector<std::pair<std::string, std::string>>& overrides) {
  std::set<std::string> replaced;
  for (const auto& [name, value] : overrides) replaced.insert(name);
  std::vector<std::string> out;
  for (char** entry = environ; *entry != nullptr; ++entry) {
    const std::string_view text(*entry);
    if (!replaced.contains(std::string(text.substr(0, text.find('='))))) out.emplace_back(text);
  }
  for (const auto& [name, value] : overrides) out.push_back(name + "=" + value);
  return out;
}

std::vector<char*> pointers(std::vector<std::string>& strings) {
  std::vector<char*> out;
  out.reserve(strings.size() + 1);
  for (auto& s : strings) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

// In the child between fork and exec: async-signal-safe calls only. Reports exec's errno
// on `status_fd` (close-on-exec, so a successful exec just closes it).
[[noreturn]] void exec_child(char** argv, char** envp, int in, int out, int err, int status_fd,
                             pid_t parent, const char* working_dir) {
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  for (int sig : {SIGPIPE, SIGTERM, SIGINT}) ::signal(sig, SIG_DFL);
  // Killed with the test if the test itself dies (a crash or ctest's timeout).
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(126);
  if (::dup2(in, STDIN_FILENO) < 0 || ::dup2(out, STDOUT_FILENO) < 0 ||
      ::dup2(err, STDERR_FILENO) < 0)
    ::_exit(126);
  if (working_dir && ::chdir(working_dir) != 0) ::_exit(126);
  ::execve(argv[0], argv, envp);
  const int error = errno;
  [[maybe_unused]] const ssize_t written = ::write(status_fd, &error, sizeof error);
  ::_exit(127);
}

}  // namespace

std::string ExitStatus::describe() const {
  if (exited) return "exit " + std::to_string(code);
  if (signal != 0) return "signal " + std::to_string(signal);
  return "unknown";
}

ChildProcess::ChildProcess(std::string name, std::vector<std::string> args,
                           const std::filesystem::path& log_dir,
                           const std::vector<std::pair<std::string, std::string>>& env,
                           const std::filesystem::path& working_dir)
    : name_(std::move(name)),
      stdout_path_(log_dir / (name_ + ".stdout")),
      stderr_path_(log_dir / (name_ + ".stderr")) {
  if (args.empty()) throw std::invalid_argument("ChildProcess " + name_ + ": no program");
  // Everything the child needs is built before fork.
  std::vector<char*> argv = pointers(args);
  std::vector<std::string> environment = child_environment(env);
  std::vector<char*> envp = pointers(environment);
  const UniqueFd in = open_for_child("/dev/null", O_RDONLY);
  const UniqueFd out = open_for_child(stdout_path_, O_WRONLY | O_CREAT | O_TRUNC);
  const UniqueFd err = open_for_child(stderr_path_, O_WRONLY | O_CREAT | O_TRUNC);
  int status_pipe[2];
  if (::pipe2(status_pipe, O_CLOEXEC) != 0)
    throw std::system_error(errno, std::generic_category(), "pipe2");
  UniqueFd status_read(status_pipe[0]);
  UniqueFd status_write(status_pipe[1]);
  const pid_t parent = ::getpid();
  const std::string cwd = working_dir.string();
  pid_ = ::fork();
  if (pid_ < 0) throw std::system_error(errno, std::generic_category(), "fork");
  if (pid_ == 0)
    exec_child(argv.data(), envp.data(), in.get(), out.get(), err.get(), status_write.get(), parent,
               cwd.empty() ? nullptr : cwd.c_str());
  status_write.reset();
  int exec_errno = 0;
  ssize_t got = 0;
  do {
    got = ::read(status_read.get(), &exec_errno, sizeof exec_errno);
  } while (got < 0 && errno == EINTR);
  if (got == static_cast<ssize_t>(sizeof exec_errno)) {  // exec failed
    reap(true);
    pid_ = -1;
    throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(exec_errno));
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !reap(false)) {
    ::kill(pid_, SIGKILL);
    reap(true);
  }
}

bool ChildProcess::reap(bool block) {
  if (status_) return true;
  if (pid_ <= 0) return false;
  int raw = 0;
  pid_t got = 0;
  do {
    got = ::waitpid(pid_, &raw, block ? 0 : WNOHANG);
  } while (got < 0 && errno == EINTR);
  if (got == 0) return false;
  ExitStatus status;
  if (got == pid_ && WIFEXITED(raw)) {
    status.exited = true;
    status.code = WEXITSTATUS(raw);
  } else if (got == pid_ && WIFSIGNALED(raw)) {
    status.signal = WTERMSIG(raw);
  }
  status_ = status;
  return true;
}

bool ChildProcess::running() {
  return pid_ > 0 && !reap(false);
}

void ChildProcess::send_signal(int sig) {
  if (running()) ::kill(pid_, sig);
}

std::optional<ExitStatus> ChildProcess::wait(std::chrono::milliseconds timeout) {
  wait_until([this] { return !running(); }, timeout, 10ms);
  return status_;
}

std::optional<ExitStatus> ChildProcess::terminate_and_wait(std::chrono::milliseconds timeout) {
  terminate();
  auto status = wait(timeout);
  if (!status) {
    kill();
    reap(true);
  }
  return status;
}

int ChildProcess::port(std::chrono::milliseconds timeout) {
  std::string text;
  wait_until(
      [&] {
        text = stdout_text();
        return text.find('\n') != std::string::npos || !running();
      },
      timeout);
  text = stdout_text();  // all of it, had the child printed its line and exited since
  const std::size_t end = text.find('\n');
  if (end == std::string::npos) return 0;
  int port = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + end, port);
  if (ec != std::errc() || ptr != text.data() + end || port <= 0 || port > 65535) return 0;
  return port;
}

std::string ChildProcess::stdout_text() const {
  return read_file(stdout_path_);
}

std::string ChildProcess::stderr_text() const {
  return read_file(stderr_path_);
}

std::string ChildProcess::diagnostics() const {
  constexpr std::size_t kTail = 4000;
  std::string err = stderr_text();
  if (err.size() > kTail) err = "..." + err.substr(err.size() - kTail);
  return name_ + " (pid " + std::to_string(pid_) + ", " +
         (status_ ? status_->describe() : std::string("running")) + "), stderr:\n" + err;
}

TempDir::TempDir(const std::string& name) {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("pnp_it_" + name + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("PNP_KEEP_TEST_DIRS") != nullptr) return;
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string loopback(int port) {
  return "127.0.0.1:" + std::to_string(port);
}

bool wait_until(const std::function<bool()>& done, std::chrono::milliseconds timeout,
                std::chrono::milliseconds poll) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (done()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(poll);
  }
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

}  // namespace pnp::integration
