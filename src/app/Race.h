// `scratchlight bench race`: the measured race that chooses optimize's defaults. Every
// configuration (objective × method × spp × planes × starts × continuation) runs on generated
// parts × training seeds; every result is scored by the judge (app/Judge.h) on the part's
// independent 1024-spp estimate; seconds are precompute (traced fresh, not cached) + search,
// measured one after another in the same run. Ratios are to the paper-loop configuration on
// the same part and seed.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "app/PartFiles.h"
#include "app/Search.h"
#include "scene/RenderDesc.h"

namespace sl {

struct RaceConfig {
    std::string name;
    SearchOptions search;
    int spp = 16;  // per estimate of T (both halves together for the unbiased objective)
    std::optional<Sampling> sampling;  // T's direction sampling (default: the part's scene's)
    std::optional<int> maxDepth;       // T's path length (default: the part's scene's)
};

/// The configurations raced by default (paper-loop first: the baseline).
std::vector<RaceConfig> defaultRaceConfigs();

/// Speed against error (`bench settings`): optimize's default search (the unbiased objective)
/// on T traced at every spp × sampling × max_depth given, named "spp16-stratified-d3". The
/// first is the parts' own setting (16 spp, the default sampler, max_depth 3), the baseline of
/// the ratios, whether or not it is in the lists.
std::vector<RaceConfig> settingsRaceConfigs(const std::vector<int>& spps,
                                            const std::vector<Sampling>& samplings,
                                            const std::vector<int>& maxDepths);

struct RacePart {
    std::string name;  // ballend-chatter | facemill-scratches | pocket
};
/// The generated parts: a ball-end part whose right half has chatter, a face-mill part with
/// scratches, a ball-end pocket (step edge); 512² samples at 0.01 mm, 256² view, max_depth 3.
std::vector<std::string> raceParts();
/// Writes race part `name` into `dir` (part.exr, its truth, scene.json at 256², 16 spp,
/// max_depth 3: as the race traces it). Throws InputError for an unknown name.
PartFiles writeRacePart(const std::string& name, const std::filesystem::path& dir);

struct RaceOptions {
    std::vector<std::string> parts = raceParts();
    int seeds = 3;  // training seeds 0..seeds−1 (render.seed)
    std::vector<RaceConfig> configs = defaultRaceConfigs();
    int judgeSpp = 1024;
    std::optional<int> judgeMaxDepth;  // the judge's path length (default: the parts' scene's)
    double lambda = 30;
    std::filesystem::path workDir = "out/race";  // parts and the judge's cache live here
    std::function<void(const std::string&)> log;
};

struct RaceRow {
    std::string part, config;
    int seed = 0;
    double secondsPrecompute = 0, secondsSearch = 0, seconds = 0;
    int evaluations = 0;
    double eq2 = 0, unbiased = 0, meanE = 0, sparsity = 0;
    double visDefect = 0, visChatter = 0;  // NaN when the part has no such region
    double trainLoss = 0, heldOwn = 0;     // own objective: training and judge estimate
    double ratioU = 0, ratioEq2 = 0, ratioSeconds = 0;  // to paper-loop, same part and seed
};

struct RaceSummary {
    std::vector<RaceRow> rows;
    std::vector<RaceRow> medians;  // per (part, config), medians over seeds (seed = −1)
    std::vector<RaceRow> overall;  // per config, medians over parts and seeds
};

RaceSummary runRace(const RaceOptions& options);

/// Writes the rows as CSV.
void writeRaceCsv(const std::filesystem::path& file, const std::vector<RaceRow>& rows);

/// A fixed-width table (the medians).
std::string formatRaceTable(const std::vector<RaceRow>& rows);

}  // namespace sl
