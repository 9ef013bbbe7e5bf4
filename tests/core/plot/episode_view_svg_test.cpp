// The episode view: both views drawn, one gripper segment per step coloured by the
// subtask chosen for it, the goal, the outcome, and text escaped.
#include "plot/episode_view_svg.h"

#include <gtest/gtest.h>

#include <string>

#include "plot/xml_escape.h"

namespace pnp::plot {
namespace {

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

EpisodeTrace three_steps() {
  EpisodeTrace t;
  t.title = "episode 424242 <seed & co>";
  t.goal = {1.4, 0.8, 0.55};
  t.table_top_z = 0.40;
  t.success = true;
  t.frames = {{{1.30, 0.75, 0.60}, {1.35, 0.70, 0.425}, -1},
              {{1.33, 0.72, 0.50}, {1.35, 0.70, 0.425}, 0},
              {{1.35, 0.70, 0.43}, {1.35, 0.70, 0.425}, 1},
              {{1.40, 0.80, 0.55}, {1.40, 0.80, 0.55}, 2}};
  return t;
}

TEST(EpisodeViewSvg, DrawsBothViewsWithOneSegmentPerStepInItsSubtasksColour) {
  const std::string svg = episode_view_svg(three_steps());
  EXPECT_TRUE(svg.starts_with("<svg ")) << svg;
  EXPECT_NE(svg.find(R"(class="episode" data-steps="3" data-success="1")"), std::string::npos);
  EXPECT_EQ(count(svg, R"(<g class="view top">)"), 1);
  EXPECT_EQ(count(svg, R"(<g class="view side">)"), 1);
  // Two views x three steps; each step coloured by the subtask chosen for it.
  EXPECT_EQ(count(svg, R"(class="gripper subtask-)"), 6);
  EXPECT_EQ(count(svg, R"(class="gripper subtask-approach")"), 2);
  EXPECT_EQ(count(svg, R"(class="gripper subtask-manipulate")"), 2);
  EXPECT_EQ(count(svg, R"(class="gripper subtask-retract")"), 2);
  EXPECT_NE(svg.find(R"(subtask-retract" x1)"), std::string::npos);
  EXPECT_EQ(count(svg, R"(class="goal")"), 2);
  EXPECT_EQ(count(svg, R"(class="object-path")"), 2);
  EXPECT_EQ(count(svg, R"(class="table")"), 1) << "the table in the side view only";
  EXPECT_NE(svg.find("placed"), std::string::npos);
  EXPECT_NE(svg.find("episode 424242 &lt;seed &amp; co&gt;"), std::string::npos);
  EXPECT_EQ(svg.find("<seed"), std::string::npos);
}

// Both axes of both views carry numbers in metres, round steps, in the world frame.
TEST(EpisodeViewSvg, BothAxesOfEachViewCarryNumbers) {
  const std::string svg = episode_view_svg(three_steps());
  EXPECT_GE(count(svg, R"(class="tick")"), 4 * 3) << "at least three numbers per axis";
  EXPECT_LE(count(svg, R"(class="tick")"), 4 * 7) << "at most seven per axis";
  EXPECT_NE(svg.find(R"(text-anchor="end">)"), std::string::npos) << "the vertical axes'";
}

TEST(EpisodeViewSvg, AFailedOrEmptyEpisodeStillDraws) {
  EpisodeTrace t = three_steps();
  t.success = false;
  EXPECT_NE(episode_view_svg(t).find(R"(data-success="0")"), std::string::npos);
  EXPECT_NE(episode_view_svg(t).find("not placed"), std::string::npos);
  t.frames.clear();
  const std::string svg = episode_view_svg(t);
  EXPECT_NE(svg.find(R"(data-steps="0")"), std::string::npos);
  EXPECT_EQ(count(svg, "class=\"gripper"), 0);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
}

TEST(XmlEscape, EscapesEveryCharacterThatBreaksMarkupOrAnAttribute) {
  EXPECT_EQ(escape_xml(R"(<a href="x">&'</a>)"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&apos;&lt;/a&gt;");
  EXPECT_EQ(escape_xml("plain 0.95"), "plain 0.95");
}

}  // namespace
}  // namespace pnp::plot
