#include "store/audit_trail.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "common/error.h"
#include "store/retry.h"
#include "store/schema.h"
#include "store/sqlite.h"

namespace pnp::store {
namespace {

constexpr std::size_t kBatch = 256;
// A batch stays under this many bytes of text, so that it travels to the store server as
// one request (its messages are capped at 512 KiB) and is committed there whole.
constexpr std::size_t kBatchBytes = 192 << 10;
// A sink that fails (a busy file, a store server restarting) is retried with backoff (for
// the trail's retry budget) before the batch is given up and reported.
constexpr auto kFirstBackoff = std::chrono::milliseconds(200);
constexpr auto kMaxBackoff = std::chrono::seconds(5);

std::size_t text_bytes(const AuditRecord& r) {
  return 72 + r.service.size() + r.principal.size() + r.peer.size() + r.rpc.size() +
         r.request.size() + r.code.size() + r.recorded_by.size();
}

void insert(Database& db, const std::vector<AuditRecord>& batch) {
  Transaction tx(db);
  auto st = db.prepare(
      "INSERT INTO audit (ts_ms, service, principal, peer, rpc, request, code, recorded_by, "
      "received_ms) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (const AuditRecord& r : batch) {
    st.reset();
    st.bind(1, r.ts_ms)
        .bind(2, r.service)
        .bind(3, r.principal)
        .bind(4, r.peer)
        .bind(5, r.rpc)
        .bind(6, r.request)
        .bind(7, r.code)
        .bind(8, r.recorded_by)
        .bind(9, r.received_ms != 0 ? r.received_ms : r.ts_ms);
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
                       std::size_t capacity, std::chrono::milliseconds retry_budget)
    : open_(std::move(open)),
      destination_(std::move(destination)),
      report_(std::move(report)),
      capacity_(capacity),
      retry_budget_(retry_budget) {
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
      std::size_t bytes = 0;
      while (!queue_.empty() && batch.size() < kBatch &&
             (batch.empty() || bytes + text_bytes(queue_.front()) <= kBatchBytes)) {
        bytes += text_bytes(queue_.front());
        batch.push_back(std::move(queue_.front()));
        queue_.pop_front();
      }
    }
    commit(sink, batch, stop);
    {
      std::lock_guard lock(mutex_);
      done_ += batch.size();
    }
    written_.notify_all();
  }
}

void AuditTrail::commit(AuditSink& sink, const std::vector<AuditRecord>& batch,
                        const std::stop_token& stop) {
  const auto give_up = std::chrono::steady_clock::now() + retry_budget_;
  std::chrono::milliseconds backoff = kFirstBackoff;
  for (;;) {
    try {
      if (!sink) sink = open_();
      sink(batch);
      return;
    } catch (const std::exception& e) {
      sink = nullptr;  // opened afresh for the next attempt
      if (stop.stop_requested() || std::chrono::steady_clock::now() + backoff > give_up) {
        if (report_) {  // the JSON log still has them
          report_(std::to_string(batch.size()) + " audit record(s) not written to " + destination_ +
                  ": " + e.what());
        }
        return;
      }
    }
    std::unique_lock lock(mutex_);
    wake_.wait_for(lock, stop, backoff, [] { return false; });  // the backoff, or a stop
    backoff = std::min<std::chrono::milliseconds>(backoff * 2, kMaxBackoff);
  }
}

std::vector<AuditRecord> read_audit(const std::string& path, Millis since_ms, int limit,
                                    std::int64_t before_id) {
  if (limit < 1) throw_invalid_argument("limit", "at least 1", std::to_string(limit));
  Database db(path, {.access = Access::kReadOnly});
  migrate(db);  // read-only: refuses a file this build cannot read
  auto st = db.prepare(
      "SELECT id, ts_ms, service, principal, peer, rpc, request, code, recorded_by, received_ms "
      "FROM audit "
      "WHERE ts_ms >= ? AND (? = 0 OR id < ?) ORDER BY id DESC LIMIT ?");
  st.bind(1, since_ms)
      .bind(2, before_id)
      .bind(3, before_id)
      .bind(4, static_cast<std::int64_t>(limit));
  std::vector<AuditRecord> out;
  while (st.step()) {
    out.push_back({st.column_int(0), st.column_int(1), st.column_text(2), st.column_text(3),
                   st.column_text(4), st.column_text(5), st.column_text(6), st.column_text(7),
                   st.column_text(8), st.column_int(9)});
  }
  std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace pnp::store
