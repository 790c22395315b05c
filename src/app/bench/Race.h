// `scratchlight bench race`: the measured race that chooses optimize's defaults. Every
// configuration (objective × method × spp × estimates × starts × continuation) runs on generated
// parts × training seeds; every result is scored by the judge (app/pipeline/Judge.h) on the part's
// independent 1024-spp estimate; seconds are precompute (traced fresh, not cached) + search,
// measured one after another in the same run. Ratios are to the paper-loop configuration on
// the same part and seed.
//
// The world (docs/DESIGN.md "Noise is the trap"): every part is raced at every image size ×
// surface roughness α × height scale given (scene overrides camera.width/height,
// material.alpha, heightmap.height_scale), beside the generated race parts the labelled test
// parts of gen-surface, variants of any generated part with its defects shallower or deeper
// than its texture's Sq, and real instrument textures with defects of known shape inserted
// (app/jobs/InsertDefectsJob.h). Every part also scores the studio lamp (scene/EnvMapPresets.h) on
// the same judge, and every result gets a figure: the defects' combined visibility
// (objective/DefectVisibility.h combinedVisibility) where the part's truth has defects in view,
// else U; its ratios to the lamp and to paper-loop are "times better" (visibility over the
// reference's, or the reference's U over its own). The race names the configuration whose
// worst part is best (kRaceWinnerRule).
#pragma once

#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "app/jobs/PartFiles.h"
#include "app/pipeline/Search.h"
#include "objective/CoarseLight.h"
#include "scene/RenderDesc.h"

