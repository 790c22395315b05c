// scratchlight info (HEIGHTMAP | SCENE.json) [-D key=value ...] [-o INFO.json]
// Prints what the readers found in a height map or a scene's: the work is app/jobs/InfoJob.h.
#include <cstdio>
#include <memory>
#include <string>

#include "app/jobs/InfoJob.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Text.h"
#include "io/AtomicFile.h"

namespace sl::cli {

namespace {

struct InfoArgs {
    InfoJobOptions job;
    std::string output;  // the summary as JSON, written too (empty: printed only)
};

int runInfo(const InfoArgs& a) {
    const InfoJobSummary s = runInfoJob(a.job);
    if (!a.output.empty()) writeTextAtomically(a.output, infoJson(s).dump(2) + "\n");
    const std::string unit = s.heightsInMm ? " mm" : " (as stored)";
    std::printf("file        %s\n", s.file.c_str());
    if (!s.scene.empty()) std::printf("scene       %s\n", s.scene.c_str());
    std::printf("reader      %s%s\n", s.reader.c_str(), s.measured ? " (a measurement)" : "");
    std::printf("size        %d x %d samples", s.width, s.height);
    if (s.pitch)
        std::printf(", %s x %s mm", formatNumber((s.width - 1) * *s.pitch, 4).c_str(),
                    formatNumber((s.height - 1) * *s.pitch, 4).c_str());
    std::printf("\n");
    if (s.pitch)
        std::printf("pitch       %s mm (the %s's)\n", formatNumber(*s.pitch).c_str(),
                    s.pitchFrom.c_str());
    else
        std::printf("pitch       none in the file (a scene must give heightmap.pixel_pitch)\n");
    if (!s.channel.empty()) std::printf("channel     %s\n", s.channel.c_str());
    std::printf("resampled   %s\n", s.resampling.empty() ? "no" : s.resampling.c_str());
    std::printf("invalid     %zu points filled\n", s.invalidFilled);
    std::printf("levelling   %s\n", s.levelling.text().c_str());
    std::printf("heights     %s .. %s%s, Sq %s%s (after levelling)\n",
                formatNumber(s.minHeight, 4).c_str(), formatNumber(s.maxHeight, 4).c_str(),
                unit.c_str(), formatNumber(s.sq, 4).c_str(), unit.c_str());
    for (const std::string& w : s.warnings) std::printf("warning     %s\n", w.c_str());
    if (!s.part.is_null()) {
        std::printf("material    %s\n", s.part.at("material").dump().c_str());
        std::printf("camera      %s\n", s.part.at("camera").dump().c_str());
    }
    if (!a.output.empty()) std::printf("wrote       %s\n", a.output.c_str());
    return kOk;
}

}  // namespace

void registerInfo(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<InfoArgs>();
    CLI::App* c = app.add_subcommand(
        "info",
        "Print what the readers found in a height map or a scene's: reader, pitch, resampling, "
        "size, heights and Sq after levelling, invalid points, the levelling in force");
    addHeightSourceInput(
        c, a->job.input, a->job.sceneOverrides,
        "Height map (X3P, SDF, an instrument's file, EXR, ...) or scene file (JSON)");
    c->add_option("-o,--output", a->output, "Also write the summary as JSON to this file");
    c->callback([a, &run] { run = [a] { return runInfo(*a); }; });
}

}  // namespace sl::cli
