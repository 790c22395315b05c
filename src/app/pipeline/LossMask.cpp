#include "app/pipeline/LossMask.h"

#include <algorithm>

#include "core/Error.h"
#include "core/Registry.h"
#include "io/MaskIO.h"
#include "objective/ImageSpace.h"
#include "objective/Objective.h"
#include "scene/Scene.h"
#include "transport/TransportMatrix.h"

namespace sl {

namespace {

constexpr LossMaskKindRow kKinds[] = {
    {LossMaskKind::Object, "object", "the whole part (default)"},
    {LossMaskKind::Scratch, "scratch", "the paper's scratch map projected into the image"},
    {LossMaskKind::File, "FILE", "a PNG/EXR in image space, white inside"},
};

}  // namespace

std::span<const LossMaskKindRow> lossMaskKindTable() {
    return kKinds;
}

std::string LossMaskSpec::name() const {
    return kind == LossMaskKind::File ? file.string() : registryRow(lossMaskKindTable(), kind).name;
}

LossMaskSpec parseLossMask(std::string_view text) {
    LossMaskSpec s;
    if (const LossMaskKindRow* r = findRegistryRow(lossMaskKindTable(), text);
        r && r->value != LossMaskKind::File) {
        s.kind = r->value;
        return s;
    }
    s.kind = LossMaskKind::File;
    s.file = std::string(text);
    return s;
}

LossMask lossMask(const LossMaskSpec& spec, const TransportMatrix& t, const Scene* scene,
                  const ScratchMapOptions& scratch) {
    LossMask m;
    m.pixels = t.objectMask;
    switch (spec.kind) {
        case LossMaskKind::Object:
            break;
        case LossMaskKind::Scratch:
            if (!scene)
                throw inputError(option("mask") + " scratch", "needs the scene",
                                 "pass SCENE.json, or a .tm whose scene file is readable");
            m.scratchCells =
                computeScratchMap(scene->heights, scene->mapWidth, scene->mapHeight, scratch).map;
            m.pixels =
                intersectMasks(m.pixels, projectToImage(tracePrimaryHits(*scene), m.scratchCells));
            break;
        case LossMaskKind::File:
            m.pixels = intersectMasks(m.pixels, loadImageMask(spec.file, t.width, t.height));
            break;
    }
    for (uint8_t v : m.pixels) m.count += v != 0;
    if (m.count == 0) {
        if (spec.kind == LossMaskKind::Object)
            throw inputError("scene", "the camera sees none of the part",
                             "point the camera at the part (see the scene file's camera)");
        throw inputError(option("mask") + " " + spec.name(), "the mask is empty on the part",
                         spec.kind == LossMaskKind::Scratch ? "lower " + option("scratch-threshold")
                                                            : "draw a larger region");
    }
    return m;
}

std::vector<uint8_t> lossMaskRegion(const LossMaskSpec& spec, const Scene& scene,
                                    const ScratchMapOptions& scratch) {
    std::vector<uint8_t> region;
    switch (spec.kind) {
        case LossMaskKind::Object:
            return region;
        case LossMaskKind::Scratch:
            region = scratchMaskImage(scene, scratch);
            break;
        case LossMaskKind::File:
            region = loadImageMask(spec.file, scene.camera.width(), scene.camera.height());
            break;
    }
    if (std::none_of(region.begin(), region.end(), [](uint8_t v) { return v != 0; }))
        throw inputError(option("mask") + " " + spec.name(), "the mask is empty",
                         spec.kind == LossMaskKind::Scratch ? "lower " + option("scratch-threshold")
                                                            : "draw a larger region");
    return region;
}

}  // namespace sl
