// The learning-curve chart: ticks a reader can use, a dot per evaluation, one legend
// entry per label, and labels that cannot break the SVG.
#include "plot/line_chart_svg.h"

#include <gtest/gtest.h>

#include <regex>
#include <string>

namespace pnp::plot {
namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(AxisTicks, AreOneTwoOrFiveTimesAPowerOfTenAndCoverTheData) {
  EXPECT_EQ(axis_ticks(2600), (std::vector<double>{0, 500, 1000, 1500, 2000, 2500, 3000}));
  EXPECT_EQ(axis_ticks(60000), (std::vector<double>{0, 10000, 20000, 30000, 40000, 50000, 60000}));
  EXPECT_EQ(axis_ticks(17400), (std::vector<double>{0, 5000, 10000, 15000, 20000}));
  const std::vector<double> fractions = axis_ticks(1);
  ASSERT_EQ(fractions.size(), 6u);
  for (std::size_t k = 0; k < fractions.size(); ++k)
    EXPECT_DOUBLE_EQ(fractions[k], 0.2 * static_cast<double>(k));
}

TEST(AxisTicks, NoDataStillGivesAnAxis) {
  EXPECT_EQ(axis_ticks(0).size(), 6u);
  EXPECT_EQ(axis_ticks(0).back(), 1);
}

TEST(TickLabel, ReadsInThousandsWithoutRoundingTwoTicksToOneLabel) {
  EXPECT_EQ(tick_label(0, true), "0");
  EXPECT_EQ(tick_label(500, true), "500");
  EXPECT_EQ(tick_label(2500, true), "2.5k");
  EXPECT_EQ(tick_label(12000, true), "12k");
  EXPECT_EQ(tick_label(2500, false), "2500");
}

TEST(LineChartSvg, MarksEachEvaluationAndListsEachLabelOnce) {
  const std::vector<Series> series{
      {"approach ddpg_her seed 1 (run 3)", "#1f77b4", {{1000, 0.2}, {2000, 0.9}, {2600, 1.0}}},
      {"seed <2> & more", "#ff7f0e", {{1000, 0.1}, {2000, 0.5}}},
      {"seed <2> & more", "#ff7f0e", {{1000, 0.3}}}};
  const std::string svg = line_chart_svg({}, series);
  EXPECT_EQ(count(svg, "<circle"), 6);
  EXPECT_EQ(count(svg, "<polyline"), 3);
  EXPECT_EQ(count(svg, "approach ddpg_her seed 1 (run 3)"), 1);
  EXPECT_EQ(count(svg, "seed &lt;2&gt; &amp; more"), 1);
  EXPECT_EQ(count(svg, "<2>"), 0);
  EXPECT_NE(svg.find(">2.5k</text>"), std::string::npos);
  EXPECT_NE(svg.find(">3k</text>"), std::string::npos);

  ChartSpec plain;
  plain.markers = false;
  EXPECT_EQ(count(line_chart_svg(plain, series), "<circle"), 0);
}

// The legend has its own column right of the plot (inside, it sat on the curves, which end
// near 1 at the top right).
TEST(LineChartSvg, TheLegendLiesRightOfThePlotNotOnTheCurves) {
  const std::vector<Series> series{{"run 1", "#1f77b4", {{1000, 0.9}, {2000, 1.0}}}};
  const std::string svg = line_chart_svg({}, series);
  std::smatch axis, legend;
  ASSERT_TRUE(std::regex_search(svg, axis, std::regex("<line x1='70' y1='370' x2='([0-9.]+)'")));
  ASSERT_TRUE(std::regex_search(svg, legend, std::regex("class='legend' x1='([0-9.]+)'")));
  EXPECT_GT(std::stod(legend[1]), std::stod(axis[1]));
}

}  // namespace
}  // namespace pnp::plot
