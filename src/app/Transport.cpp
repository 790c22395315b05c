#include "app/Transport.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <nlohmann/json.hpp>

#include "app/HeldOut.h"
#include "core/Error.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct LoadedScene {
    std::unique_ptr<Scene> scene;
    RenderOptions render;
    TransportProvenance provenance;
};

LoadedScene load(const std::filesystem::path& file, const PrecomputeOptions& o) {
    SceneDesc desc = readSceneFile(file);
    if (o.spp) desc.render.spp = *o.spp;
    if (o.maxDepth) desc.render.maxDepth = *o.maxDepth;
    if (o.seed) desc.render.seed = *o.seed;
    LoadedScene l;
    l.scene = loadScene(desc);
    l.render = renderOptionsFor(*l.scene);
    l.render.threads = o.threads;
    l.render.sampleSets = o.sampleSets;
    l.render.progress = o.progress;
    l.provenance = transportProvenance(*l.scene, l.render, o.rgb ? 3 : 1);
    return l;
}

TransportSource trace(LoadedScene& l, bool rgb, const std::filesystem::path& out,
                      std::chrono::steady_clock::time_point t0) {
    PrecomputeResult r = precomputeTransport(*l.scene, l.render, rgb ? 3 : 1);
    TransportSource s;
    s.secondsTrace = r.summary.seconds;
    s.trace = r.summary;
    writeTransportFile(out, r.matrix, l.provenance);
    s.file.matrix = std::move(r.matrix);
    s.file.provenance = l.provenance;
    s.path = out;
    s.secondsTotal = since(t0);
    return s;
}

}  // namespace

bool isTransportFile(const std::filesystem::path& input) {
    return input.extension() == ".tm";
}

TransportSource heldOutFor(const TransportFile& training, int spp,
                           const std::filesystem::path& cacheDir,
                           const std::filesystem::path& sceneOverride) {
    using json = nlohmann::json;
    const json in = json::parse(training.provenance.inputs);
    std::filesystem::path scene = sceneOverride;
    if (scene.empty()) {
        if (!in.contains("scene_file"))
            throw inputError("held-out estimate", "the transport matrix does not record its scene",
                             "pass the scene file instead of the .tm, or --heldout none");
        scene = in.at("scene_file").get<std::string>();
    }
    PrecomputeOptions o;
    o.spp = spp > 0 ? spp : training.provenance.spp;
    o.seed = training.provenance.seed + kHeldOutSeedOffset;
    o.maxDepth = training.provenance.maxDepth;
    o.rgb = training.matrix.channels == 3;
    o.sampleSets = 2;
    TransportSource s = transportForScene(scene, o, cacheDir);
    // Same scene, camera, material and height map: only the sampling may differ.
    auto strip = [](json j) {
        for (const char* k : {"render", "planes", "scene_file"}) j.erase(k);
        j["heightmap"].erase("file");
        j["material"].erase("name");
        return j;
    };
    if (strip(json::parse(s.file.provenance.inputs)) != strip(in))
        throw inputError(scene.string(),
                         "has changed since the transport matrix was computed (camera, material "
                         "or height map differ)",
                         "recompute the transport matrix, or pass --heldout none");
    return s;
}

TransportSource precomputeToFile(const std::filesystem::path& scene,
                                 const PrecomputeOptions& options,
                                 const std::filesystem::path& out) {
    auto t0 = std::chrono::steady_clock::now();
    LoadedScene l = load(scene, options);
    return trace(l, options.rgb, out, t0);
}

TransportSource transportForScene(const std::filesystem::path& scene,
                                  const PrecomputeOptions& options,
                                  const std::filesystem::path& cacheDir) {
    auto t0 = std::chrono::steady_clock::now();
    LoadedScene l = load(scene, options);
    const auto cached = cacheDir / ("transport-" + l.provenance.fingerprint + ".tm");
    if (std::filesystem::exists(cached)) {
        try {
            TransportSource s;
            s.file = readTransportFile(cached, l.provenance.fingerprint);
            s.path = cached;
            s.cacheHit = true;
            s.secondsTotal = since(t0);
            spdlog::info("transport matrix from cache {}", cached.string());
            return s;
        } catch (const InputError& e) {
            spdlog::warn("ignoring cached transport matrix: {}", e.what());
        }
    }
    return trace(l, options.rgb, cached, t0);
}

}  // namespace sl
