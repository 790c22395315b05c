// scratchlight bench race [--parts a,b,c] [--real FILE...] [--sizes 128,256] [--alphas 0.05,0.3]
//                        [--height-scales 1,2] [--seeds 3] [--configs NAME,...] [--threads N]
//                        [-o DIR]
// scratchlight bench settings [--spp 4,16,64] [--sampling ...] [--max-depth 2,3,4] [-o DIR]
// The race that chooses optimize's defaults (app/bench/Race.h): prints the median table and the
// standings (median and worst part per configuration, the winner by the worst part), writes
// race.csv (every run), race-median.csv, race-configs.csv (the standings) and a Pareto plot
// (seconds vs U) race.png; settings
// races the trace settings of T the same way (settings.csv, settings.png).
#include <algorithm>
#include <cstdio>
#include <memory>

#include "app/bench/Race.h"
#include "app/host/Plot.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Interrupt.h"
#include "core/Registry.h"
#include "core/Stopwatch.h"

namespace sl::cli {

namespace {

/// DIR/STEM.csv (every run), DIR/STEM-median.csv and the plot DIR/STEM.png by
/// scripts/plot_STEM.py (a warning with the command when it cannot run).
void writeRaceOutputs(const std::filesystem::path& dir, const std::string& stem,
                      const std::vector<RaceRow>& rows, const std::vector<RaceRow>& medians) {
    const auto csv = dir / (stem + ".csv"), medianCsv = dir / (stem + "-median.csv"),
               png = dir / (stem + ".png");
    writeRaceCsv(csv, rows);
    writeRaceCsv(medianCsv, medians);
    const PlotOutcome plot = runPlotScript("plot_" + stem + ".py", {csv.string(), png.string()});
    if (!plot.ran || plot.exitCode != 0)
        std::fprintf(stderr, "warning: the plot failed (%s); plot with: %s\n",
                     plot.message.empty() ? "python3 with matplotlib needed" : plot.message.c_str(),
                     shellQuoted(plot.command).c_str());
    std::printf("wrote %s, %s and %s\n", csv.c_str(), medianCsv.c_str(), png.c_str());
}

struct RaceArgs {
    RaceOptions o;
    std::vector<std::string> configs;
    std::string out = "out/race";
};

int runRaceCmd(RaceArgs a) {
    if (!a.configs.empty()) {
        std::vector<RaceConfig> all = defaultRaceConfigs(), chosen;
        for (const auto& name : a.configs) {
            auto it = std::find_if(all.begin(), all.end(),
                                   [&](const RaceConfig& c) { return c.name == name; });
            if (it == all.end())
                throw UsageError("--configs: unknown configuration '" + name + "'");
            chosen.push_back(*it);
        }
        if (chosen.front().name != "paper-loop")
            chosen.insert(chosen.begin(), all.front());  // the baseline of every ratio
        a.o.configs = chosen;
    }
    a.o.workDir = a.out;
    a.o.log = [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); };
    const Stopwatch wall;
    RaceSummary s = runRace(a.o);
    std::printf(
        "medians over %d seed(s); ratios to paper-loop on the same part and seed; gap: "
        "judge score of the own objective over the training loss; xlamp, xpl: times better "
        "than the studio lamp, than paper-loop, on the part's figure (the defects' combined "
        "visibility; U where no defect is in view)\n",
        a.o.seeds);
    std::vector<RaceRow> med;
    for (size_t i = 0; i < s.medians.size(); ++i) {  // each part's configs, then its lamp
        med.push_back(s.medians[i]);
        if ((i + 1) % a.o.configs.size() == 0) med.push_back(s.lampMedians[i / a.o.configs.size()]);
    }
    std::printf("%s\n", formatRaceTable(med).c_str());
    std::printf("%s\n", formatRaceTable(s.overall).c_str());
    std::printf(
        "per configuration over %zu part(s): median and worst (min) of its per-part "
        "medians\n%s",
        s.lampMedians.size(), formatRaceStandings(s.standings).c_str());
    std::printf("%s: %s\n", kRaceWinnerRule, s.winner.c_str());
    std::printf("race wall time %.1f s\n", wall.seconds());
    std::vector<RaceRow> rows = s.rows;
    rows.insert(rows.end(), s.lamps.begin(), s.lamps.end());
    med.insert(med.end(), s.overall.begin(), s.overall.end());
    enterCommit();  // the last safe point: every output or none (core/Interrupt.h)
    writeRaceStandingsCsv(std::filesystem::path(a.out) / "race-configs.csv", s.standings);
    writeRaceOutputs(a.out, "race", rows, med);
    return kOk;
}

struct SettingsArgs {
    RaceOptions o;
    std::vector<int> spps{4, 16, 64}, depths{2, 3, 4};
    std::vector<std::string> samplings{"bsdf", "stratified", "mis"};
    std::string out = "out/settings";
};

int runSettingsCmd(SettingsArgs a) {
    std::vector<Sampling> samplings;
    for (const std::string& name : a.samplings) {
        const SamplingRow* row = findRegistryRow(samplingTable(), name);
        if (!row)
            throw UsageError("--sampling: unknown sampler '" + name + "' (" +
                             registryNames(samplingTable()) + ")");
        samplings.push_back(row->value);
    }
    a.o.configs = settingsRaceConfigs(a.spps, samplings, a.depths);
    if (!a.o.judgeMaxDepth)
        a.o.judgeMaxDepth = 2 + *std::max_element(a.depths.begin(), a.depths.end());
    a.o.workDir = a.out;
    a.o.log = [](const std::string& s) { std::fprintf(stderr, "%s\n", s.c_str()); };
    RaceSummary s = runRace(a.o);
    std::printf(
        "speed against error: optimize's default search on T traced at each setting; judge: %d "
        "spp, max_depth %d, held out; medians over %d seed(s); ratios to %s on the same part and "
        "seed\n",
        a.o.judgeSpp, *a.o.judgeMaxDepth, a.o.seeds, a.o.configs.front().name.c_str());
    std::printf("%s\n", formatRaceTable(s.medians).c_str());
    enterCommit();
    writeRaceOutputs(a.out, "settings", s.rows, s.medians);
    return kOk;
}

/// The options `bench race` and `bench settings` share: the parts, the training seeds, the
/// judge's spp and the output directory.
void addRaceRunOptions(CLI::App* c, RaceOptions& o, std::string& out) {
    std::string parts;
    for (const std::string& n : knownRaceParts()) parts += (parts.empty() ? "" : ", ") + n;
    c->add_option("--parts", o.parts, "Generated parts: " + parts)
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--real", o.real,
                  "Real textures (instrument height maps: .x3p, .opd, .plu, ...) with defects "
                  "inserted as insert-defects does");
    c->add_option("--sizes", o.sizes, "Image sizes (width = height) of every part")
        ->delimiter(',')
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--alphas", o.alphas,
                  "Surface roughness alpha (material.alpha; default: the part's)")
        ->delimiter(',')
        ->check(inRange(1e-4, 1.0));
    c->add_option("--height-scales", o.heightScales,
                  "Texture height (heightmap.height_scale) of every part")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--threads", o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("--seeds", o.seeds, "Training seeds per part")
        ->check(inRange(1, 100))
        ->capture_default_str();
    c->add_option("--heldout-spp", o.judgeSpp, "spp of the judge's held-out estimate")
        ->check(inRange(2, 1 << 20))
        ->capture_default_str();
    c->add_option("-o,--output", out, "Output directory (parts, cache, CSV, plot)")
        ->capture_default_str();
}

}  // namespace

