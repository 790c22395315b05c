#include "transport/TransportSink.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "core/Color.h"
#include "core/Error.h"
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
                         "use a smaller env-map grid (default 50x25)");
}

void TransportSink::consume(const PixelPaths& px) {
    struct Entry {
        uint16_t col;
        uint16_t plane;
        std::array<double, 3> v;
    };
    thread_local std::vector<Entry> entries;
    entries.clear();
    const double planeScale = planes_;  // a half of the samples: weights were divided by spp
    for (const EscapedPath& p : px.paths) {
        TexelWeights tw = basis_.weights(p.direction);
        std::array<double, 3> w{p.weight.x, p.weight.y, p.weight.z};
        if (channels_ == 1) w = {luminance<double>(w[0], w[1], w[2]), 0, 0};
        const auto plane = static_cast<uint16_t>(planes_ == 2 ? p.set : 0);
        for (int k = 0; k < 4; ++k) {
            if (tw.weight[k] == 0.0f) continue;
            const double b = tw.weight[k] * planeScale;
            entries.push_back(
                {static_cast<uint16_t>(tw.index[k]), plane, {w[0] * b, w[1] * b, w[2] * b}});
        }
    }
    std::sort(entries.begin(), entries.end(),
              [](const Entry& a, const Entry& b) { return a.col < b.col; });
    thread_local std::vector<uint16_t> cols;
    thread_local std::vector<float> vals;
    cols.clear();
    vals.clear();
    for (size_t i = 0; i < entries.size();) {
        std::array<std::array<double, 3>, 2> sum{};
        const uint16_t c = entries[i].col;
        for (; i < entries.size() && entries[i].col == c; ++i)
            for (int k = 0; k < 3; ++k) sum[entries[i].plane][k] += entries[i].v[k];
        cols.push_back(c);
        for (int pl = 0; pl < planes_; ++pl)
            for (int k = 0; k < channels_; ++k) vals.push_back(static_cast<float>(sum[pl][k]));
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
