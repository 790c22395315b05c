// The options of a trace that `precompute` and `optimize` share: the scene overrides, --spp N|auto
// and its --tolerance, --max-depth N|auto, --seed and --threads.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "app/pipeline/Transport.h"

namespace sl::cli {

/// The trace's options. noiseAware: optimize's spp auto (app/pipeline/TrainingNoise.h) instead of
/// precompute's gradient-noise pilot.
void addTraceOptions(CLI::App* c, PrecomputeOptions& p, std::vector<std::string>& overrides,
                     bool noiseAware = false);

}  // namespace sl::cli
