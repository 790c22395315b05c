#include "app/jobs/DefectMapJob.h"

#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "app/report/Preview.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/MaskIO.h"
#include "io/SceneFile.h"
#include "objective/ImageSpace.h"
#include "scene/Scene.h"

namespace sl {

namespace {

void checkPng(const std::filesystem::path& file, const std::string& what) {
    if (file.extension() != ".png")
        throw inputError(what + " '" + file.string() + "'", "must end in .png",
                         "The map is an 8-bit PNG (255 marked, 0 not)");
}

// A second output beside the map: `given`, else <output stem><suffix> in the map's folder.
std::filesystem::path besideMap(const std::filesystem::path& output,
                                const std::filesystem::path& given, const std::string& suffix) {
    return !given.empty() ? given : output.parent_path() / (output.stem().string() + suffix);
}

}  // namespace

DefectMapJobSummary runDefectMapJob(const DefectMapJobOptions& o) {
    const Stopwatch clock;
    checkPng(o.output, option("output"));
    const bool isScene = o.input.extension() == ".json";
    if (!o.imageOutput.empty()) {
        checkPng(o.imageOutput, option("image-output"));
        if (!isScene)
            throw inputError(
                option("image-output"),
                "needs a scene file (its camera), not a bare height map '" + o.input.string() + "'",
                "Give SCENE.json as the input");
    }
    // No output replaces what this run reads (the height map, the truth or its legend).
    std::vector<std::filesystem::path> inputs{o.input};
    if (isScene)
        for (const auto& f : sceneInputFiles(readSceneFile(o.input, o.sceneOverrides)))
            inputs.push_back(f);
    if (!o.truth.empty()) {
        inputs.push_back(o.truth);
        inputs.push_back(std::filesystem::path(o.truth).replace_extension(".json"));  // legend
    }
    const std::filesystem::path csv =
        o.truth.empty() ? std::filesystem::path() : besideMap(o.output, o.csv, "-score.csv");
    refuseOutputOverInput(o.output, option("output"), inputs);
    refuseOutputOverInput(o.imageOutput, option("image-output"), inputs);
    refuseOutputOverInput(csv, option("score-output"), inputs);
    const std::filesystem::path unjudged = besideMap(o.output, o.unjudgedOutput, "-unjudged.png"),
                                preview = besideMap(o.output, o.previewOutput, "-preview.png");
    for (const auto& [file, name] :
         {std::pair{unjudged, "unjudged-output"}, std::pair{preview, "preview-output"}}) {
        checkPng(file, option(name));
        refuseOutputOverInput(file, option(name), inputs);
    }
    // Every output staged before the work (a directory in the way is refused now, not after
    // it), renamed into place together at the end: none appears unless all do.
    AtomicOutput mapOut(o.output), previewOut(preview);
    std::optional<AtomicOutput> imageOut, csvOut, unjudgedOut;
    if (!o.imageOutput.empty()) imageOut.emplace(o.imageOutput);
    if (!csv.empty()) csvOut.emplace(csv);
    const HeightSource src = loadHeightSource(o.input, o.sceneOverrides);
    const std::vector<float>& h = src.heights();
    DefectMapJobSummary s;
    s.width = src.width();
    s.height = src.height();
    std::optional<LabelMask> truth;
    if (!o.truth.empty()) truth = readLabelMask(o.truth, s.width, s.height);

    {
        const ProgressTask task("defect map (" + std::to_string(s.width) + "x" +
                                std::to_string(s.height) + ")");
        DefectMapOptions mo = o.map;
        mo.measured = src.measured();
        if (methodInForce(mo) == DefectMethod::SelfSim) unjudgedOut.emplace(unjudged);
        s.map = detectDefects(h, s.width, s.height, mo);
    }
    if (truth) s.score = scoreDefectMap(s.map.map, truth->labels, truth->legend, o.negatives);
    std::vector<uint8_t> image;
    if (!o.imageOutput.empty()) {
        const PrimaryHits hits = tracePrimaryHits(*src.scene);
        image = projectToImage(hits, s.map.map);
        s.imageWidth = hits.width;
        s.imageHeight = hits.height;
        s.imagePartPixels = hits.hitCount();
        for (uint8_t v : image) s.imageMarked += v != 0;
    }

    writeMaskPng(mapOut.tempPath(), s.map.map, s.width, s.height);
    if (imageOut) writeMaskPng(imageOut->tempPath(), image, s.imageWidth, s.imageHeight);
    if (csvOut) writeTextAtomically(csvOut->tempPath(), defectScoreCsv(*s.score));
    if (unjudgedOut) writeMaskPng(unjudgedOut->tempPath(), s.map.unjudged, s.width, s.height);
    writePng(previewOut.tempPath(),
             defectMapPreview(h, s.width, s.height, s.map.map, s.map.unjudged));
    enterCommit();  // Ctrl-C before the files appear: none does; after: all (core/Interrupt.h)
    for (AtomicOutput* out : {&mapOut, &previewOut, imageOut ? &*imageOut : nullptr,
                              csvOut ? &*csvOut : nullptr, unjudgedOut ? &*unjudgedOut : nullptr})
        if (out) {
            out->commit();
            s.written.push_back(out->finalPath());
        }
    s.seconds = clock.seconds();
    return s;
}

std::string defectScoreCsv(const DefectScore& score) {
    std::ostringstream os;
    os.precision(6);
    os << "kind,value,truth,hits,marked,precision,recall,f1\n";
    auto row = [&os](const DefectScoreRow& r) {
        os << r.name << ',' << static_cast<int>(r.value) << ',' << r.truth << ',' << r.hits << ','
           << r.marked << ',' << r.precision << ',' << r.recall << ',' << r.f1 << '\n';
    };
    row(score.overall);
    for (const DefectScoreRow& r : score.kinds) row(r);
    return os.str();
}

}  // namespace sl
