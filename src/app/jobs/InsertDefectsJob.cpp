#include "app/jobs/InsertDefectsJob.h"

#include <cmath>
#include <cstdio>

#include "app/jobs/PartFiles.h"
#include "core/Error.h"
#include "io/HeightmapIO.h"
#include "io/SceneFile.h"

namespace sl {

InsertDefectsJobSummary runInsertDefectsJob(const InsertDefectsJobOptions& o) {
    if (o.output.extension() != ".exr")
        throw inputError(option("output") + " '" + o.output.string() + "'", "must end in .exr",
                         "insert-defects writes float32 heights in mm (EXR), its truth and a "
                         "scene file beside it");
    if (!(o.depthSq > 0) && !(o.depthUm > 0))
        throw inputError(option("depth-sq"), "must be > 0 (or give " + option("depth-um") + ")");
    if (!(o.faintSq > 0)) throw inputError(option("faint-sq"), "must be > 0");
    if (o.size < 0 || o.size == 1) throw inputError(option("size"), "must be 0 (as read) or >= 2");
    if (o.pitch < 0 || !std::isfinite(o.pitch)) throw inputError(option("pitch"), "must be > 0");

    std::vector<float> h;
    int W = 0, H = 0;
    double pitch = 0;
    bool measured = false;  // the texture is a measurement: so is the map with defects in it
    if (o.input.extension() == ".json") {
        const std::unique_ptr<Scene> scene = loadScene(o.input, o.sceneOverrides);
        measured = scene->load.measured;
        h = scene->heights;
        W = scene->mapWidth;
        H = scene->mapHeight;
        pitch = scene->desc.heightmap.pitch;
    } else {
        if (!o.sceneOverrides.empty())
            throw inputError(o.input.string(), "scene overrides need a scene file",
                             "Give SCENE.json, or leave out the overrides");
        HeightmapData d = loadHeightmap(o.input, HeightmapOptions{});
        measured = d.measured();
        h = std::move(d.heights);
        W = d.width;
        H = d.height;
        if (d.pitch) pitch = *d.pitch;
    }
    if (o.pitch > 0) pitch = o.pitch;
    if (!(pitch > 0))
        throw inputError(o.input.string(), "carries no sample spacing",
                         "Give " + option("pitch") + " (mm) or a scene file with pixel_pitch");

    InsertDefectsJobSummary s;
    s.resampled = resampleToMaxSide(h, W, H, o.size);
    pitch *= s.resampled;
    s.width = W;
    s.height = H;
    s.pitch = pitch;
    s.sq = textureSq(h, W, H);
    s.depth = o.depthUm > 0 ? o.depthUm * 1e-3 : o.depthSq * s.sq;
    s.faintDepth = o.faintSq * s.sq;
    if (!(s.depth > 0) || !(s.faintDepth > 0))
        throw inputError(o.input.string(), "is flat (Sq 0): a depth relative to Sq is 0",
                         "Give " + option("depth-um"));
    InsertSpec spec = o.spec;
    spec.depth = s.depth;
    spec.faintDepth = s.faintDepth;
    s.result = insertDefects(h, W, H, spec);

    GeneratedSurface g;
    g.width = W;
    g.height = H;
    g.pitch = pitch;
    g.heights = s.result.heights;
    g.truth = s.result.truth;
    char desc[256];
    std::snprintf(desc, sizeof desc,
                  "%s with defects inserted (model %s, seed %llu; depth %.4g um = %.3g x Sq %.4g "
                  "um; faint %.4g um, unlabelled)",
                  o.input.filename().string().c_str(), spec.model == DefectModel::A ? "A" : "B",
                  static_cast<unsigned long long>(spec.seed), s.depth * 1e3, s.depth / s.sq,
                  s.sq * 1e3, s.faintDepth * 1e3);
    g.description = desc;

    PartFileOptions po;
    po.scene = o.output.parent_path() / (o.output.stem().string() + ".json");
    po.imageSize = o.imageSize;
    po.measured = measured;
    nlohmann::ordered_json tex;
    tex["source"] = o.input.string();
    tex["model"] = spec.model == DefectModel::A ? "A" : "B";
    tex["seed"] = spec.seed;
    tex["width"] = W;
    tex["height"] = H;
    tex["pitch_mm"] = pitch;
    tex["resampled"] = s.resampled;
    tex["sq_mm"] = s.sq;
    tex["depth_mm"] = s.depth;
    tex["faint_depth_mm"] = s.faintDepth;
    tex["skipped"] = s.result.skipped;
    po.legendExtra["texture"] = tex;
    po.legendExtra["inserted"] = nlohmann::ordered_json::array();
    for (const InsertedDefect& d : s.result.defects)
        po.legendExtra["inserted"].push_back(
            {{"kind", insertKindRow(d.kind).name},
             {"label", d.labelled ? insertKindRow(d.kind).label : 0},
             {"labelled", d.labelled},
             {"why", d.labelled ? "" : "faint: below what any light shows, kept out of the truth"},
             {"depth_mm", d.depth},
             {"centre", {d.x, d.z}},
             {"box", {d.x0, d.z0, d.x1, d.z1}},
             {"size_samples", d.size},
             {"samples", d.samples}});
    const PartFiles f = writePartFiles(g, o.output, po);
    s.written = {f.heightmap, f.truth, f.legend, f.scene};
    return s;
}

}  // namespace sl
