#pragma once
// Prometheus metrics: counters, gauges and histograms, each identified by a family name
// and a label set, rendered in the text exposition format 0.0.4. Looking a metric up
// takes a lock and may allocate; the handle it returns lives as long as the registry and
// updates through it are lock-free atomics, so hot paths look up once and keep it.

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace pnp::services {

// Label name -> value; any order (rendered sorted by name), each name at most once.
using Labels = std::vector<std::pair<std::string, std::string>>;

enum class MetricType { kCounter, kGauge, kHistogram };

class Counter {
 public:
  void inc(double amount = 1.0);  // INVALID_ARGUMENT for a negative or NaN amount
  double value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

class Gauge {
 public:
  void set(double value) { value_.store(value, std::memory_order_relaxed); }
  void inc(double amount = 1.0) { value_.fetch_add(amount, std::memory_order_relaxed); }
  void dec(double amount = 1.0) { value_.fetch_sub(amount, std::memory_order_relaxed); }
  double value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

class Histogram {
 public:
  // `bounds`: the buckets' upper bounds, finite and strictly increasing (+Inf is implied).
  explicit Histogram(std::vector<double> bounds);
  void observe(double value);

  const std::vector<double>& bounds() const { return bounds_; }
  // Per bucket, not cumulative; the last one counts values above every bound.
  std::vector<std::uint64_t> bucket_counts() const;
  double sum() const { return sum_.load(std::memory_order_relaxed); }

 private:
  std::vector<double> bounds_;
  std::vector<std::atomic<std::uint64_t>> counts_;  // bounds_.size() + 1, never resized
  std::atomic<double> sum_{0.0};
};

class MetricsRegistry {
 public:
  // The metric of that family and label set, created on first use. INVALID_ARGUMENT for
  // a name or label name outside Prometheus' grammar, a name already registered with
  // another type, help text or buckets, or label names that differ from the family's.
  Counter& counter(std::string_view name, std::string_view help, const Labels& labels = {});
  Gauge& gauge(std::string_view name, std::string_view help, const Labels& labels = {});
  Histogram& histogram(std::string_view name, std::string_view help,
                       const std::vector<double>& bounds, const Labels& labels = {});

  // Text exposition format 0.0.4: families sorted by name, series by label values.
  std::string render() const;

 private:
  using Child =
      std::variant<std::unique_ptr<Counter>, std::unique_ptr<Gauge>, std::unique_ptr<Histogram>>;
  struct Family {
    MetricType type;
    std::string help;
    std::vector<double> bounds;  // histograms only
    std::vector<std::string> label_names;
    std::map<Labels, Child> children;  // labels sorted by name
  };

  template <typename Metric>
  Metric& find_or_add(MetricType type, std::string_view name, std::string_view help,
                      const std::vector<double>& bounds, const Labels& labels);

  mutable std::mutex mutex_;
  std::map<std::string, Family, std::less<>> families_;
};

}  // namespace pnp::services
