#pragma once
// The audit trail: who called which operator or robot RPC, with what, and how it ended
// (table `audit`, schema migration 6). Appending never makes the RPC wait for the disk: a
// writer thread commits the records in order, in batches, to a sink: the store file, or
// the store server for a server that holds no file (services/store/remote_audit.h). A
// batch that fails (a busy file, a store server restarting) is retried for 30 s before it
// is given up and reported; a batch whose answer was lost in transit may so be written
// twice. At most `capacity` records wait; beyond that new ones are dropped and counted
// (the services' JSON log has every record regardless).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "store/records.h"

namespace pnp::store {

// Commits one batch, in order, all or nothing; throws on failure.
using AuditSink = std::function<void(const std::vector<AuditRecord>&)>;
// Makes a sink, on the writer thread (again after a batch failed); throws on failure.
using AuditSinkOpener = std::function<AuditSink()>;

// The store file at `path`, created and migrated if needed; a busy store is retried.
AuditSinkOpener file_audit_sink(std::string path);

class AuditTrail {
 public:
  using Report = std::function<void(const std::string&)>;
  // Writes to the store file at `path` (file_audit_sink); `report` hears about records
  // that could not be written.
  AuditTrail(std::string path, Report report, std::size_t capacity = 10'000);
  // Writes to the sinks `open` makes; `destination` names them in reports; a failing batch
  // is retried for `retry_budget`.
  AuditTrail(AuditSinkOpener open, std::string destination, Report report,
             std::size_t capacity = 10'000,
             std::chrono::milliseconds retry_budget = std::chrono::seconds(30));
  ~AuditTrail();  // commits what is queued, then stops
  AuditTrail(const AuditTrail&) = delete;
  AuditTrail& operator=(const AuditTrail&) = delete;

  void append(AuditRecord record);
  // Blocks until every record appended before the call is committed (or failed).
  void flush();
  std::uint64_t dropped() const;

 private:
  void write_loop(const std::stop_token& stop);
  // Commits `batch` through `sink` (reopened when it fails), retrying with backoff.
  void commit(AuditSink& sink, const std::vector<AuditRecord>& batch, const std::stop_token& stop);

  AuditSinkOpener open_;
  std::string destination_;
  Report report_;
  std::size_t capacity_;
  std::chrono::milliseconds retry_budget_;
  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  std::condition_variable written_;
  std::deque<AuditRecord> queue_;
  std::uint64_t appended_ = 0, done_ = 0, dropped_ = 0;
  std::jthread writer_;  // last: stopped and joined before the members it uses go
};

// The records with ts_ms >= since_ms (and, with before_id > 0, an id below it), oldest
// first, at most `limit` (the newest ones).
std::vector<AuditRecord> read_audit(const std::string& path, Millis since_ms, int limit,
                                    std::int64_t before_id = 0);

}  // namespace pnp::store
