#pragma once
// Checkpoint bytes (and backup files) over the store service: sent in chunks small enough
// for any message limit, reassembled with their declared size as a bound, and verified
// against their checksum on arrival at either end (a corrupted or truncated transfer is
// DATA_LOSS, never stored and never handed to a caller).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pnp::services {

inline constexpr std::size_t kCheckpointChunkBytes = 256 * 1024;
// The message size the store service and its clients accept: a chunk and its framing.
inline constexpr int kStoreMessageBytes = static_cast<int>(2 * kCheckpointChunkBytes);
// The largest blob either end of a transfer takes at all; the store server takes at most
// its --max-checkpoint-mb (store/store_quotas.h, 64 MiB by default).
inline constexpr std::int64_t kMaxCheckpointBytes = 1LL << 30;

// Collects one blob's chunks. `what` names the blob in errors ("checkpoint 12").
class BlobAssembler {
 public:
  // INVALID_ARGUMENT naming `size_field` unless 0 < size <= max_bytes, or
  // `checksum_field` unless the checksum is 16 hex digits.
  BlobAssembler(std::string what, std::int64_t size_bytes, std::string checksum,
                std::string_view size_field, std::string_view checksum_field,
                std::int64_t max_bytes = kMaxCheckpointBytes);
  // DATA_LOSS if the chunks would exceed the declared size.
  void append(std::string_view chunk);
  // DATA_LOSS unless the bytes received are the declared size and checksum.
  std::vector<std::uint8_t> take();
  bool complete() const { return static_cast<std::int64_t>(bytes_.size()) == size_; }

 private:
  std::string what_;
  std::int64_t size_;
  std::string checksum_;
  std::vector<std::uint8_t> bytes_;
};

// Calls `send(chunk)` for consecutive pieces of `blob`, each at most kCheckpointChunkBytes;
// stops early (returning false) when `send` returns false.
template <typename Send>
bool for_each_chunk(std::span<const std::uint8_t> blob, Send&& send) {
  for (std::size_t at = 0; at < blob.size(); at += kCheckpointChunkBytes) {
    const std::size_t n = std::min(kCheckpointChunkBytes, blob.size() - at);
    if (!send(std::string_view(reinterpret_cast<const char*>(blob.data() + at), n))) return false;
  }
  return true;
}

// The FNV-1a 64 of a whole file, read piece by piece.
std::uint64_t file_checksum(const std::string& path);

// Calls `send(chunk)` for consecutive pieces of the file at `path`, each at most
// kCheckpointChunkBytes; false if `send` stopped it. NOT_FOUND if it cannot be read.
bool for_each_file_chunk(const std::string& path,
                         const std::function<bool(std::string_view)>& send);

// Removes a file when it goes out of scope (a backup copy once sent).
class TemporaryFile {
 public:
  explicit TemporaryFile(std::string path) : path_(std::move(path)) {}
  ~TemporaryFile();
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

 private:
  std::string path_;
};

}  // namespace pnp::services
