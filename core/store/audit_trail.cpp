#include "store/audit_trail.h"

#include <algorithm>
#include <memory>

#include "common/error.h"
#include "store/retry.h"
#include "store/schema.h"
#include "store/sqlite.h"

namespace pnp::store {
namespace {

constexpr std::size_t kBatch = 256;

void insert(Database& db, const std::vector<AuditRecord>& batch) {
  Transaction tx(db);
  auto st = db.prepare(
      "INSERT INTO audit (ts_ms, service, principal, peer, rpc, request, code) "
      "VALUES (?, ?, ?, ?, ?, ?, ?)");
  for (const AuditRecord& r : batch) {
    st.reset();
    st.bind(1, r.ts_ms)
        .bind(2, r.service)
        .bind(3, r.principal)
        .bind(4, r.peer)
        .bind(5, r.rpc)
        .bind(6, r.request)
        .bind(7, r.code);
    st.run();
  }
  tx.commit();
}

}  // namespace

AuditSinkOpener file_audit_sink(std::string path) {
  return [path = std::move(path)]() -> AuditSink {
    auto db = std::make_shared<Database>(path);
    migrate(*db);
    return [db, retry = RetryPolicy{}](const std::vector<AuditRecord>& batch) {
      with_retry(retry, [&] { insert(*db, batch); });
    };
  };
}

AuditTrail::AuditTrail(std::string path, Report report, std::size_t capacity)
    : AuditTrail(file_audit_sink(path), path, std::move(report), capacity) {}

AuditTrail::AuditTrail(AuditSinkOpener open, std::string destination, Report report,
                       std::size_t capacity)
    : open_(std::move(open)),
      destination_(std::move(destination)),
      report_(std::move(report)),
      capacity_(capacity) {
  if (capacity_ == 0) throw_invalid_argument("capacity", "at least 1 record", "0");
  writer_ = std::jthread([this](std::stop_token stop) { write_loop(stop); });
}

AuditTrail::~AuditTrail() {
  writer_.request_stop();
  wake_.notify_all();
}

void AuditTrail::append(AuditRecord record) {
  {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= capacity_) {
      ++dropped_;
      return;
    }
    queue_.push_back(std::move(record));
    ++appended_;
  }
  wake_.notify_all();
}

void AuditTrail::flush() {
  std::unique_lock lock(mutex_);
  const std::uint64_t target = appended_;
  written_.wait(lock, [&] { return done_ >= target; });
}

std::uint64_t AuditTrail::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

void AuditTrail::write_loop(const std::stop_token& stop) {
  AuditSink sink;
  for (;;) {
    std::vector<AuditRecord> batch;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, stop, [&] { return !queue_.empty(); });
      if (queue_.empty()) return;  // stopped with nothing left to write
      while (!queue_.empty() && batch.size() < kBatch) {
        batch.push_back(std::move(queue_.front()));
        queue_.pop_front();
      }
    }
    try {
      if (!sink) sink = open_();
      sink(batch);
    } catch (const std::exception& e) {  // the JSON log still has them
      sink = nullptr;                    // opened afresh for the next batch
      if (report_) {
        report_(std::to_string(batch.size()) + " audit record(s) not written to " + destination_ +
                ": " + e.what());
      }
    }
    {
      std::lock_guard lock(mutex_);
      done_ += batch.size();
    }
    written_.notify_all();
  }
}

std::vector<AuditRecord> read_audit(const std::string& path, Millis since_ms, int limit) {
  if (limit < 1) throw_invalid_argument("limit", "at least 1", std::to_string(limit));
  Database db(path, {.access = Access::kReadOnly});
  migrate(db);  // read-only: refuses a file this build cannot read
  auto st = db.prepare(
      "SELECT id, ts_ms, service, principal, peer, rpc, request, code FROM audit "
      "WHERE ts_ms >= ? ORDER BY id DESC LIMIT ?");
  st.bind(1, since_ms).bind(2, static_cast<std::int64_t>(limit));
  std::vector<AuditRecord> out;
  while (st.step()) {
    out.push_back({st.column_int(0), st.column_int(1), st.column_text(2), st.column_text(3),
                   st.column_text(4), st.column_text(5), st.column_text(6), st.column_text(7)});
  }
  std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace pnp::store
