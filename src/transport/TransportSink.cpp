#include "transport/TransportSink.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "core/Color.h"
#include "core/Error.h"
#include "scene/EnvMapBasis.h"
#include "scene/Scene.h"

namespace sl {

TransportSink::TransportSink(const EnvMapBasis& basis, int width, int height, int channels,
                             int planes)
    : basis_(basis),
      width_(width),
      height_(height),
      channels_(channels),
      planes_(planes),
      chunkEntries_(
          std::clamp<size_t>(size_t{2} * kBandRows * static_cast<size_t>(width), 1024, 65536)),
      bands_(static_cast<size_t>((height + kBandRows - 1) / kBandRows)),
      rows_(static_cast<size_t>(width) * height) {
    if (channels != 1 && channels != 3)
        throw std::invalid_argument("TransportSink: channels must be 1 or 3");
    if (planes != 1 && planes != 2) throw std::invalid_argument("TransportSink: planes is 1 or 2");
    if (basis.texelCount() > kMaxTransportTexels)
        throw inputError("envmap.width/height",
                         std::to_string(basis.width()) + "x" + std::to_string(basis.height()) +
                             " = " + std::to_string(basis.texelCount()) +
                             " texels, more than a transport matrix's limit of " +
                             std::to_string(kMaxTransportTexels),
                         "use a smaller env-map grid (default " +
                             std::to_string(kDefaultEnvMapGrid.width) + "x" +
                             std::to_string(kDefaultEnvMapGrid.height) + ")");
}

void TransportSink::consume(const PixelPaths& px) {
    // A per-thread dense accumulator over the texels (and planes): each path's weights are
    // added in path order where they land, and the touched texels, sorted, give the row's
    // columns. A sort of all entries by column cost 13 % of a precompute.
    const size_t texels = static_cast<size_t>(basis_.texelCount());
    const size_t planes = static_cast<size_t>(planes_);
    thread_local std::vector<std::array<double, 3>> acc;
    thread_local std::vector<uint8_t> seen;
    thread_local std::vector<uint16_t> touched;
    if (acc.size() != texels * 2) {
        acc.assign(texels * 2, {0.0, 0.0, 0.0});
        seen.assign(texels, 0);
    }
    touched.clear();
    const double planeScale = planes_;  // a half of the samples: weights were divided by spp
    for (const EscapedPath& p : px.paths) {
        TexelWeights tw = basis_.weights(p.direction);
        std::array<double, 3> w{p.weight.x, p.weight.y, p.weight.z};
        if (channels_ == 1) w = {luminance<double>(w[0], w[1], w[2]), 0, 0};
        const size_t plane = planes_ == 2 ? static_cast<size_t>(p.set) : 0;
        for (int k = 0; k < 4; ++k) {
            if (tw.weight[k] == 0.0f) continue;
            const double b = tw.weight[k] * planeScale;
            const auto c = static_cast<uint16_t>(tw.index[k]);
            if (!seen[c]) {
                seen[c] = 1;
                touched.push_back(c);
            }
            std::array<double, 3>& a = acc[c * planes + plane];
            for (int j = 0; j < 3; ++j) a[j] += w[j] * b;
        }
    }
    std::sort(touched.begin(), touched.end());
    thread_local std::vector<uint16_t> cols;
    thread_local std::vector<float> vals;
    cols.clear();
    vals.clear();
    for (uint16_t c : touched) {
        cols.push_back(c);
        for (size_t pl = 0; pl < planes; ++pl) {
            std::array<double, 3>& a = acc[c * planes + pl];
            for (int k = 0; k < channels_; ++k) vals.push_back(static_cast<float>(a[k]));
            a = {0.0, 0.0, 0.0};
        }
        seen[c] = 0;
    }
    if (cols.empty()) return;
    const size_t st = vals.size() / cols.size();
    Band& band = bands_[px.pixel / static_cast<uint32_t>(width_) / kBandRows];
    const std::lock_guard<std::mutex> hold(band.lock);
    if (band.chunks.empty() ||
        band.chunks.back().cols.size() + cols.size() > band.chunks.back().cols.capacity()) {
        Chunk& c = band.chunks.emplace_back();
        const size_t n = std::max(chunkEntries_, cols.size());
        c.cols.reserve(n);
        c.vals.reserve(n * st);
    }
    Chunk& c = band.chunks.back();
    rows_[px.pixel] = {static_cast<uint32_t>(band.chunks.size() - 1),
                       static_cast<uint32_t>(c.cols.size()), static_cast<uint32_t>(cols.size())};
    c.cols.insert(c.cols.end(), cols.begin(), cols.end());
    c.vals.insert(c.vals.end(), vals.begin(), vals.end());
}

TransportMatrix TransportSink::finish(const TraceSummary& summary) {
    TransportMatrix t;
    t.width = width_;
    t.height = height_;
    t.envWidth = basis_.width();
    t.envHeight = basis_.height();
    t.channels = channels_;
    t.planes = planes_;
    t.storage = TransportStorage::Sparse;
    t.rowPtr.assign(t.rows() + 1, 0);
    for (size_t r = 0; r < t.rows(); ++r) t.rowPtr[r + 1] = t.rowPtr[r] + rows_[r].count;
    t.colIdx.resize(t.rowPtr.back());
    const size_t st = static_cast<size_t>(t.stride());
    t.values.resize(t.rowPtr.back() * st);
    const size_t w = static_cast<size_t>(width_);
    for (size_t b = 0; b < bands_.size(); ++b) {
        const size_t r1 = std::min(t.rows(), (b + 1) * kBandRows * w);
        for (size_t r = b * kBandRows * w; r < r1; ++r) {
            const RowRef& ref = rows_[r];
            if (ref.count == 0) continue;
            const Chunk& c = bands_[b].chunks[ref.chunk];
            std::copy_n(c.cols.begin() + ref.offset, ref.count, t.colIdx.begin() + t.rowPtr[r]);
            std::copy_n(c.vals.begin() + ref.offset * st, ref.count * st,
                        t.values.begin() + t.rowPtr[r] * st);
        }
        std::vector<Chunk>().swap(bands_[b].chunks);
    }
    std::vector<RowRef>().swap(rows_);
    t.objectMask = summary.objectMask;
    return t;
}

PrecomputeResult precomputeTransport(const Scene& scene, const RenderOptions& options,
                                     int channels) {
    TransportSink sink(scene.basis, scene.camera.width(), scene.camera.height(), channels,
                       options.sampleSets);
    PrecomputeResult r;
    r.summary = PathTracer(scene).trace(options, sink);
    r.matrix = sink.finish(r.summary);
    chooseStorage(r.matrix);
    return r;
}

}  // namespace sl
