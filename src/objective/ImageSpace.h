// From height-map space to image space: which height-map sample each pixel sees.
//
// CONVENTION (primary hits): pixel (x, y) traces ONE ray, the camera ray through its centre,
// camera.generateRay(x + 0.5, y + 0.5), against the surface (closest hit, t > 0). The pixel's
// sample is the height-map sample NEAREST to the hit point in x–z (the frame of
// scene/Heightfield.h: i = round(x/p + (W−1)/2), j = round(z/p + (H−1)/2), clamped to the map),
// stored as the linear index j·W + i; −1 when the centre ray misses the part. A per-sample map
// (scratch map, ground-truth defect mask: both live on the samples) is projected into the image
// by reading it at that index. Pixels at the silhouette may differ from the renderer's object
// mask (every camera sample hit): intersect the projection with the object mask for a loss mask.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "detect/ScratchMap.h"

namespace sl {

struct Scene;

struct PrimaryHits {
    int width = 0, height = 0;        // image (the scene's camera)
    int mapWidth = 0, mapHeight = 0;  // height map
    std::vector<int64_t> sample;      // width*height: j*mapWidth + i, or −1 (miss)

    size_t hitCount() const;
};

/// Traces every pixel's centre ray (parallel, deterministic).
PrimaryHits tracePrimaryHits(const Scene& scene, int threads = 0);

/// Image mask (width*height, 255/0) of the pixels whose sample is nonzero in `mapMask`
/// (mapWidth*mapHeight, height-map space, nonzero = inside). Misses are 0.
/// Throws InputError if mapMask's size does not match the height map.
std::vector<uint8_t> projectToImage(const PrimaryHits& hits, std::span<const uint8_t> mapMask);

/// The same lookup keeping the map's values (label images: one value per region).
std::vector<uint8_t> projectLabelsToImage(const PrimaryHits& hits,
                                          std::span<const uint8_t> mapLabels);

/// optimize's `scratch` mask: computeScratchMap(scene.heights, options) projected into the image
/// (255/0, width*height). Intersect it with the object mask before using it as a loss mask.
std::vector<uint8_t> scratchMaskImage(const Scene& scene, const ScratchMapOptions& options = {},
                                      int threads = 0);

}  // namespace sl
