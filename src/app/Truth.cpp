#include "app/Truth.h"

#include "objective/ImageSpace.h"
#include "scene/Scene.h"

namespace sl {

std::vector<uint8_t> projectMaskFile(const Scene& scene, const std::filesystem::path& file,
                                     int threads) {
    const std::vector<uint8_t> m = loadHeightMapMask(file, scene.mapWidth, scene.mapHeight);
    return projectToImage(tracePrimaryHits(scene, threads), m);
}

LabelMask projectTruth(const Scene& scene, const std::filesystem::path& truth, int threads) {
    LabelMask m = readLabelMask(truth, scene.mapWidth, scene.mapHeight);
    const PrimaryHits hits = tracePrimaryHits(scene, threads);
    LabelMask out;
    out.width = hits.width;
    out.height = hits.height;
    out.legend = std::move(m.legend);
    out.labels = projectLabelsToImage(hits, m.labels);
    return out;
}

}  // namespace sl
