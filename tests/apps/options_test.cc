// The command table: every numeric option of every command is bounded (finite, within a range), so that no value
// given on the command line reaches a library unchecked (a NaN timeout reached Aravis; 1024000 disparities reached
// OpenCV).
#include <gtest/gtest.h>

#include <memory>

#include "apps/commands.h"

namespace hovs::apps {
namespace {

bool IsNumeric(const std::string& type) {
  for (const char* t : {"INT", "UINT", "FLOAT", "NUMBER"})
    if (type.rfind(t, 0) == 0) return true;
  return false;
}

TEST(Options, EveryNumericOptionOfEveryCommandIsBounded) {
  int numeric = 0;
  for (const Command& cmd : Commands()) {
    CLI::App app;
    GlobalOptions global;
    CLI::App* sub = app.add_subcommand(cmd.name, cmd.help);
    cmd.setup(sub, &global);
    for (CLI::Option* opt : sub->get_options()) {
      if (opt->get_type_size() == 0 || !IsNumeric(opt->get_type_name())) continue;
      ++numeric;
      bool bounded = true;
      try {
        opt->get_validator("bounded");
      } catch (const CLI::OptionNotFound&) { bounded = false; }
      EXPECT_TRUE(bounded) << "hovs " << cmd.name << " " << opt->get_name() << " (" << opt->get_type_name()
                           << ") has no bounds: add ->check(Bounded(lo, hi))";
    }
  }
  EXPECT_GT(numeric, 50);
}

TEST(Options, BoundedRefusesNonFiniteAndOutOfRangeValues) {
  const CLI::Validator b = Bounded(0, 10, true);
  for (std::string ok : {"0.5", "10", "3", "1e-3"}) EXPECT_EQ(b(ok), "") << ok;
  for (std::string bad : {"nan", "inf", "-inf", "0", "-1", "10.5", "1e400", "3x", "", "0x10"})
    EXPECT_NE(b(bad), "") << bad;
}

}  // namespace
}  // namespace hovs::apps
