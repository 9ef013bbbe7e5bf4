// audit: who called which operator or robot RPC, with what, and how it ended, read from a
// store's audit trail (docs/RELIABILITY.md, "Who may do what"): the store file itself,
// read-only (like gc: the trail is for whoever holds the store), or through pnp-store-server
// as an operator (ReadAudit).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "clients/pnpctl/commands.h"
#include "clients/pnpctl/since_arg.h"
#include "clients/pnpctl/table.h"
#include "common/error.h"
#include "services/store/remote_audit.h"
#include "store/audit_trail.h"

namespace pnp::pnpctl {

namespace {

std::vector<store::AuditRecord> read_records(const AuditArgs& args, std::int64_t since) {
  if (args.store.remote())
    return services::read_remote_audit(args.store.address, args.store.tls, since, args.limit);
  if (args.db.empty())
    throw_invalid_argument("--db", "a store file, or --store host:port", "neither");
  if (!std::filesystem::is_regular_file(args.db))
    throw_invalid_argument("--db", "an existing store file", "\"" + args.db + "\" (no such file)");
  return store::read_audit(args.db, since, args.limit);
}

}  // namespace

int audit_command(const AuditArgs& args) {
  const std::int64_t now = std::chrono::duration_cast<std::chrono::milliseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
  const std::int64_t since = args.since.empty() ? 0 : parse_since(args.since, now, "--since");
  const auto records = read_records(args, since);
  if (args.json) {
    for (const store::AuditRecord& r : records) {
      std::printf("%s\n", nlohmann::json{{"id", r.id},
                                         {"time", utc_text(r.ts_ms)},
                                         {"ts_ms", r.ts_ms},
                                         {"service", r.service},
                                         {"principal", r.principal},
                                         {"peer", r.peer},
                                         {"rpc", r.rpc},
                                         {"code", r.code},
                                         {"request", r.request},
                                         {"recorded_by", r.recorded_by},
                                         {"received_ms", r.received_ms}}
                              .dump()
                              .c_str());
    }
    return 0;
  }
  // "recorded by": the server that forwarded the record, as the store authenticated it
  // ("self": written by the server that answered the call).
  Table table({"time", "service", "principal", "rpc", "code", "recorded by", "peer", "request"});
  // A request can be 2 KB of JSON: cut in the table (whole with --wide or --json), at a
  // character boundary.
  constexpr std::size_t kRequestColumn = 48;
  const auto shown = [&](const std::string& request) {
    if (args.wide || request.size() <= kRequestColumn) return request;
    std::size_t cut = kRequestColumn - 3;
    while (cut > 0 && (static_cast<unsigned char>(request[cut]) & 0xC0) == 0x80) --cut;
    return request.substr(0, cut) + "...";
  };
  for (const store::AuditRecord& r : records) {
    // "/pnp.policy.v1.PolicyService/PromoteCheckpoint" -> "PolicyService/PromoteCheckpoint"
    const auto slash = r.rpc.rfind('/');
    const auto dot = r.rpc.rfind('.', slash);
    const std::string rpc = dot == std::string::npos ? r.rpc : r.rpc.substr(dot + 1);
    table.add({utc_text(r.ts_ms), r.service, r.principal.empty() ? "-" : r.principal, rpc, r.code,
               r.recorded_by.empty() ? "self" : r.recorded_by, r.peer, shown(r.request)});
  }
  table.print(stdout);
  return 0;
}

}  // namespace pnp::pnpctl
