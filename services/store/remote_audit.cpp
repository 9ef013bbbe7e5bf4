#include "services/store/remote_audit.h"

#include <algorithm>
#include <chrono>

#include "pnp/store/v1/store_service.grpc.pb.h"
#include "services/common/security_flags.h"
#include "services/common/status.h"
#include "services/store/remote_store.h"
#include "services/store/store_convert.h"

namespace pnp::services {
namespace {

constexpr auto kCallTimeout = std::chrono::seconds(10);
constexpr std::size_t kAppendBytes = 256 << 10;
constexpr int kReadPage = 10'000;  // the service's largest limit

std::shared_ptr<store_v1::StoreService::Stub> stub_for(const std::string& address,
                                                       const ClientTlsFiles& tls) {
  return store_v1::StoreService::NewStub(dial_store(address, tls));
}

void set_deadline(grpc::ClientContext& context) {
  context.set_deadline(std::chrono::system_clock::now() + kCallTimeout);
}

}  // namespace

std::unique_ptr<store::AuditTrail> open_remote_audit_trail(const std::string& address,
                                                           const ClientTlsFiles& tls,
                                                           std::string_view service) {
  std::shared_ptr<store_v1::StoreService::Stub> stub = stub_for(address, tls);
  store::AuditSinkOpener open = [stub, address]() -> store::AuditSink {
    return [stub, address](const std::vector<store::AuditRecord>& batch) {
      // In requests of at most 256 KiB (the service caps messages at 512 KiB), in order.
      store_v1::AppendAuditRequest request;
      const auto send = [&] {
        grpc::ClientContext context;
        set_deadline(context);
        store_v1::AppendAuditResponse response;
        throw_if_error(stub->AppendAudit(&context, request, &response), "store service AppendAudit",
                       address);
        request.Clear();
      };
      for (const store::AuditRecord& record : batch) {
        to_proto(record, *request.add_records());
        if (request.ByteSizeLong() >= kAppendBytes) send();
      }
      if (request.records_size() > 0) send();
    };
  };
  return std::make_unique<store::AuditTrail>(std::move(open), "the store server " + address,
                                             audit_failure_report(service));
}

std::vector<store::AuditRecord> read_remote_audit(const std::string& address,
                                                  const ClientTlsFiles& tls, store::Millis since_ms,
                                                  int limit) {
  const auto stub = stub_for(address, tls);
  // Pages from the newest back, each oldest first, until `limit` or the start.
  std::vector<store::AuditRecord> out;
  store_v1::ReadAuditRequest request;
  request.set_since_ms(since_ms);
  for (int remaining = limit;;) {
    const int ask = std::min(remaining, kReadPage);
    request.set_limit(ask);
    grpc::ClientContext context;
    set_deadline(context);
    store_v1::ReadAuditResponse response;
    throw_if_error(stub->ReadAudit(&context, request, &response), "store service ReadAudit",
                   address);
    std::vector<store::AuditRecord> page;
    for (const auto& entry : response.records()) page.push_back(from_proto(entry));
    remaining -= static_cast<int>(page.size());
    out.insert(out.begin(), page.begin(), page.end());
    if (page.empty() || remaining <= 0) break;
    if (!response.more() && static_cast<int>(page.size()) < ask) break;  // the start reached
    request.set_before_id(page.front().id);
  }
  return out;
}

}  // namespace pnp::services
