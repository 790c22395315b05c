#include "objective/Metrics.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/Color.h"

namespace sl {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double safeDiv(double a, double b) {
    return (std::isnan(a) || std::isnan(b) || b == 0.0) ? kNaN : a / b;
}

struct PairSum {
    double sum = 0;
    size_t n = 0;
    double mean() const { return n ? sum / static_cast<double>(n) : kNaN; }
};

nlohmann::json num(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace

double chromaUv01(double r, double g, double b) {
    double X, Y, Z, Xn, Yn, Zn;
    rgbToXyz(r, g, b, X, Y, Z);
    rgbToXyz(1.0, 1.0, 1.0, Xn, Yn, Zn);
    const double dn = Xn + 15.0 * Yn + 3.0 * Zn;
    const double un = 4.0 * Xn / dn, vn = 9.0 * Yn / dn;
    const double d = X + 15.0 * Y + 3.0 * Z;
    if (!(d > 0.0)) return 0.0;  // black (or negative): no chroma
    const double u = 4.0 * X / d, v = 9.0 * Y / d;
    const double y = std::max(0.0, Y / Yn);
    constexpr double eps = 216.0 / 24389.0, kappa = 24389.0 / 27.0;
    const double L = y > eps ? 116.0 * std::cbrt(y) - 16.0 : kappa * y;
    const double us = 13.0 * L * (u - un), vs = 13.0 * L * (v - vn);
    return std::sqrt(us * us + vs * vs) / 100.0;
}

VisibilityMetrics computeVisibilityMetrics(const MetricsInput& in) {
    const int W = in.width, H = in.height, C = in.channels;
    const size_t n = static_cast<size_t>(W) * H;
    auto fail = [](const std::string& what) {
        throw std::invalid_argument("computeVisibilityMetrics: " + what);
    };
    if (W < 1 || H < 1) fail("empty image");
    if (C != 1 && C != 3) fail("image channels must be 1 or 3");
    if (in.image.size() != n * C) fail("image size does not match width*height*channels");
    if (in.objectMask.size() != n) fail("object mask size does not match the image");
    if (!in.lossMask.empty() && in.lossMask.size() != n) fail("loss mask size mismatch");
    if (!in.truthMask.empty() && in.truthMask.size() != n) fail("truth mask size mismatch");
    if (in.envChannels != 1 && in.envChannels != 3) fail("env map channels must be 1 or 3");
    if (in.envmap.size() % in.envChannels != 0) fail("env map size is not a multiple of channels");

    std::vector<double> Y(n);
    for (size_t p = 0; p < n; ++p)
        Y[p] = C == 1 ? in.image[p]
                      : luminance(in.image[3 * p], in.image[3 * p + 1], in.image[3 * p + 2]);
    auto obj = [&](size_t p) { return in.objectMask[p] != 0; };
    auto inM = [&](size_t p) { return in.lossMask.empty() ? obj(p) : in.lossMask[p] != 0; };
    auto outM = [&](size_t p) { return obj(p) && !inM(p); };
    const bool hasTruth = !in.truthMask.empty();
    auto isDefect = [&](size_t p) { return in.truthMask[p] != 0; };

    PairSum inside, outside, defect, background;
    auto pair = [&](size_t a, size_t b) {
        const double d = std::abs(Y[b] - Y[a]);
        if (inM(a) && inM(b)) inside.sum += d, ++inside.n;
        if (outM(a) && outM(b)) outside.sum += d, ++outside.n;
        if (hasTruth && obj(a) && obj(b)) {
            PairSum& s = (isDefect(a) || isDefect(b)) ? defect : background;
            s.sum += d;
            ++s.n;
        }
    };
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = static_cast<size_t>(y) * W + x;
            if (x + 1 < W) pair(p, p + 1);
            if (y + 1 < H) pair(p, p + W);
        }

    VisibilityMetrics m;
    m.gradientInside = inside.mean();
    m.gradientOutside = outside.mean();
    m.gradientRatio = safeDiv(m.gradientInside, m.gradientOutside);
    m.pairsInside = inside.n;
    m.pairsOutside = outside.n;

    size_t clipped = 0;
    double sumDef = 0, sumRest = 0;
    size_t nDef = 0, nRest = 0;
    for (size_t p = 0; p < n; ++p) {
        if (!obj(p)) continue;
        ++m.objectPixels;
        bool clip = false;
        for (int c = 0; c < C; ++c) clip = clip || in.image[p * C + c] >= 1.0;
        clipped += clip;
        if (hasTruth) {
            if (isDefect(p))
                sumDef += Y[p], ++nDef;
            else
                sumRest += Y[p], ++nRest;
        }
    }
    m.clippedFraction =
        m.objectPixels ? static_cast<double>(clipped) / static_cast<double>(m.objectPixels) : kNaN;

    size_t small = 0;
    for (double e : in.envmap) small += e < 1e-3;
    m.envSparsity = in.envmap.empty()
                        ? kNaN
                        : static_cast<double>(small) / static_cast<double>(in.envmap.size());
    if (in.envChannels == 1 || in.envmap.empty()) {
        m.envMeanChroma = in.envmap.empty() ? kNaN : 0.0;
    } else {
        const size_t texels = in.envmap.size() / 3;
        double s = 0;
        for (size_t t = 0; t < texels; ++t)
            s += chromaUv01(in.envmap[3 * t], in.envmap[3 * t + 1], in.envmap[3 * t + 2]);
        m.envMeanChroma = s / static_cast<double>(texels);
    }

    if (hasTruth) {
        TruthMetrics t;
        t.defectGradient = defect.mean();
        t.backgroundGradient = background.mean();
        t.gradientRatio = safeDiv(t.defectGradient, t.backgroundGradient);
        t.defectPairs = defect.n;
        t.backgroundPairs = background.n;
        t.defectPixels = nDef;
        const double meanDef = nDef ? sumDef / static_cast<double>(nDef) : kNaN;
        const double meanRest = nRest ? sumRest / static_cast<double>(nRest) : kNaN;
        t.weberContrast = safeDiv(meanDef - meanRest, meanRest);
        m.truth = t;
    }
    return m;
}

nlohmann::json toJson(const VisibilityMetrics& m) {
    nlohmann::json j;
    j["gradient_inside"] = num(m.gradientInside);
    j["gradient_outside"] = num(m.gradientOutside);
    j["gradient_ratio"] = num(m.gradientRatio);
    j["pairs_inside"] = m.pairsInside;
    j["pairs_outside"] = m.pairsOutside;
    j["clipped_fraction"] = num(m.clippedFraction);
    j["object_pixels"] = m.objectPixels;
    j["env_sparsity"] = num(m.envSparsity);
    j["env_mean_chroma"] = num(m.envMeanChroma);
    if (m.truth) {
        const TruthMetrics& t = *m.truth;
        j["truth"] = {{"defect_gradient", num(t.defectGradient)},
                      {"background_gradient", num(t.backgroundGradient)},
                      {"gradient_ratio", num(t.gradientRatio)},
                      {"weber_contrast", num(t.weberContrast)},
                      {"defect_pairs", t.defectPairs},
                      {"background_pairs", t.backgroundPairs},
                      {"defect_pixels", t.defectPixels}};
    } else {
        j["truth"] = nullptr;
    }
    return j;
}

}  // namespace sl
