#pragma once
// The audit trail of a server that holds no file (--store): its audited calls are appended
// to pnp-store-server's trail (StoreService.AppendAudit, in the writer thread's batches),
// and an operator reads them back from there (pnpctl audit --store).

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "services/common/transport_security.h"
#include "store/audit_trail.h"
#include "store/records.h"

namespace pnp::services {

// A trail whose batches go to the store server at `address`, dialled with `tls`; failures
// are logged as `service`'s audit_write_failed events (the JSON log keeps every record).
std::unique_ptr<store::AuditTrail> open_remote_audit_trail(const std::string& address,
                                                           const ClientTlsFiles& tls,
                                                           std::string_view service);

// The records with ts_ms >= since_ms, oldest first, the newest `limit` of them.
std::vector<store::AuditRecord> read_remote_audit(const std::string& address,
                                                  const ClientTlsFiles& tls, store::Millis since_ms,
                                                  int limit);

}  // namespace pnp::services
