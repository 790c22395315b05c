// TransportSink: the path tracer's escaped paths, recorded as rows of T instead of pixel values.
// Each path adds its throughput (luminance for a gray T, RGB for an RGB T) times the env map's
// bilinear weights (EnvMapBasis::weights, the one convention) into its pixel's row; rows are
// accumulated in double and stored as float32.
#pragma once

#include <cstdint>
#include <vector>

#include "render/PathSink.h"
#include "render/PathTracer.h"
#include "scene/EnvMapBasis.h"
#include "transport/TransportMatrix.h"

namespace sl {

struct Scene;

class TransportSink : public PathSink {
  public:
    /// planes: 1 (T), or 2 (the halves T_a, T_b from sample sets 0 and 1; each scaled by 2 so
    /// that it is an unbiased estimate on its own and T = (T_a + T_b)/2).
    TransportSink(const EnvMapBasis& basis, int width, int height, int channels, int planes = 1);
    void consume(const PixelPaths& pixel) override;
    /// Assembles the CSR matrix (call once, after the trace).
    TransportMatrix finish(const TraceSummary& summary);

  private:
    const EnvMapBasis& basis_;
    int width_, height_, channels_, planes_;
    std::vector<std::vector<uint16_t>> cols_;
    std::vector<std::vector<float>> vals_;
};

struct PrecomputeResult {
    TransportMatrix matrix;
    TraceSummary summary;
};

/// Traces the scene once with a TransportSink (same tracer, same samples as `render`).
/// channels: 1 (gray T) or 3 (RGB T). options.sampleSets == 2 stores the two halves (planes).
/// Storage is chosen from the measured density.
PrecomputeResult precomputeTransport(const Scene& scene, const RenderOptions& options,
                                     int channels);

}  // namespace sl
