#include "services/store/checkpoint_chunks.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "common/checksum.h"
#include "common/error.h"

namespace pnp::services {

BlobAssembler::BlobAssembler(std::string what, std::int64_t size_bytes, std::string checksum,
                             std::string_view size_field, std::string_view checksum_field,
                             std::int64_t max_bytes)
    : what_(std::move(what)), size_(size_bytes), checksum_(std::move(checksum)) {
  if (size_bytes <= 0 || size_bytes > max_bytes) {
    throw_invalid_argument(size_field,
                           "the blob's size, 1 to " + std::to_string(max_bytes) + " bytes",
                           std::to_string(size_bytes));
  }
  const bool hex =
      checksum_.size() == 16 && std::all_of(checksum_.begin(), checksum_.end(), [](char c) {
        return std::isxdigit(static_cast<unsigned char>(c)) != 0;
      });
  if (!hex) {
    throw_invalid_argument(checksum_field, "the blob's FNV-1a 64, 16 hex digits",
                           "\"" + checksum_ + "\"");
  }
  std::transform(checksum_.begin(), checksum_.end(), checksum_.begin(), [](char c) {
    return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  });
  // What the caller declared is only a bound: memory grows with the bytes that arrive.
  constexpr std::int64_t kReserveAtMost = 16 << 20;
  bytes_.reserve(static_cast<std::size_t>(std::min(size_bytes, kReserveAtMost)));
}

void BlobAssembler::append(std::string_view chunk) {
  if (static_cast<std::int64_t>(bytes_.size() + chunk.size()) > size_) {
    throw Error(ErrorCode::kDataLoss,
                what_ + ": more bytes arrived than the declared " + std::to_string(size_));
  }
  bytes_.insert(bytes_.end(), chunk.begin(), chunk.end());
}

std::vector<std::uint8_t> BlobAssembler::take() {
  if (!complete()) {
    throw Error(ErrorCode::kDataLoss, what_ + ": " + std::to_string(bytes_.size()) +
                                          " bytes arrived of the declared " +
                                          std::to_string(size_));
  }
  const std::string actual = fnv1a64_hex(bytes_);
  if (actual != checksum_) {
    throw Error(ErrorCode::kDataLoss, what_ + ": the bytes that arrived have checksum " + actual +
                                          ", not the declared " + checksum_);
  }
  return std::move(bytes_);
}

std::uint64_t file_checksum(const std::string& path) {
  std::uint64_t checksum = kFnv1a64Start;
  for_each_file_chunk(path, [&](std::string_view chunk) {
    checksum = fnv1a64(std::span(reinterpret_cast<const std::uint8_t*>(chunk.data()), chunk.size()),
                       checksum);
    return true;
  });
  return checksum;
}

bool for_each_file_chunk(const std::string& path,
                         const std::function<bool(std::string_view)>& send) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, "cannot read " + path);
  std::string buffer(kCheckpointChunkBytes, '\0');
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got == 0) break;
    if (!send(std::string_view(buffer.data(), got))) return false;
  }
  return true;
}

TemporaryFile::~TemporaryFile() {
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

}  // namespace pnp::services
