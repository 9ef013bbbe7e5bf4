#pragma once
// The store tests' fixture: a fresh database file per test, removed afterwards (with its
// WAL files), a run spec, and the error code a call throws (also used by the Store
// contract suite, tests/store_contract/).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

#include "common/error.h"
#include "store/records.h"

namespace pnp::store {

// A run spec of `role`, as the store tests create runs.
inline RunSpec test_spec(const std::string& role = "approach") {
  RunSpec s;
  s.role = role;
  s.algorithm = role == "hlc" ? "a3c" : "ddpg_her";
  s.robot = "fetch";
  s.object = "block";
  s.seed = 7;
  s.config_json = R"({"batch_size":256})";
  s.code_commit = "abc123";
  return s;
}

// The code of the pnp::Error `f` throws (a test failure if it throws none).
inline ErrorCode error_code_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "no error";
  return ErrorCode::kInternal;
}

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("pnp_store_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "pnp.db").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  static RunSpec spec(const std::string& role = "approach") { return test_spec(role); }
  static ErrorCode code_of(const std::function<void()>& f) { return error_code_of(f); }

  std::filesystem::path dir_;
  std::string path_;
};

}  // namespace pnp::store
