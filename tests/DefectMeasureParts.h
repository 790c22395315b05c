// The test part the defects objective's measures (objective/JndObjective.h,
// BothMeasuresObjective.h) are checked on: a bumpy part seen through T's two halves, two
// labelled stripes of columns as its defects, and the JND measure's viewing options.
#pragma once

#include <cstdint>
#include <vector>

#include "TestUtil.h"
#include "objective/DefectObjective.h"
#include "objective/JndObjective.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl::test {

/// A 20×20 view of a bumpy 32×32 part, T in two independent halves.
inline TransportMatrix bumpyHalves(int spp) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.camera.origin = {0, 2, 2};
    d.camera.width = d.camera.height = 20;
    d.render.maxDepth = 3;
    const Scene scene(d, 32, 32, bumpyHeightMap(32));
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = 3;
    o.sampleSets = 2;
    return precomputeTransport(scene, o, 1).matrix;
}

/// Two labelled stripes of columns: [4, 7) label 1, [12, 14) label 2.
inline std::vector<uint8_t> twoStripes(const TransportMatrix& t) {
    std::vector<uint8_t> m(t.rows(), 0);
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x)
            m[static_cast<size_t>(y) * t.width + x] = x >= 4 && x < 7     ? 1
                                                      : x >= 12 && x < 14 ? 2
                                                                          : 0;
    return m;
}

/// The JND measure seen at 38.8 px/deg with a 200 cd/m² white, T's white furnace as the band's.
inline JndObjectiveOptions jndOptions(const TransportMatrix& t) {
    JndObjectiveOptions o;
    o.view.pixelsPerDegree = 38.8;
    o.view.whiteLuminance = 200;
    o.band.whiteMean = whiteFurnaceMean(t, t.objectMask);
    return o;
}

}  // namespace sl::test
