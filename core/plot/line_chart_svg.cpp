#include "plot/line_chart_svg.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include "plot/xml_escape.h"

namespace pnp::plot {

std::string palette_colour(std::size_t i) {
  static constexpr std::array<const char*, 8> kColours{"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728",
                                                       "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
  return kColours[i % kColours.size()];
}

std::vector<double> axis_ticks(double max, int max_ticks) {
  if (!(max > 0) || !std::isfinite(max)) max = 1;
  max_ticks = std::max(max_ticks, 1);
  const double magnitude = std::pow(10.0, std::floor(std::log10(max / max_ticks)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (max / step <= max_ticks) break;
  }
  const int intervals = static_cast<int>(std::ceil(max / step - 1e-9));
  std::vector<double> ticks;
  for (int k = 0; k <= intervals; ++k) ticks.push_back(step * k);
  return ticks;
}

std::string tick_label(double value, bool in_thousands) {
  if (!in_thousands || std::abs(value) < 1000) return fmt::format("{:g}", value);
  return fmt::format("{:g}k", value / 1000);
}

namespace {

// Each label once, in the order the series come.
std::vector<const Series*> legend_entries(const std::vector<Series>& series) {
  std::vector<const Series*> entries;
  std::set<std::string> listed;
  for (const auto& s : series)
    if (listed.insert(s.label).second) entries.push_back(&s);
  return entries;
}

}  // namespace

std::string line_chart_svg(const ChartSpec& spec, const std::vector<Series>& series) {
  // The legend has a column of its own right of the plot: inside it, it sat on the curves,
  // which end near success 1 at the top right.
  const std::vector<const Series*> entries = legend_entries(series);
  constexpr double kPlotW = 900, H = 420, L = 70, B = 50, kLegendW = 270;
  const double W = kPlotW + (entries.empty() ? 0 : kLegendW);
  const double R = W - kPlotW + 20;
  const double T = spec.title.empty() ? 30 : 45;
  double data_max = 0;
  for (const auto& s : series)
    for (const auto& [x, y] : s.points) data_max = std::max(data_max, x);
  const std::vector<double> x_ticks = axis_ticks(data_max);
  const double x_max = x_ticks.back();
  const double y_span = spec.y_max > spec.y_min ? spec.y_max - spec.y_min : 1;
  auto px = [&](double x) { return L + (W - L - R) * x / x_max; };
  auto py = [&](double y) {
    return T + (H - T - B) * (1 - (std::clamp(y, spec.y_min, spec.y_max) - spec.y_min) / y_span);
  };
  std::string svg = fmt::format(
      "<svg xmlns='http://www.w3.org/2000/svg' width='{}' height='{}' font-family='sans-serif' "
      "font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
      "<line x1='{}' y1='{}' x2='{}' y2='{}' stroke='black'/>"
      "<line x1='{}' y1='{}' x2='{}' y2='{}' stroke='black'/>\n"
      "<text x='{}' y='{}' text-anchor='middle'>{}</text>\n"
      "<text x='15' y='{}' transform='rotate(-90 15 {})' text-anchor='middle'>{}</text>\n",
      W, H, L, H - B, W - R, H - B, L, T, L, H - B, (L + W - R) / 2, H - 12,
      escape_xml(spec.x_label), (T + H - B) / 2, (T + H - B) / 2, escape_xml(spec.y_label));
  if (!spec.title.empty()) {
    svg += fmt::format("<text x='{}' y='22' text-anchor='middle' font-size='15'>{}</text>\n",
                       kPlotW / 2, escape_xml(spec.title));
  }
  for (double g : spec.y_grid) {
    svg += fmt::format(
        "<line x1='{}' y1='{:.1f}' x2='{}' y2='{:.1f}' stroke='#ddd'/><text x='{}' y='{:.1f}' "
        "text-anchor='end'>{}</text>\n",
        L, py(g), W - R, py(g), L - 5, py(g) + 4, g);
  }
  for (double x : x_ticks) {
    svg += fmt::format(
        "<line x1='{0:.1f}' y1='{1}' x2='{0:.1f}' y2='{2}' stroke='black'/>"
        "<text x='{0:.1f}' y='{3}' text-anchor='middle'>{4}</text>\n",
        px(x), H - B, H - B + 4, H - B + 16, tick_label(x, spec.x_in_thousands));
  }
  for (const auto& s : series) {
    std::string points;
    for (const auto& [x, y] : s.points) points += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
    svg += fmt::format("<polyline fill='none' stroke='{}' stroke-opacity='0.8' points='{}'/>\n",
                       s.colour, points);
    if (!spec.markers) continue;
    for (const auto& [x, y] : s.points)
      svg += fmt::format("<circle cx='{:.1f}' cy='{:.1f}' r='2.5' fill='{}'/>\n", px(x), py(y),
                         s.colour);
  }
  const double lx = W - kLegendW + 10;
  double ly = T + 12;
  for (const Series* s : entries) {
    svg += fmt::format(
        "<line class='legend' x1='{}' y1='{}' x2='{}' y2='{}' stroke='{}' stroke-width='3'/>"
        "<text x='{}' y='{}'>{}</text>\n",
        lx, ly, lx + 25, ly, s->colour, lx + 32, ly + 4, escape_xml(s->label));
    ly += 18;
  }
  return svg + "</svg>\n";
}

}  // namespace pnp::plot
