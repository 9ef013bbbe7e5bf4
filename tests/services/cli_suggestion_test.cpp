// "did you mean": the closest flag or command to a mistyped one, and none for a value.
#include "services/common/cli_suggestion.h"

#include <gtest/gtest.h>

namespace pnp::services {
namespace {

TEST(CliSuggestion, EditDistanceCountsASwapOfNeighboursOnce) {
  EXPECT_EQ(edit_distance("train", "train"), 0u);
  EXPECT_EQ(edit_distance("trian", "train"), 1u);
  EXPECT_EQ(edit_distance("--seeed", "--seed"), 1u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
}

TEST(CliSuggestion, TheClosestKnownNameIsSuggestedAndAValueNever) {
  CLI::App app("t");
  std::string robot;
  int episodes = 0;
  auto* evaluate = app.add_subcommand("evaluate");
  evaluate->add_option("--robot", robot);
  evaluate->add_option("--episodes", episodes);
  app.add_subcommand("train");
  try {
    app.parse(std::vector<std::string>{"--robto", "panda", "evaluate"});  // reversed: argv order
  } catch (const CLI::ParseError&) {
  }
  const std::string text = suggest_for_unknown(app, {"evaluate", "--robto", "panda", "3"});
  EXPECT_NE(text.find("--robto: did you mean --robot?"), std::string::npos) << text;
  EXPECT_EQ(text.find("panda:"), std::string::npos) << text;
  EXPECT_EQ(text.find("3:"), std::string::npos) << text;
  EXPECT_NE(suggest_for_unknown(app, {"trian"}).find("did you mean train?"), std::string::npos);
  EXPECT_EQ(suggest_for_unknown(app, {"--completely-different"}), "");
}

}  // namespace
}  // namespace pnp::services
