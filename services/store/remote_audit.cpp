#include "services/store/remote_audit.h"

#include <chrono>

#include "pnp/store/v1/store_service.grpc.pb.h"
#include "services/common/address.h"
#include "services/common/server_runtime.h"
#include "services/common/status.h"
#include "services/store/remote_store.h"
#include "services/store/store_convert.h"

namespace pnp::services {
namespace {

constexpr auto kCallTimeout = std::chrono::seconds(10);

std::shared_ptr<store_v1::StoreService::Stub> stub_for(const std::string& address,
                                                       const ClientTlsFiles& tls) {
  validate_address(address, "--store");  // the flag every caller takes it from
  return store_v1::StoreService::NewStub(dial(address, tls, store_channel_arguments()));
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
      store_v1::AppendAuditRequest request;
      for (const store::AuditRecord& record : batch) to_proto(record, *request.add_records());
      grpc::ClientContext context;
      set_deadline(context);
      store_v1::AppendAuditResponse response;
      throw_if_error(stub->AppendAudit(&context, request, &response), "store service AppendAudit",
                     address);
    };
  };
  return std::make_unique<store::AuditTrail>(
      std::move(open), "the store server " + address,
      [service = std::string(service)](const std::string& problem) {
        log_event(service, "audit_write_failed", {{"error", problem}});
      });
}

std::vector<store::AuditRecord> read_remote_audit(const std::string& address,
                                                  const ClientTlsFiles& tls, store::Millis since_ms,
                                                  int limit) {
  const auto stub = stub_for(address, tls);
  store_v1::ReadAuditRequest request;
  request.set_since_ms(since_ms);
  request.set_limit(limit);
  grpc::ClientContext context;
  set_deadline(context);
  store_v1::ReadAuditResponse response;
  throw_if_error(stub->ReadAudit(&context, request, &response), "store service ReadAudit", address);
  std::vector<store::AuditRecord> out;
  for (const auto& entry : response.records()) out.push_back(from_proto(entry));
  return out;
}

}  // namespace pnp::services
