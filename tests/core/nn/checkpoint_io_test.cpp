#include "nn/checkpoint_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "common/error.h"

namespace pnp::nn {
namespace {

std::vector<std::uint8_t> sample_file() {
  CheckpointWriter w;
  w.add_text("config", "{\"role\":\"approach\"}");
  const std::vector<float> weights{1.5f, -2.0f, 3.25f};
  w.add_floats("actor", weights);
  const std::vector<double> stats{0.1, 0.2};
  w.add_doubles("obs_sum", stats);
  return w.finish();
}

ErrorCode refusal_code(std::span<const std::uint8_t> bytes, std::string* message = nullptr) {
  try {
    CheckpointReader r(bytes);
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  return ErrorCode::kInternal;
}

TEST(Checkpoint, RoundTrip) {
  const auto file = sample_file();
  CheckpointReader r(file);
  EXPECT_EQ(r.text("config"), "{\"role\":\"approach\"}");
  EXPECT_EQ(r.floats("actor", 3), (std::vector<float>{1.5f, -2.0f, 3.25f}));
  EXPECT_EQ(r.doubles("obs_sum", 2), (std::vector<double>{0.1, 0.2}));
}

TEST(Checkpoint, EveryFlippedByteIsDetected) {
  const auto file = sample_file();
  for (std::size_t i = 0; i < file.size(); ++i) {
    auto bad = file;
    bad[i] ^= 0x40;
    EXPECT_EQ(refusal_code(bad), ErrorCode::kDataLoss) << "byte " << i;
  }
}

TEST(Checkpoint, EveryTruncationIsDetected) {
  const auto file = sample_file();
  for (std::size_t n = 0; n < file.size(); ++n) {
    EXPECT_EQ(refusal_code(std::span(file).first(n)), ErrorCode::kDataLoss) << "length " << n;
  }
}

TEST(Checkpoint, WrongSectionSizeOrMissingSectionIsRefused) {
  const auto file = sample_file();
  CheckpointReader r(file);
  EXPECT_THROW(r.floats("actor", 4), Error);
  try {
    r.bytes("critic");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
    EXPECT_STREQ(e.what(), "checkpoint: missing section \"critic\"");
  }
}

TEST(Checkpoint, ForeignFileIsRefusedNamingTheProblem) {
  std::vector<std::uint8_t> png(64, 0x89);
  std::string message;
  EXPECT_EQ(refusal_code(png, &message), ErrorCode::kDataLoss);
  EXPECT_EQ(message, "checkpoint: not a pnp checkpoint (bad magic)");
}

TEST(Checkpoint, AtomicWriteLeavesNoTemporary) {
  const auto dir = std::filesystem::temp_directory_path() / "pnp_ckpt_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "a.ckpt").string();
  write_file_atomically(path, sample_file());
  EXPECT_EQ(read_file(path), sample_file());
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pnp::nn
