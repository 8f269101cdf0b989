#pragma once
// What pcr throws on a bad input (a file, a field, a value, an option), outside the real-time
// core, which reports in SolverSummary instead.

#include <stdexcept>
#include <string>

namespace pcr {

/// Bad input (a file, a field, a value). The message names the file, the field path and the value.
class InputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Throws InputError "`what`: <is_valid's message>" when `options.is_valid` refuses them.
template <class Options>
void require_valid(const Options& options, const std::string& what) {
  std::string error;
  if (!options.is_valid(&error)) throw InputError(what + ": " + error);
}

}  // namespace pcr
