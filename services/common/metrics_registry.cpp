#include "services/common/metrics_registry.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iterator>
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

// What client_golang writes (Go's strconv 'g', shortest): the shortest round-trip digits,
// in exponent form below 1e-4 and from 1e6 on: 1, 0.25, 0.0001, 5e-05, 1.5e+06, +Inf.
void append_value(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "NaN";
    return;
  }
  if (std::isinf(value)) {
    out += value > 0 ? "+Inf" : "-Inf";
    return;
  }
  char buffer[64];
  auto result =
      std::to_chars(std::begin(buffer), std::end(buffer), value, std::chars_format::scientific);
  const std::string_view scientific(buffer, static_cast<std::size_t>(result.ptr - buffer));
  const int exponent = std::stoi(std::string(scientific.substr(scientific.find('e') + 1)));
  if (exponent < -4 || exponent >= 6) {
    out += scientific;
    return;
  }
  result = std::to_chars(std::begin(buffer), std::end(buffer), value, std::chars_format::fixed);
  out.append(buffer, result.ptr);
}

void append_escaped(std::string& out, std::string_view text, bool escape_quotes) {
  for (char c : text) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '"' && escape_quotes) {
      out += "\\\"";
    } else {
      out += c;
    }
  }
}

// name{a="x",b="y",le="0.1"} value
void append_series(std::string& out, std::string_view name, const Labels& labels,
                   std::string_view le, std::string_view value) {
  out += name;
  if (!labels.empty() || !le.empty()) {
    out += '{';
    bool first = true;
    for (const auto& [label, label_value] : labels) {
      if (!first) out += ',';
      first = false;
      out.append(label).append("=\"");
      append_escaped(out, label_value, true);
      out += '"';
    }
    if (!le.empty()) out.append(first ? "" : ",").append("le=\"").append(le).append("\"");
    out += '}';
  }
  out.append(" ").append(value).append("\n");
}

std::string formatted(double value) {
  std::string out;
  append_value(out, value);
  return out;
}

}  // namespace

void Counter::inc(double amount) {
  if (!(amount >= 0.0))
    throw_invalid_argument("counter increment", "a non-negative amount", std::to_string(amount));
  value_.fetch_add(amount, std::memory_order_relaxed);
}

Histogram::Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)) {
  check_bounds(bounds_);
  counts_ = std::vector<std::atomic<std::uint64_t>>(bounds_.size() + 1);
}

void Histogram::observe(double value) {
  // Bucket k holds values in (bounds[k-1], bounds[k]]; NaN is above every bound.
  const auto k =
      std::isnan(value)
          ? bounds_.size()
          : static_cast<std::size_t>(std::lower_bound(bounds_.begin(), bounds_.end(), value) -
                                     bounds_.begin());
  counts_[k].fetch_add(1, std::memory_order_relaxed);
  sum_.fetch_add(value, std::memory_order_relaxed);
}

std::vector<std::uint64_t> Histogram::bucket_counts() const {
  std::vector<std::uint64_t> out;
  out.reserve(counts_.size());
  for (const auto& count : counts_) out.push_back(count.load(std::memory_order_relaxed));
  return out;
}

template <typename Metric>
Metric& MetricsRegistry::find_or_add(MetricType type, std::string_view name, std::string_view help,
                                     const std::vector<double>& bounds, const Labels& labels) {
  check_metric_name(name);
  Labels sorted = sorted_labels(name, labels, type == MetricType::kHistogram);
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
    family = families_
                 .emplace(std::string(name),
                          Family{type,
                                 std::string(help),
                                 type == MetricType::kHistogram ? bounds : std::vector<double>{},
                                 std::move(label_names),
                                 {}})
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

  auto& children = family->second.children;
  auto child = children.find(sorted);
  if (child == children.end()) {
    std::unique_ptr<Metric> metric;
    if constexpr (std::is_same_v<Metric, Histogram>) {
      metric = std::make_unique<Histogram>(bounds);
    } else {
      metric = std::make_unique<Metric>();
    }
    child = children.emplace(std::move(sorted), std::move(metric)).first;
  }
  return *std::get<std::unique_ptr<Metric>>(child->second);
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
  std::string out;
  std::lock_guard lock(mutex_);
  for (const auto& [name, family] : families_) {
    out.append("# HELP ").append(name).append(" ");
    append_escaped(out, family.help, false);
    out.append("\n# TYPE ").append(name).append(" ").append(type_name(family.type)).append("\n");
    for (const auto& [labels, child] : family.children) {
      if (const auto* counter = std::get_if<std::unique_ptr<Counter>>(&child)) {
        append_series(out, name, labels, {}, formatted((*counter)->value()));
      } else if (const auto* gauge = std::get_if<std::unique_ptr<Gauge>>(&child)) {
        append_series(out, name, labels, {}, formatted((*gauge)->value()));
      } else {
        const Histogram& h = *std::get<std::unique_ptr<Histogram>>(child);
        const auto counts = h.bucket_counts();
        // _count is the +Inf bucket, both from the same reads: a scrape racing an
        // observation still shows them equal.
        std::uint64_t cumulative = 0;
        for (std::size_t k = 0; k < counts.size(); ++k) {
          cumulative += counts[k];
          append_series(out, name + "_bucket", labels,
                        k < h.bounds().size() ? formatted(h.bounds()[k]) : "+Inf",
                        std::to_string(cumulative));
        }
        append_series(out, name + "_sum", labels, {}, formatted(h.sum()));
        append_series(out, name + "_count", labels, {}, std::to_string(cumulative));
      }
    }
  }
  return out;
}

}  // namespace pnp::services
