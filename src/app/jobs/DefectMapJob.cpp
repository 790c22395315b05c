#include "app/jobs/DefectMapJob.h"

#include <sstream>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
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

    enterCommit();  // Ctrl-C before the files appear: none does; after: all (core/Interrupt.h)
    writeMaskPng(o.output, s.map.map, s.width, s.height);
    s.written.push_back(o.output);
    if (!o.imageOutput.empty()) {
        writeMaskPng(o.imageOutput, image, s.imageWidth, s.imageHeight);
        s.written.push_back(o.imageOutput);
    }
    if (s.score) {
        std::filesystem::path csv = o.csv;
        if (csv.empty()) csv = o.output.parent_path() / (o.output.stem().string() + "-score.csv");
        writeTextAtomically(csv, defectScoreCsv(*s.score));
        s.written.push_back(csv);
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
