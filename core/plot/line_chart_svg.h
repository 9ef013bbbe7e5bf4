#pragma once
// A line chart as a standalone SVG document: learning curves (success against training
// steps) for reports and the CLI. No dependencies beyond formatting.

#include <string>
#include <utility>
#include <vector>

namespace pnp::plot {

struct Series {
  std::string label;   // legend entry; series sharing a label share one entry
  std::string colour;  // any SVG colour, e.g. "#1f77b4"
  std::vector<std::pair<double, double>> points;  // (x, y), in order of x
};

struct ChartSpec {
  std::string title;  // empty: none
  std::string x_label, y_label;
  double y_min = 0, y_max = 1;
  std::vector<double> y_grid{0, 0.5, 0.95, 1.0};  // labelled horizontal lines
  // x ticks are labelled in thousands ("12k", "2.5k") when x_in_thousands.
  bool x_in_thousands = true;
  bool markers = true;  // a dot at each point: evaluations are where the curve is known
};

std::string line_chart_svg(const ChartSpec& spec, const std::vector<Series>& series);

// Axis ticks from 0 to at least `max` (> 0), evenly spaced by 1, 2 or 5 times a power of
// ten, at most `max_ticks` intervals: 2600 gives 0, 500, ..., 3000.
std::vector<double> axis_ticks(double max, int max_ticks = 6);

// A tick's label: "0", "500", "2.5k", "12k" in thousands; "2500" otherwise.
std::string tick_label(double value, bool in_thousands);

// A distinct colour for the i-th series.
std::string palette_colour(std::size_t i);

}  // namespace pnp::plot
