// TransportSink: the path tracer's escaped paths, recorded as rows of T instead of pixel values.
// Each path adds its throughput (luminance for a gray T, RGB for an RGB T) times the env map's
// bilinear weights (EnvMapBasis::weights, the one convention) into its pixel's row; rows are
// accumulated in double and stored as float32.
#pragma once

#include <cstdint>
#include <mutex>
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
    /// The rows of each band of kBandRows image rows, kept until finish() in chunks of
    /// chunkEntries_ entries (a row never spans two; 2 entries per pixel of a band, 1024 to
    /// 65536): no allocation per pixel, and at most one partly filled chunk per band. Vectors
    /// grown pixel by pixel held up to twice their size plus 48 bytes a pixel; the trace's peak
    /// memory is these lists plus the CSR arrays finish() fills.
    struct Chunk {
        std::vector<uint16_t> cols;  // reserved to capacity once, never reallocated
        std::vector<float> vals;
    };
    struct Band {
        std::mutex lock;
        std::vector<Chunk> chunks;
    };
    struct RowRef {
        uint32_t chunk = 0, offset = 0, count = 0;  // in its band; count 0: no entries
    };
    static constexpr int kBandRows = 16;

    const EnvMapBasis& basis_;
    int width_, height_, channels_, planes_;
    size_t chunkEntries_;
    std::vector<Band> bands_;
    std::vector<RowRef> rows_;  // per pixel
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
