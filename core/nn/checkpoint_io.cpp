#include "nn/checkpoint_io.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace pnp::nn {
namespace {

constexpr char kMagic[8] = {'P', 'N', 'P', 'C', 'K', 'P', 'T', '\0'};

[[noreturn]] void data_loss(const std::string& what) {
  throw Error(ErrorCode::kDataLoss, "checkpoint: " + what);
}

template <typename T>
void put(std::vector<std::uint8_t>& out, T value) {
  std::uint8_t raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  out.insert(out.end(), raw, raw + sizeof(T));
}

class Cursor {
 public:
  explicit Cursor(std::span<const std::uint8_t> data) : data_(data) {}
  template <typename T>
  T get(const char* what) {
    if (remaining() < sizeof(T)) data_loss(std::string("truncated while reading ") + what);
    T value;
    std::memcpy(&value, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  std::span<const std::uint8_t> take(std::size_t n, const char* what) {
    if (remaining() < n) data_loss(std::string("truncated while reading ") + what);
    auto s = data_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  std::size_t remaining() const { return data_.size() - pos_; }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
};

template <typename T>
std::span<const std::uint8_t> as_bytes_of(std::span<const T> values) {
  return {reinterpret_cast<const std::uint8_t*>(values.data()), values.size_bytes()};
}

template <typename T>
std::vector<T> decode(std::span<const std::uint8_t> bytes, std::size_t expected,
                      const std::string& name) {
  if (bytes.size() != expected * sizeof(T)) {
    data_loss("section \"" + name + "\" holds " + std::to_string(bytes.size() / sizeof(T)) +
              " values, expected " + std::to_string(expected));
  }
  std::vector<T> out(expected);
  std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

}  // namespace

void CheckpointWriter::add(const std::string& name, std::span<const std::uint8_t> bytes) {
  sections_.emplace_back(name, std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
}
void CheckpointWriter::add_floats(const std::string& name, std::span<const float> values) {
  add(name, as_bytes_of(values));
}
void CheckpointWriter::add_doubles(const std::string& name, std::span<const double> values) {
  add(name, as_bytes_of(values));
}
void CheckpointWriter::add_text(const std::string& name, std::string_view text) {
  add(name, {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
}

std::vector<std::uint8_t> CheckpointWriter::finish() const {
  std::vector<std::uint8_t> out;
  for (char ch : kMagic) out.push_back(static_cast<std::uint8_t>(ch));
  put<std::uint32_t>(out, kCheckpointFormatVersion);
  put<std::uint32_t>(out, static_cast<std::uint32_t>(sections_.size()));
  for (const auto& [name, bytes] : sections_) {
    put<std::uint32_t>(out, static_cast<std::uint32_t>(name.size()));
    out.insert(out.end(), name.begin(), name.end());
    put<std::uint64_t>(out, bytes.size());
    out.insert(out.end(), bytes.begin(), bytes.end());
  }
  put<std::uint64_t>(out, fnv1a64(out));
  return out;
}

CheckpointReader::CheckpointReader(std::span<const std::uint8_t> file) {
  if (file.size() < sizeof(kMagic) + 16) data_loss("file too short to be a checkpoint");
  if (std::memcmp(file.data(), kMagic, sizeof(kMagic)) != 0)
    data_loss("not a pnp checkpoint (bad magic)");
  const auto body = file.first(file.size() - sizeof(std::uint64_t));
  std::uint64_t stored;
  std::memcpy(&stored, file.data() + body.size(), sizeof(stored));
  if (fnv1a64(body) != stored) data_loss("checksum mismatch: the file is corrupted or truncated");
  Cursor cur(body.subspan(sizeof(kMagic)));
  const auto version = cur.get<std::uint32_t>("version");
  if (version != kCheckpointFormatVersion) {
    data_loss("format version " + std::to_string(version) + ", this build reads version " +
              std::to_string(kCheckpointFormatVersion));
  }
  const auto count = cur.get<std::uint32_t>("section count");
  for (std::uint32_t s = 0; s < count; ++s) {
    const auto name_len = cur.get<std::uint32_t>("section name length");
    const auto name_bytes = cur.take(name_len, "section name");
    const auto size = cur.get<std::uint64_t>("section size");
    const auto bytes = cur.take(size, "section body");
    sections_.emplace(std::string(name_bytes.begin(), name_bytes.end()),
                      std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  }
  if (cur.remaining() != 0) data_loss("trailing bytes after the last section");
}

std::span<const std::uint8_t> CheckpointReader::bytes(const std::string& name) const {
  const auto it = sections_.find(name);
  if (it == sections_.end()) data_loss("missing section \"" + name + "\"");
  return it->second;
}
std::vector<float> CheckpointReader::floats(const std::string& name, std::size_t expected) const {
  return decode<float>(bytes(name), expected, name);
}
std::vector<double> CheckpointReader::doubles(const std::string& name, std::size_t expected) const {
  return decode<double>(bytes(name), expected, name);
}
std::string CheckpointReader::text(const std::string& name) const {
  const auto b = bytes(name);
  return {b.begin(), b.end()};
}

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, "cannot open \"" + path + "\"");
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file_atomically(const std::string& path, std::span<const std::uint8_t> bytes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorCode::kFailedPrecondition, "cannot write \"" + tmp + "\"");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) throw Error(ErrorCode::kResourceExhausted, "short write to \"" + tmp + "\"");
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace pnp::nn