namespace sl {

struct RaceConfig {
    std::string name;
    SearchOptions search;
    int spp = 16;  // per estimate of T (both halves together for the unbiased objective)
    std::optional<Sampling> sampling;  // T's direction sampling (default: the part's scene's)
    std::optional<int> maxDepth;       // T's path length (default: the part's scene's)
    /// The defects objective's regions: false, the part's truth (every label); true, the
    /// defect map found without labels (app/pipeline/Truth.h RegionSpec "auto", as optimize's).
    bool autoDefects = false;
    /// Run the whole `optimize` job (app/jobs/OptimizeJob.h: the noise rule's spp and light grid,
    /// the defect pixels' samples, the self-checked answer) on the part with its defects named
    /// (the truth, or the defect map with autoDefects) instead of one search on a T at `spp`;
    /// the row's light is the job's answer and its seconds the job's. `search` only names the
    /// objective (defects).
    bool wholeJob = false;
    std::optional<LightGrid> jobLightGrid;  // the job's light grid (unset: its rule's)
    /// What the defects objective makes large (the ratio, or JND as the judge sees it; the
    /// default: optimize's).
    DefectMeasure measure = ObjectiveOptions{}.defectMeasure;
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

/// The generated parts: a ball-end part whose right half has chatter, a face-mill part with
/// scratches, a ball-end pocket (step edge); 512² samples at 0.01 mm, 256² view, max_depth 3.
std::vector<std::string> raceParts();
/// Every part name writeRacePart knows: raceParts(), gen-surface's labelled test parts
/// (ballend, facemill, flatend, turned: synth/SurfaceGenerator.h testPartSpec, 1024² at
/// 0.01 mm), and NAME-shallow / NAME-deep for each of those.
std::vector<std::string> knownRaceParts();
/// A variant's defects (scratches, gouges, dents: their deepest) are this many times the
/// texture's Sq (synth/DefectInsert.h textureSq of the part made without its defects and pocket).
inline constexpr double kShallowDefectsSq = 0.5;
inline constexpr double kDeepDefectsSq = 4.0;
/// Writes race part `name` (knownRaceParts) into `dir` (part.exr, its truth, scene.json at
/// 256², 16 spp, max_depth 3: as the race traces it). Throws InputError for an unknown name.
PartFiles writeRacePart(const std::string& name, const std::filesystem::path& dir);
/// A real texture as a race part: defects of known shape inserted into `file` (an instrument
/// height map carrying its pitch, or a scene file) by the insert-defects job's defaults, the map
/// resampled to at most kRealPartSamples on its longer side, written into `dir` (part.exr, its
/// truth, part.json at 256², max_depth 3). Throws InputError naming the file when it cannot be
/// read or used.
inline constexpr int kRealPartSamples = 512;
PartFiles writeRealRacePart(const std::filesystem::path& file, const std::filesystem::path& dir);

struct RaceOptions {
    std::vector<std::string> parts = raceParts();  // knownRaceParts() names
    std::vector<std::filesystem::path> real;       // real textures (writeRealRacePart)
    std::vector<int> sizes{256};                   // image width = height of every part
    std::vector<double> alphas;                    // material.alpha (empty: the part's own)
    std::vector<double> heightScales{1.0};         // heightmap.height_scale
    int threads = 0;                               // worker threads (0: all)
    int seeds = 3;                                 // training seeds 0..seeds−1 (render.seed)
    std::vector<RaceConfig> configs = defaultRaceConfigs();
    int judgeSpp = 1024;
    std::optional<int> judgeMaxDepth;  // the judge's path length (default: the parts' scene's)
    double lambda = 30;
    std::filesystem::path workDir = "out/race";  // parts and the judge's cache live here
    std::function<void(const std::string&)> log;
};

struct RaceRow {
    std::string part, config;  // part: the world, e.g. "turned@128/a0.3/h2" (the size when not 256,
                               // α when given, the height scale when not 1)
    int seed = 0;
    double secondsPrecompute = 0, secondsSearch = 0, seconds = 0;
    int evaluations = 0;
    double eq2 = 0, unbiased = 0, meanE = 0, sparsity = 0;
    double visDefect = 0, visChatter = 0;  // NaN when the part has no such region
    double trainLoss = 0, heldOwn = 0;     // own objective: training and judge estimate
    double ratioU = 0, ratioEq2 = 0, ratioSeconds = 0;  // to paper-loop, same part and seed
    /// The part's figure: the defects' combined visibility, or U when no defect is in view.
    bool figureIsU = false;
    double figure = 0;
    double vsLamp = 0, vsPaper = 0;  // times better than the studio lamp, than paper-loop
    /// The defects' JND as a person sees them: the least visible kind's
    /// (objective/DefectVisibility.h leastVisibleJnd; the scene's viewing model) and its ratio to
    /// the lamp's; NaN without defects in view.
    double jnd = std::numeric_limits<double>::quiet_NaN();
    double jndVsLamp = std::numeric_limits<double>::quiet_NaN();
};

/// The name of the studio lamp's reference row.
inline constexpr const char* kLampConfig = "studio-lamp";
/// How the race names its winner (printed with the table).
inline constexpr const char* kRaceWinnerRule =
    "winner: the configuration whose worst part is best (the highest minimum over parts of its "
    "JND over the studio lamp's, the judge's first figure; of its visibility ratio over the "
    "lamp's where a configuration has no JND; ties: the higher median)";

/// One configuration over the parts: the median and the worst (minimum) over parts of its
/// per-part medians over seeds. A part where the configuration has no figure (no light returned:
/// no defect in view to name; or a light under which the figure cannot be formed) counts as
/// ratio 0 and in `failed`; a part where the reference has none is left out of that ratio.
struct RaceStanding {
    std::string config;
    int parts = 0, failed = 0;
    double medianVsLamp = 0, worstVsLamp = 0;
    std::string worstLampPart;
    double medianVsPaper = 0, worstVsPaper = 0;
    std::string worstPaperPart;
    /// The same over parts on JND (the light's least visible kind's JND over the lamp's; the
    /// winner's rule when every configuration has it). NaN when no part has JND.
    double medianJndVsLamp = std::numeric_limits<double>::quiet_NaN(),
           worstJndVsLamp = std::numeric_limits<double>::quiet_NaN();
    std::string worstJndPart;
    double medianSeconds = 0;
};

struct RaceSummary {
    std::vector<RaceRow> rows;
    std::vector<RaceRow> medians;         // per (part, config), medians over seeds (seed = −1)
    std::vector<RaceRow> overall;         // per config, medians over parts and seeds
    std::vector<RaceRow> lamps;           // the studio lamp per part and seed (config kLampConfig)
    std::vector<RaceRow> lampMedians;     // ... per part, medians over seeds
    std::vector<RaceStanding> standings;  // per config, then the lamp (kRaceWinnerRule's input)
    std::string winner;                   // raceWinner(standings)
};

RaceSummary runRace(const RaceOptions& options);

/// The standings of every configuration over the per-part median rows (`medians`, any order).
std::vector<RaceStanding> raceStandings(const std::vector<RaceRow>& medians,
                                        const std::vector<std::string>& configs);
/// kRaceWinnerRule over the standings (the lamp is a reference, never the winner).
std::string raceWinner(const std::vector<RaceStanding>& standings);
/// The standings as a fixed-width table, and as CSV.
std::string formatRaceStandings(const std::vector<RaceStanding>& standings);
void writeRaceStandingsCsv(const std::filesystem::path& file,
                           const std::vector<RaceStanding>& standings);

/// Writes the rows as CSV.
void writeRaceCsv(const std::filesystem::path& file, const std::vector<RaceRow>& rows);

/// A fixed-width table (the medians).
std::string formatRaceTable(const std::vector<RaceRow>& rows);

}  // namespace sl
