// The audit trail's writer: batches small enough to travel as one request, a failing sink
// retried until it recovers (nothing lost, nothing written twice), and a sink that never
// recovers reported once its retry budget is spent, without blocking the caller.
#include "store/audit_trail.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>

#include "common/error.h"

namespace pnp::store {
namespace {

using namespace std::chrono_literals;

AuditRecord record(int k, std::size_t request_bytes = 10) {
  return {0,
          1000 + k,
          "inference",
          "ops",
          "ipv4:127.0.0.1:1",
          "/pnp.policy.v1.PolicyService/X",
          std::string(request_bytes, 'r'),
          "OK"};
}

// A sink that fails its first `failures` calls, then keeps every batch it is given.
struct FlakySink {
  int failures = 0;
  std::mutex mutex;
  std::vector<std::vector<AuditRecord>> batches;
  int calls = 0;

  AuditSinkOpener opener() {
    return [this]() -> AuditSink {
      return [this](const std::vector<AuditRecord>& batch) {
        const std::lock_guard lock(mutex);
        if (calls++ < failures) throw Error(ErrorCode::kUnavailable, "store server restarting");
        batches.push_back(batch);
      };
    };
  }
};

TEST(AuditTrail, BatchesStayUnderTheSizeOneRequestCarries) {
  FlakySink sink;
  {
    AuditTrail trail(sink.opener(), "test", nullptr);
    for (int k = 0; k < 300; ++k) trail.append(record(k, 2048));
    trail.flush();
  }
  std::size_t total = 0;
  for (const auto& batch : sink.batches) {
    std::size_t bytes = 0;
    for (const auto& r : batch) bytes += r.request.size();
    EXPECT_LT(bytes, 256u << 10) << "a batch of " << batch.size() << " records";
    total += batch.size();
  }
  EXPECT_EQ(total, 300u);
  EXPECT_GT(sink.batches.size(), 1u);
}

TEST(AuditTrail, AFailingSinkIsRetriedUntilItRecoversAndNothingIsLostOrRepeated) {
  FlakySink sink;
  sink.failures = 3;
  std::vector<std::string> reports;
  AuditTrail trail(sink.opener(), "test", [&](const std::string& r) { reports.push_back(r); });
  for (int k = 0; k < 5; ++k) trail.append(record(k));
  trail.flush();
  EXPECT_TRUE(reports.empty()) << reports.front();
  std::vector<Millis> seen;
  for (const auto& batch : sink.batches)
    for (const auto& r : batch) seen.push_back(r.ts_ms);
  EXPECT_EQ(seen, (std::vector<Millis>{1000, 1001, 1002, 1003, 1004}));
}

TEST(AuditTrail, ASinkThatNeverRecoversIsReportedOnceItsBudgetIsSpent) {
  FlakySink sink;
  sink.failures = 1'000'000;
  std::vector<std::string> reports;
  AuditTrail trail(
      sink.opener(), "the store server 127.0.0.1:1",
      [&](const std::string& r) { reports.push_back(r); }, 100, 300ms);
  trail.append(record(0));  // never blocks
  trail.flush();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("1 audit record(s) not written to the store server 127.0.0.1:1"),
            std::string::npos)
      << reports[0];
  EXPECT_NE(reports[0].find("restarting"), std::string::npos) << reports[0];
  EXPECT_GT(sink.calls, 1) << "given up without a retry";
}

}  // namespace
}  // namespace pnp::store
