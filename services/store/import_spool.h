#pragma once
// The checkpoints of one ImportFinished, kept on disk until its transaction commits: an
// import may bring 256 MiB, and holding it in memory until the stream ends let a few
// concurrent imports take the store Pod's whole memory. Each blob arrives whole (it is
// checked as a replica would serve it), is written here and dropped; the commit reads them
// back one at a time. The file lives beside the store (a disk the operator already sizes),
// readable by the server alone, and is removed when the import ends however it ends.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace pnp::services {

class ImportSpool {
 public:
  // Where one blob is in the spool.
  struct Segment {
    std::int64_t offset = 0;
    std::int64_t size = 0;
  };

  // Creates a fresh file named after `beside` (the store's path); UNAVAILABLE if it cannot.
  explicit ImportSpool(const std::string& beside);
  ~ImportSpool();
  ImportSpool(const ImportSpool&) = delete;
  ImportSpool& operator=(const ImportSpool&) = delete;

  // UNAVAILABLE naming the file if the disk refuses (full, read-only).
  Segment write(std::span<const std::uint8_t> blob);
  // DATA_LOSS if the bytes are not all there.
  std::vector<std::uint8_t> read(Segment segment) const;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::int64_t end_ = 0;
};

}  // namespace pnp::services
