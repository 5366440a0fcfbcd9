// Error type of hovs: a message (what went wrong) and a location (which input, file, key or stage).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace hovs {

class Error : public std::runtime_error {
 public:
  // where: the input that is wrong (a file path, "file:line", a config key, a parameter name, a stage).
  Error(std::string where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(std::move(where)), what_(what) {}

  const std::string& where() const { return where_; }
  const std::string& message() const { return what_; }

 private:
  std::string where_;
  std::string what_;
};

namespace internal {
template <class... Args>
std::string Concat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}
}  // namespace internal

}  // namespace hovs

// Throws hovs::Error(where, message) unless cond holds. For validating inputs and invariants, not hot loops.
#define HOVS_REQUIRE(cond, where, ...)                                                \
  do {                                                                                \
    if (!(cond)) throw ::hovs::Error((where), ::hovs::internal::Concat(__VA_ARGS__)); \
  } while (0)
