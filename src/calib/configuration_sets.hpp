#pragma once
// The calibration and validation sets of a sampling, one rule for the planar sampler
// (sample_configurations) and the spatial one (spatial_sample_configurations): a Poisson-disc
// draw of count + validation configurations split in two; with the D-optimal design, the
// calibration set chosen instead among candidates kept away from the validation set.

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "pcr/calib/sampling.hpp"  // SamplingDesign, kDesignCandidateFactor
#include "pcr/csv_io.hpp"          // format_double
#include "pcr/input_error.hpp"

namespace pcr::internal {

/// `Sets` as ConfigurationSets (calibration, validation, spread, candidates, design);
/// poisson_disc(options) draws a SamplingResult-like set, d_optimal(candidates, count) chooses
/// `count` of them. `caller` names the function in the errors.
template <class Sets, class Options, class PoissonDisc, class DOptimal>
Sets sample_configuration_sets(const char* caller, const Options& options, int validation_count,
                               PoissonDisc&& poisson_disc, DOptimal&& d_optimal) {
  if (validation_count < 0) {
    throw InputError(std::string(caller) + ": validation count must be >= 0, got " +
                     std::to_string(validation_count));
  }
  const bool designed = options.design == SamplingDesign::kDOptimal;
  Sets sets;
  if (!designed || validation_count > 0) {
    // D-optimal too draws count + validation_count, so that its validation set is the one the
    // Poisson-disc design gets with the same seed (a paired comparison of the designs).
    Options spread = options;
    spread.count = options.count + validation_count;
    sets.spread = poisson_disc(spread);
    if (!sets.spread.complete) {
      throw std::runtime_error("only " + std::to_string(sets.spread.configurations.size()) +
                               " admissible configurations are " +
                               format_double(sets.spread.min_distance) + " m apart; asked for " +
                               std::to_string(spread.count) +
                               " (lower min_distance: pcr sample --min-distance)");
    }
    const auto& all = sets.spread.configurations;
    sets.calibration.assign(all.begin(), all.begin() + options.count);
    sets.validation.assign(all.begin() + options.count, all.end());
  }
  if (!designed) return sets;

  Options pool = options;
  pool.count = options.candidates > 0 ? options.candidates : kDesignCandidateFactor * options.count;
  pool.min_distance = 0.0;  // from the candidate count
  sets.candidates = poisson_disc(pool);
  // Disjoint from the validation set, and the union still a Poisson-disc set of the candidates'
  // radius.
  auto candidates = sets.candidates.configurations;
  candidates.clear();
  const double r2 = sets.candidates.min_distance * sets.candidates.min_distance;
  for (const auto& q : sets.candidates.configurations) {
    bool far = true;
    for (const auto& v : sets.validation) far = far && (q - v).squaredNorm() >= r2;
    if (far) candidates.push_back(q);
  }
  if (static_cast<int>(candidates.size()) < options.count) {
    throw std::runtime_error(
        std::string(caller) + ": d-optimal design: only " + std::to_string(candidates.size()) +
        " candidates away from the validation set; asked for " + std::to_string(options.count));
  }
  sets.candidates.configurations = std::move(candidates);
  sets.design = d_optimal(sets.candidates.configurations, options.count);
  sets.calibration.clear();
  for (int j : sets.design.selected) {
    sets.calibration.push_back(sets.candidates.configurations[static_cast<std::size_t>(j)]);
  }
  return sets;
}

}  // namespace pcr::internal
