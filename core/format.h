// One number through a printf format ("%.4f" and the like), for the text of summaries, tables and reports.
#pragma once

#include <cstdio>
#include <string>

namespace hovs {

inline std::string FormatNumber(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

}  // namespace hovs
