#include "objective/Autodiff.h"

#include <ceres/jet.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/Color.h"
#include "core/Stopwatch.h"
#include "render/PathTracer.h"
#include "scene/Scene.h"

namespace sl {

PathRecording::PathRecording(const EnvMapBasis& basis, int width, int height)
    : basis_(basis), width_(width), height_(height), paths_(static_cast<size_t>(width) * height) {}

void PathRecording::consume(const PixelPaths& px) {
    auto& out = paths_.at(px.pixel);
    out.clear();
    out.reserve(px.paths.size());
    for (const EscapedPath& p : px.paths) {
        Path r;
        r.luminance = luminance<double>(p.weight.x, p.weight.y, p.weight.z);
        r.texels = basis_.weights(p.direction);
        out.push_back(r);
    }
}

size_t PathRecording::pathCount() const {
    size_t n = 0;
    for (const auto& v : paths_) n += v.size();
    return n;
}

PathRecording recordPaths(const Scene& scene, const RenderOptions& options, TraceSummary* summary) {
    PathRecording rec(scene.basis, scene.camera.width(), scene.camera.height());
    TraceSummary s = PathTracer(scene).trace(options, rec);
    if (summary) *summary = std::move(s);
    return rec;
}

namespace {

using Jet = ceres::Jet<double, kAutodiffChunk>;

/// Runs evalChunk(E_jet) for every chunk of kAutodiffChunk texels, seeding the dual parts of
/// that chunk's texels, and gathers the gradient.
template <typename F>
AutodiffGradient autodiffChunks(std::span<const double> E, int threads, F&& evalChunk) {
    const Stopwatch clock;
    const size_t n = E.size();
    const size_t chunks = (n + kAutodiffChunk - 1) / kAutodiffChunk;
    AutodiffGradient g;
    g.gradient.assign(n, 0.0);
    g.passes = static_cast<int>(chunks);
    std::vector<double> losses(chunks, 0.0);
    auto body = [&](const tbb::blocked_range<size_t>& range) {
        std::vector<Jet> ej(n);
        for (size_t c = range.begin(); c < range.end(); ++c) {
            const size_t c0 = c * kAutodiffChunk, c1 = std::min(n, c0 + kAutodiffChunk);
            for (size_t i = 0; i < n; ++i) ej[i] = Jet(E[i]);
            for (size_t i = c0; i < c1; ++i) ej[i] = Jet(E[i], static_cast<int>(i - c0));
            const Jet loss = evalChunk(std::span<const Jet>(ej));
            losses[c] = loss.a;
            for (size_t i = c0; i < c1; ++i) g.gradient[i] = loss.v[static_cast<int>(i - c0)];
        }
    };
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1), body); });
    g.loss = chunks > 0 ? losses[0] : 0.0;
    for (double v : g.gradient)
        if (!std::isfinite(v))
            throw std::range_error(
                "autodiff: the gradient is not finite (a NaN or Inf in the chain)");
    g.seconds = clock.seconds();
    return g;
}

}  // namespace

AutodiffGradient autodiffThroughPaths(const PathRecording& paths, const ImageObjective& objective,
                                      std::span<const double> E, int threads) {
    if (E.size() != static_cast<size_t>(paths.texelCount()))
        throw std::invalid_argument("autodiffThroughPaths: E has " + std::to_string(E.size()) +
                                    " values, the env map " + std::to_string(paths.texelCount()) +
                                    " texels (gray)");
    if (static_cast<size_t>(objective.width()) * objective.height() != paths.pixelCount())
        throw std::invalid_argument("autodiffThroughPaths: objective image size != recording's");
    return autodiffChunks(E, threads, [&](std::span<const Jet> ej) {
        return lossThroughPaths<Jet>(paths, objective, ej);
    });
}

AutodiffGradient autodiffThroughMatrix(const TransportMatrix& t, const ImageObjective& objective,
                                       std::span<const double> E, int threads) {
    if (t.channels != 1 || t.planes != 1)
        throw std::invalid_argument(
            "autodiffThroughMatrix: needs a gray transport matrix with one plane");
    if (E.size() != t.cols())
        throw std::invalid_argument("autodiffThroughMatrix: E has " + std::to_string(E.size()) +
                                    " values, T " + std::to_string(t.cols()) + " columns");
    if (static_cast<size_t>(objective.width()) * objective.height() != t.rows())
        throw std::invalid_argument("autodiffThroughMatrix: objective image size != T's rows");
    return autodiffChunks(E, threads, [&](std::span<const Jet> ej) {
        return lossThroughMatrix<Jet>(t, objective, ej);
    });
}

namespace {

template <typename HalfObjective>
AutodiffGradient halvesByChunks(const TransportMatrix& t, const HalfObjective& objective,
                                std::span<const double> E, int threads) {
    if (t.channels != 1 || t.planes != 2)
        throw std::invalid_argument(
            "autodiffThroughHalves: needs a gray transport matrix with two planes");
    if (E.size() != t.cols())
        throw std::invalid_argument("autodiffThroughHalves: E has " + std::to_string(E.size()) +
                                    " values, T " + std::to_string(t.cols()) + " columns");
    if (static_cast<size_t>(objective.width()) * objective.height() != t.rows())
        throw std::invalid_argument("autodiffThroughHalves: objective image size != T's rows");
    return autodiffChunks(E, threads, [&](std::span<const Jet> ej) {
        return lossThroughHalves<Jet, HalfObjective>(t, objective, ej);
    });
}

}  // namespace

AutodiffGradient autodiffThroughHalves(const TransportMatrix& t, const DefectObjective& objective,
                                       std::span<const double> E, int threads) {
    return halvesByChunks(t, objective, E, threads);
}

AutodiffGradient autodiffThroughHalves(const TransportMatrix& t, const JndObjective& objective,
                                       std::span<const double> E, int threads) {
    return halvesByChunks(t, objective, E, threads);
}

AutodiffGradient autodiffThroughHalves(const TransportMatrix& t,
                                       const BothMeasuresObjective& objective,
                                       std::span<const double> E, int threads) {
    return halvesByChunks(t, objective, E, threads);
}

GradientError compareGradients(std::span<const double> g, std::span<const double> ref) {
    if (g.size() != ref.size())
        throw std::invalid_argument("compareGradients: sizes differ (" + std::to_string(g.size()) +
                                    " vs " + std::to_string(ref.size()) + ")");
    double d2 = 0, r2 = 0, g2 = 0, dot = 0;
    for (size_t i = 0; i < g.size(); ++i) {
        const double d = g[i] - ref[i];
        d2 += d * d;
        r2 += ref[i] * ref[i];
        g2 += g[i] * g[i];
        dot += g[i] * ref[i];
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    GradientError e;
    e.relativeL2 = r2 > 0 ? std::sqrt(d2 / r2) : nan;
    e.cosine = (r2 > 0 && g2 > 0) ? dot / std::sqrt(r2 * g2) : nan;
    return e;
}

}  // namespace sl
