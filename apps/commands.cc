#include "apps/commands.h"

namespace hovs::apps {

const std::vector<Command>& Commands() {
  static const std::vector<Command> table = {
      {"design", "Mirror design study: sweep (a, b[, d]), constrained optima, report with figures", SetupDesign},
      {"version", "Print the versions of hovs and its libraries", SetupVersion},
  };
  return table;
}

}  // namespace hovs::apps