void addRaceBench(CLI::App* c, std::function<int()>& run) {
    auto a = std::make_shared<RaceArgs>();
    addRaceRunOptions(c, a->o, a->out);
    c->add_option("--configs", a->configs, "Configurations (default: all; paper-loop always)")
        ->delimiter(',');
    c->callback([a, &run] { run = [a] { return runRaceCmd(*a); }; });
}

void addSettingsBench(CLI::App* st, std::function<int()>& run) {
    auto sa = std::make_shared<SettingsArgs>();
    sa->o.parts = {"ballend-chatter"};
    sa->o.seeds = 2;
    addRaceRunOptions(st, sa->o, sa->out);
    st->add_option("--spp", sa->spps, "Samples per pixel of T")
        ->delimiter(',')
        ->check(inRange(2, 1 << 16))
        ->capture_default_str();
    st->add_option("--sampling", sa->samplings, "Direction samplers (render.sampling)")
        ->delimiter(',')
        ->capture_default_str();
    st->add_option("--max-depth", sa->depths, "Path lengths of T")
        ->delimiter(',')
        ->check(inRange(2, 64))
        ->capture_default_str();
    st->add_option("--judge-max-depth", sa->o.judgeMaxDepth,
                   "The judge's path length (default: the longest of --max-depth + 2)")
        ->check(inRange(2, 64));
    st->callback([sa, &run] { run = [sa] { return runSettingsCmd(*sa); }; });
}

}  // namespace sl::cli
