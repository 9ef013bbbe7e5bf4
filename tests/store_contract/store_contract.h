#pragma once
// One suite for the Store contract (store/store.h), run against both implementations:
// the SQLite file in the test's process (RunStore) and the same file behind a real
// pnp.store.v1.StoreService on a loopback port, reached through RemoteStore. Each test gets
// a fresh file; `direct()` opens it in-process to do what no client can (damage a blob).

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "common/error.h"
#include "services/common/server_runtime.h"
#include "services/store/checkpoint_chunks.h"
#include "services/store/remote_store.h"
#include "services/store/store_service.h"
#include "store/run_store.h"
#include "store/store.h"
#include "tests/core/store/store_fixture.h"

namespace pnp::store {

enum class Backend { kEmbedded, kRemote };

inline std::string backend_name(const ::testing::TestParamInfo<Backend>& info) {
  return info.param == Backend::kEmbedded ? "Embedded" : "Remote";
}

class StoreContract : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(test->name());
    for (char& c : name)
      if (c == '/') c = '_';
    dir_ = std::filesystem::temp_directory_path() /
           ("pnp_store_contract_" + std::to_string(::getpid()) + "_" + name);
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "pnp.db").string();
    if (GetParam() == Backend::kRemote) {
      // The contract is about storage: any bytes are a checkpoint here. The server's own
      // check (rl::probe_checkpoint) is pinned by store_service_test.
      service_ = std::make_unique<services::StoreServiceImpl>(
          path_, [](std::string_view, std::span<const std::uint8_t>, std::string_view) {});
      server_ = std::make_unique<services::ServerRuntime>(
          services::ServerConfig{.address = "127.0.0.1:0",
                                 .max_message_bytes = pnp::services::kStoreMessageBytes,
                                 .services = {service_.get()},
                                 .service_names = {"pnp.store.v1.StoreService"},
                                 .metrics = nullptr,
                                 .metrics_address = {},
                                 .security = {},
                                 .log_name = "store"});
      address_ = "127.0.0.1:" + std::to_string(server_->port());
    }
  }

  void TearDown() override {
    if (server_) {
      service_->stop_watches();
      server_->shutdown(std::chrono::milliseconds(500));
    }
    server_.reset();
    service_.reset();
    std::filesystem::remove_all(dir_);
  }

  // A new handle on the test's store (one per thread).
  std::unique_ptr<Store> open() {
    if (GetParam() == Backend::kEmbedded) return std::make_unique<RunStore>(path_);
    return std::make_unique<services::RemoteStore>(
        grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(),
                                  services::store_channel_arguments()),
        address_);
  }
  // The file itself, in this process, whatever the backend.
  RunStore direct() { return RunStore(path_); }

  static RunSpec spec(const std::string& role = "approach") { return test_spec(role); }
  static ErrorCode code_of(const std::function<void()>& f) { return error_code_of(f); }

  std::filesystem::path dir_;
  std::string path_;
  std::string address_;
  std::unique_ptr<services::StoreServiceImpl> service_;
  std::unique_ptr<services::ServerRuntime> server_;
};

}  // namespace pnp::store
