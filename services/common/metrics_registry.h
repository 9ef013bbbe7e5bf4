#pragma once
// Prometheus metrics on prometheus-cpp (Debian's prometheus-cpp-dev): counters, gauges and
// histograms, each identified by a family name and a label set. On top of prometheus-cpp
// this adds the checks the Prometheus data model needs and prometheus-cpp leaves to its
// caller: one type, help text, bucket layout and set of label names per family, no clash
// with a histogram's _bucket/_sum/_count series, no reserved or duplicate label names.
// Looking a metric up takes a lock and may allocate; the reference it returns lives as long
// as the registry, so hot paths look up once and keep it (counters and gauges then update
// with atomics, a histogram under its own lock).

#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/gauge.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace pnp::services {

// Label name -> value; any order, each name at most once.
using Labels = std::vector<std::pair<std::string, std::string>>;
using Counter = prometheus::Counter;
using Gauge = prometheus::Gauge;
using Histogram = prometheus::Histogram;

enum class MetricType { kCounter, kGauge, kHistogram };

class MetricsRegistry {
 public:
  MetricsRegistry();

  // The metric of that family and label set, created on first use. INVALID_ARGUMENT for
  // a name or label name outside Prometheus' grammar, a name already registered with
  // another type, help text or buckets, label names that differ from the family's, or
  // histogram bounds that are not finite and strictly increasing.
  Counter& counter(std::string_view name, std::string_view help, const Labels& labels = {});
  Gauge& gauge(std::string_view name, std::string_view help, const Labels& labels = {});
  Histogram& histogram(std::string_view name, std::string_view help,
                       const std::vector<double>& bounds, const Labels& labels = {});

  // Text exposition format 0.0.4 (prometheus-cpp's serializer).
  std::string render() const;

  // For prometheus-cpp collectors and exposers that take a registry.
  std::shared_ptr<prometheus::Registry> prometheus_registry() const { return registry_; }

 private:
  struct Family {
    MetricType type;
    std::string help;
    std::vector<double> bounds;  // histograms only
    std::vector<std::string> label_names;
    std::variant<prometheus::Family<Counter>*, prometheus::Family<Gauge>*,
                 prometheus::Family<Histogram>*>
        metrics;  // owned by registry_
  };

  template <typename Metric>
  Metric& find_or_add(MetricType type, std::string_view name, std::string_view help,
                      const std::vector<double>& bounds, const Labels& labels);

  std::shared_ptr<prometheus::Registry> registry_;
  mutable std::mutex mutex_;
  std::map<std::string, Family, std::less<>> families_;
};

}  // namespace pnp::services
