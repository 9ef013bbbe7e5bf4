#include "services/common/metrics_registry.h"

#include <prometheus/text_serializer.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "common/error.h"

namespace pnp::services {
namespace {

bool is_name_start(char c, bool colon_allowed) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' ||
         (colon_allowed && c == ':');
}

bool is_name_char(char c, bool colon_allowed) {
  return is_name_start(c, colon_allowed) || (c >= '0' && c <= '9');
}

// Prometheus' grammar: metric names [a-zA-Z_:][a-zA-Z0-9_:]*, label names without ':'.
bool matches_name(std::string_view name, bool colon_allowed) {
  return !name.empty() && is_name_start(name.front(), colon_allowed) &&
         std::all_of(name.begin() + 1, name.end(),
                     [&](char c) { return is_name_char(c, colon_allowed); });
}

std::string quoted(std::string_view s) {
  return "\"" + std::string(s) + "\"";
}

void check_metric_name(std::string_view name) {
  if (!matches_name(name, true))
    throw_invalid_argument("metric name", "a name matching [a-zA-Z_:][a-zA-Z0-9_:]*", quoted(name));
}

// Validated, and sorted by name so that the same set always finds the same series.
Labels sorted_labels(std::string_view metric, const Labels& labels, bool histogram) {
  Labels out = labels;
  std::sort(out.begin(), out.end());
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::string& label = out[i].first;
    const std::string field = std::string(metric) + " label name";
    if (!matches_name(label, false))
      throw_invalid_argument(field, "a name matching [a-zA-Z_][a-zA-Z0-9_]*", quoted(label));
    if (label.starts_with("__"))
      throw_invalid_argument(field, "a name not starting with __ (reserved)", quoted(label));
    if (histogram && label == "le")
      throw_invalid_argument(field, "a name other than le (a histogram's bucket label)",
                             quoted(label));
    if (i > 0 && out[i - 1].first == label)
      throw_invalid_argument(field, "each label name once", quoted(label) + " twice");
  }
  return out;
}

void check_bounds(const std::vector<double>& bounds) {
  for (std::size_t i = 0; i < bounds.size(); ++i) {
    if (!std::isfinite(bounds[i]) || (i > 0 && !(bounds[i - 1] < bounds[i])))
      throw_invalid_argument("histogram bounds[" + std::to_string(i) + "]",
                             "finite and strictly increasing bounds", std::to_string(bounds[i]));
  }
}

std::string_view type_name(MetricType type) {
  switch (type) {
    case MetricType::kCounter:
      return "counter";
    case MetricType::kGauge:
      return "gauge";
    case MetricType::kHistogram:
      return "histogram";
  }
  return "untyped";
}

}  // namespace

MetricsRegistry::MetricsRegistry() : registry_(std::make_shared<prometheus::Registry>()) {}

template <typename Metric>
Metric& MetricsRegistry::find_or_add(MetricType type, std::string_view name, std::string_view help,
                                     const std::vector<double>& bounds, const Labels& labels) {
  check_metric_name(name);
  const Labels sorted = sorted_labels(name, labels, type == MetricType::kHistogram);
  std::vector<std::string> label_names;
  for (const auto& label : sorted) label_names.push_back(label.first);

  std::lock_guard lock(mutex_);
  auto family = families_.find(name);
  if (family == families_.end()) {
    if (type == MetricType::kHistogram) check_bounds(bounds);
    // A histogram's series are name_bucket, name_sum and name_count: no family may take
    // those names from it, nor it from them.
    for (std::string_view suffix : {"_bucket", "_sum", "_count"}) {
      bool clash = type == MetricType::kHistogram &&
                   families_.contains(std::string(name) + std::string(suffix));
      if (name.ends_with(suffix)) {
        const auto stem = families_.find(name.substr(0, name.size() - suffix.size()));
        clash = clash || (stem != families_.end() && stem->second.type == MetricType::kHistogram);
      }
      if (clash)
        throw_invalid_argument(quoted(name), "a name no histogram's series uses",
                               "a clash with a histogram's " + std::string(suffix) + " series");
    }
    auto& added = prometheus::detail::Builder<Metric>()
                      .Name(std::string(name))
                      .Help(std::string(help))
                      .Register(*registry_);
    family = families_
                 .emplace(std::string(name),
                          Family{type, std::string(help),
                                 type == MetricType::kHistogram ? bounds : std::vector<double>{},
                                 std::move(label_names), &added})
                 .first;
  } else {
    const Family& f = family->second;
    if (f.type != type)
      throw_invalid_argument(
          quoted(name),
          std::string("a ") + std::string(type_name(f.type)) + " (as first registered)",
          std::string("a ") + std::string(type_name(type)));
    if (f.help != help)
      throw_invalid_argument(quoted(name) + " help", quoted(f.help) + " (as first registered)",
                             quoted(help));
    if (type == MetricType::kHistogram && f.bounds != bounds)
      throw_invalid_argument(quoted(name) + " bounds", "the buckets first registered",
                             "other buckets");
    if (f.label_names != label_names)
      throw_invalid_argument(quoted(name) + " labels", "the label names first registered",
                             "other label names");
  }
  // The family returns the existing metric for a label set it has seen.
  auto& metrics = *std::get<prometheus::Family<Metric>*>(family->second.metrics);
  const prometheus::Labels keyed(sorted.begin(), sorted.end());
  if constexpr (std::is_same_v<Metric, Histogram>) {
    return metrics.Add(keyed, bounds);
  } else {
    return metrics.Add(keyed);
  }
}

Counter& MetricsRegistry::counter(std::string_view name, std::string_view help,
                                  const Labels& labels) {
  return find_or_add<Counter>(MetricType::kCounter, name, help, {}, labels);
}

Gauge& MetricsRegistry::gauge(std::string_view name, std::string_view help, const Labels& labels) {
  return find_or_add<Gauge>(MetricType::kGauge, name, help, {}, labels);
}

Histogram& MetricsRegistry::histogram(std::string_view name, std::string_view help,
                                      const std::vector<double>& bounds, const Labels& labels) {
  return find_or_add<Histogram>(MetricType::kHistogram, name, help, bounds, labels);
}

std::string MetricsRegistry::render() const {
  return prometheus::TextSerializer().Serialize(registry_->Collect());
}

}  // namespace pnp::services
