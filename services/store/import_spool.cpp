#include "services/store/import_spool.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>

#include "common/error.h"
#include "services/common/tcp_listener.h"

namespace pnp::services {

namespace {

[[noreturn]] void fail(ErrorCode code, const std::string& what, const std::string& path) {
  throw Error(code, "import spool " + path + ": " + what + ": " + errno_text(errno));
}

}  // namespace

ImportSpool::ImportSpool(const std::string& beside) {
  std::string name = beside + ".import-XXXXXX";
  fd_ = ::mkstemp(name.data());  // O_EXCL, mode 0600
  if (fd_ < 0) fail(ErrorCode::kUnavailable, "cannot create", name);
  path_ = std::move(name);
}

ImportSpool::~ImportSpool() {
  ::close(fd_);
  ::unlink(path_.c_str());
}

ImportSpool::Segment ImportSpool::write(std::span<const std::uint8_t> blob) {
  const Segment segment{end_, static_cast<std::int64_t>(blob.size())};
  std::size_t done = 0;
  while (done < blob.size()) {
    const ssize_t n = ::pwrite(fd_, blob.data() + done, blob.size() - done,
                               static_cast<off_t>(end_) + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(ErrorCode::kUnavailable, "cannot write", path_);
    done += static_cast<std::size_t>(n);
  }
  end_ += segment.size;
  return segment;
}

std::vector<std::uint8_t> ImportSpool::read(Segment segment) const {
  if (segment.offset < 0 || segment.size < 0 || segment.offset + segment.size > end_)
    throw Error(ErrorCode::kInternal, "import spool " + path_ + ": no such segment");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(segment.size));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::pread(fd_, bytes.data() + done, bytes.size() - done,
                              static_cast<off_t>(segment.offset) + static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(ErrorCode::kDataLoss, "cannot read back", path_);
    done += static_cast<std::size_t>(n);
  }
  return bytes;
}

}  // namespace pnp::services
