#include "app/pipeline/JudgeEstimate.h"

#include <nlohmann/json.hpp>

#include "app/pipeline/Judge.h"
#include "core/Error.h"
#include "scene/Scene.h"

namespace sl {

TransportSource judgeEstimateFor(const TransportFile& training, const Scene& scene, int spp,
                                 const std::filesystem::path& cacheDir) {
    using json = nlohmann::json;
    const json trainingInputs = json::parse(training.provenance.inputs);
    if (trainingInputs.value("tracer_revision", 1) != kTracerRevision)
        throw inputError(
            "transport matrix " + training.provenance.fingerprint,
            "was traced by an older scratchlight tracer (revision " +
                std::to_string(trainingInputs.value("tracer_revision", 1)) + ", this one is " +
                std::to_string(kTracerRevision) +
                "), so an estimate traced now would not be comparable",
            "recompute it with `scratchlight precompute`, or pass " + option("heldout") + " none");
    PrecomputeOptions o;
    o.spp = spp > 0 ? spp : kJudgeDefaultSpp;
    o.seed = kJudgeSeed;
    o.maxDepth = training.provenance.maxDepth;
    o.rgb = training.matrix.channels == 3;
    o.sampleSets = 2;
    o.label = "judge estimate (held out)";
    TransportSource s = transportInDoublings(scene, o, kJudgeDoublingBase, cacheDir);
    // Same scene, camera, material and height map: only the sampling may differ, and the
    // renderer (a T from another renderer's basis renders, app/host/ExternalRenderer.h, is judged
    // on our tracer's estimate: the cross-renderer check).
    auto strip = [](json j) {
        for (const char* k :
             {"render", "planes", "scene_file", "scene_overrides", "renderer", "pixels", "doubled"})
            j.erase(k);
        j["heightmap"].erase("file");
        j["material"].erase("name");
        return j;
    };
    if (strip(json::parse(s.file.provenance.inputs)) != strip(trainingInputs))
        throw inputError(scene.desc.file.string(),
                         "has changed since the transport matrix was computed (camera, material "
                         "or height map differ)",
                         "recompute the transport matrix, or pass " + option("heldout") + " none");
    return s;
}

}  // namespace sl
