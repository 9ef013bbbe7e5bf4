#pragma once
// The binary container every checkpoint uses: a magic, a format version, named sections
// of bytes, and an FNV-1a 64 checksum of everything before it. A truncated, corrupted or
// foreign file is refused with a DATA_LOSS error that says what is wrong; nothing is
// half-read.

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/checksum.h"

namespace pnp::nn {

inline constexpr std::uint32_t kCheckpointFormatVersion = 1;

using pnp::fnv1a64;

class CheckpointWriter {
 public:
  void add(const std::string& name, std::span<const std::uint8_t> bytes);
  void add_floats(const std::string& name, std::span<const float> values);
  void add_doubles(const std::string& name, std::span<const double> values);
  void add_text(const std::string& name, std::string_view text);
  std::vector<std::uint8_t> finish() const;  // the serialised file

 private:
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> sections_;
};

class CheckpointReader {
 public:
  // Validates magic, version, structure and checksum up front.
  explicit CheckpointReader(std::span<const std::uint8_t> file);

  bool has(const std::string& name) const { return sections_.count(name) != 0; }
  std::span<const std::uint8_t> bytes(const std::string& name) const;
  std::vector<float> floats(const std::string& name, std::size_t expected_count) const;
  std::vector<double> doubles(const std::string& name, std::size_t expected_count) const;
  std::string text(const std::string& name) const;

 private:
  std::map<std::string, std::vector<std::uint8_t>> sections_;
};

std::vector<std::uint8_t> read_file(const std::string& path);
// Writes to path.tmp then renames, so a crash never leaves a half-written checkpoint.
void write_file_atomically(const std::string& path, std::span<const std::uint8_t> bytes);

}  // namespace pnp::nn
