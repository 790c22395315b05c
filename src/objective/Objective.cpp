// The paper's objective (Motegi et al. §3.2, eq. 1–3) on a luminance image Y, exactly defined.
//
//   Loss = L_grad(Y) + λ · L_reg,   L_grad = S / G
//
// Image layout: Y is row-major, width × height, row 0 = top (core/Image.h). The mask M has the
// same layout; a pixel is inside when its byte is nonzero.
//
// Differences: forward differences, Δx(x,y) = Y(x+1,y) − Y(x,y) for x < width−1 and
// Δy(x,y) = Y(x,y+1) − Y(x,y) for y < height−1. Pairs that would leave the image are omitted
// (no padding, no wrap-around).
//
// Pair mask (a deliberate deviation from the paper): a difference counts only if BOTH of its
// pixels are inside M. The paper writes M_ij·(|Δx| + |Δy|), which masks only the first pixel,
// so the step from the part to the black background (Mitsuba's hide_emitters, our background
// = 0) would be counted along the right and bottom edges of the mask but not along its left and
// top edges. That silhouette step is not a defect, it is typically the largest |Δ| in the
// image, and its size grows with the part's overall brightness: with the paper's mask the
// optimizer can lower L_grad by lighting the whole part brighter, which is exactly the
// blow-out the L2 term then has to fight. Counting only pairs fully inside M makes G measure
// the part's own texture (scratches, tool marks) and makes it symmetric in the mask's edges.
//
//   S = Σ_p M_p                      (number of inside pixels; isolated pixels count in S only)
//   G = Σ_{counted pairs} |Δ|
//
// |x|: by default the exact |x| with the sub-gradient sign(0) = 0 (a pair with Δ = 0
// contributes nothing to the gradient). ObjectiveOptions::smoothAbs replaces it by
// |x|_ε = sqrt(x² + ε²) − ε (0 at 0, derivative x / sqrt(x² + ε²)), evaluated as
// x² / (sqrt(x² + ε²) + ε) to avoid cancellation near 0; ε = smoothEps > 0, in luminance units.
//
// Gradient: dL_grad/dY = −(S/G²) · dG/dY, where dG/dY_p = Σ over counted pairs (p, q) that touch
// p of ±sign(Δ) (+ when p is the pair's second pixel q, − when it is the first), or of
// ±Δ/sqrt(Δ² + ε²) with the smooth |x|. gradientSigns() returns exactly this s = dG/dY and G, so
// a fused kernel can form dL/dY = lGradScale(G)·s (+ the image regulariser's 2λY/(W·H)) itself.
//
// G → 0: the floor G_min = 1e-12·S (> 0 because S ≥ 1). If G < G_min then L_grad = S/G_min,
// the gradient of L_grad is 0 and LossParts::clamped = true. This makes every image with
// (almost) no contrast inside M a stationary point of L_grad, on a plateau of value 1e12. In
// particular E = 0 (Y = T·0 = 0, and the EnvMap regulariser's gradient 2λE/N = 0 there too) is
// a stationary point of the whole loss: an optimizer started at E = 0 never moves, so never
// start there. The same holds for a constant image inside M.
//
// Regulariser (without λ):
//   RegTarget::EnvMap: L_reg = Σ E² / N over all N entries of E (texels × channels), the
//                      paper's eq. 3; dLoss/dE = 2λE/N. E must not be empty.
//   RegTarget::Image:  L_reg = Σ_p Y_p² / (W·H) over every pixel (not only M), the paper's
//                      ablation; its gradient 2λY/(W·H) is added to dLdY, dLdE = 0.
// total = L_grad + λ·L_reg.
//
// Numerics and checks: sums in double; the same traversal (detail::forEachMaskedPair) and |x|
// (detail::objectiveAbs) are used by evaluate(), gradientSigns() and value<T>, so
// value<double> reproduces evaluate().total. Sizes are checked, a non-finite entry in Y or E
// throws std::invalid_argument naming the array and index, and a non-finite loss (overflow of
// huge inputs) throws std::range_error: no NaN leaves silently. On a throw, the output spans
// hold unspecified values. An empty mask, a mask of the wrong size, a non-positive size or bad
// options (λ < 0 or not finite, smooth ε ≤ 0) are InputErrors from the constructor.

#include "objective/Objective.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/Error.h"
#include "core/Text.h"

namespace sl {

namespace {

std::string sizeStr(int w, int h) {
    return std::to_string(w) + "x" + std::to_string(h);
}

// G and, if s is non-null, s = dG/dY (s must be zeroed by the caller), over the pairs whose
// first pixel lies in rows [y0, y1) (default: all). Y and s hold the image from pixel index
// `base` on (base = firstRow·width), so a band of rows can live in a small buffer.
double accumulateG(int width, int height, const std::vector<uint8_t>& mask, const double* Y,
                   double* s, bool smooth, double eps, int y0 = 0, int y1 = -1, size_t base = 0) {
    double G = 0.0;
    if (!s) {
        detail::forEachMaskedPair(
            width, height, mask.data(),
            [&](size_t p, size_t q) {
                G += detail::objectiveAbs<double>(Y[q - base] - Y[p - base], smooth, eps);
            },
            y0, y1);
        return G;
    }
    if (smooth) {
        const double eps2 = eps * eps;
        detail::forEachMaskedPair(
            width, height, mask.data(),
            [&](size_t p, size_t q) {
                const double d = Y[q - base] - Y[p - base];
                G += detail::objectiveAbs<double>(d, true, eps);
                const double g = d / std::sqrt(d * d + eps2);
                s[q - base] += g;
                s[p - base] -= g;
            },
            y0, y1);
    } else {
        detail::forEachMaskedPair(
            width, height, mask.data(),
            [&](size_t p, size_t q) {
                const double d = Y[q - base] - Y[p - base];
                G += detail::objectiveAbs<double>(d, false, eps);
                // sign(d) without a branch: the signs of a textured image are not predictable.
                const double g = static_cast<double>(d > 0.0) - static_cast<double>(d < 0.0);
                s[q - base] += g;
                s[p - base] -= g;
            },
            y0, y1);
    }
    return G;
}

}  // namespace

ImageObjective::ImageObjective(int width, int height, std::vector<uint8_t> mask,
                               ObjectiveOptions options)
    : width_(width), height_(height), mask_(std::move(mask)), opt_(options) {
    if (width <= 0 || height <= 0) {
        throw inputError("objective", "image size " + sizeStr(width, height) + " is not positive",
                         "Render or load an image with at least one pixel");
    }
    const size_t n = static_cast<size_t>(width) * static_cast<size_t>(height);
    if (mask_.size() != n) {
        throw inputError("objective mask",
                         "has " + std::to_string(mask_.size()) + " pixels, the image " +
                             sizeStr(width, height) + " has " + std::to_string(n),
                         "Use a mask of the same size as the rendered image");
    }
    if (!std::isfinite(opt_.lambda) || opt_.lambda < 0.0) {
        throw inputError(option("lambda"),
                         "is " + formatNumber(opt_.lambda) + ", not a finite value >= 0",
                         "Use e.g. 30 (the paper's value; 10 for its RGB run) or 0 for no L2");
    }
    if (opt_.smoothAbs && !(std::isfinite(opt_.smoothEps) && opt_.smoothEps > 0.0)) {
        throw inputError("objective.smoothEps",
                         "is " + std::to_string(opt_.smoothEps) + ", not a finite value > 0",
                         "Use e.g. 1e-4 (luminance units) or turn smoothAbs off");
    }
    size_t count = 0;
    for (uint8_t m : mask_) count += m != 0;
    if (count == 0) {
        throw inputError("objective mask",
                         "mask is empty (no pixel inside; the loss S/G would be 0/0)",
                         "Check the mask file (white = inside) and that the part is in view of "
                         "the camera, or omit the mask to use the whole part");
    }
    S_ = static_cast<double>(count);
}

void ImageObjective::checkSizes(size_t nY, size_t nE, const char* who) const {
    const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
    if (nY != n) {
        throw std::invalid_argument(std::string("ImageObjective::") + who + ": Y has " +
                                    std::to_string(nY) + " values, expected " +
                                    sizeStr(width_, height_) + " = " + std::to_string(n));
    }
    if (opt_.reg == RegTarget::EnvMap && nE == 0) {
        throw std::invalid_argument(std::string("ImageObjective::") + who +
                                    ": E is empty but the regulariser is mean(E^2) "
                                    "(RegTarget::EnvMap)");
    }
}

double ImageObjective::envMapRegulariser(std::span<const double> E, std::span<double> dLdE) const {
    double reg = 0.0;
    for (double e : E) reg += e * e;
    const double n = static_cast<double>(E.size());
    if (!dLdE.empty()) {
        const double k = 2.0 * opt_.lambda / n;
        for (size_t i = 0; i < E.size(); ++i) dLdE[i] = k * E[i];
    }
    return reg / n;
}

LossParts ImageObjective::evaluate(std::span<const double> Y, std::span<const double> E,
                                   std::span<double> dLdY, std::span<double> dLdE) const {
    checkSizes(Y.size(), E.size(), "evaluate");
    if (!dLdY.empty() && dLdY.size() != Y.size()) {
        throw std::invalid_argument("ImageObjective::evaluate: dLdY has " +
                                    std::to_string(dLdY.size()) + " values, expected " +
                                    std::to_string(Y.size()) + " (or none)");
    }
    if (!dLdE.empty() && dLdE.size() != E.size()) {
        throw std::invalid_argument("ImageObjective::evaluate: dLdE has " +
                                    std::to_string(dLdE.size()) + " values, expected " +
                                    std::to_string(E.size()) + " (or none)");
    }
    detail::checkFinite(Y, "Y", "evaluate");
    detail::checkFinite(E, "E", "evaluate");

    const bool wantY = !dLdY.empty();
    if (wantY) std::fill(dLdY.begin(), dLdY.end(), 0.0);
    const double G = accumulateG(width_, height_, mask_, Y.data(), wantY ? dLdY.data() : nullptr,
                                 opt_.smoothAbs, opt_.smoothEps);
    double sumY2 = 0.0;
    if (opt_.reg == RegTarget::Image)
        for (double y : Y) sumY2 += y * y;
    const LossParts r = fromSums(G, sumY2, E, dLdE);
    if (wantY) {
        const double scale = lGradScale(r.G);
        for (double& g : dLdY) g *= scale;
        const double k = imageRegScale();  // 2λ/(W·H) for RegTarget::Image, else 0
        if (k != 0.0)
            for (size_t i = 0; i < Y.size(); ++i) dLdY[i] += k * Y[i];
    }
    return r;
}

LossParts ImageObjective::fromSums(double G, double sumY2, std::span<const double> E,
                                   std::span<double> dLdE) const {
    LossParts r;
    r.S = S_;
    r.G = G;
    r.clamped = r.G < gFloor();
    r.lGrad = lGrad(r.G);
    if (opt_.reg == RegTarget::EnvMap) {
        r.lReg = envMapRegulariser(E, dLdE);
    } else {
        r.lReg = sumY2 / (static_cast<double>(width_) * static_cast<double>(height_));
        std::fill(dLdE.begin(), dLdE.end(), 0.0);
    }
    r.total = r.lGrad + opt_.lambda * r.lReg;
    if (!std::isfinite(r.total)) {
        throw std::range_error(
            "ImageObjective::evaluate: the loss is not finite (G = " + std::to_string(r.G) +
            ", L_reg = " + std::to_string(r.lReg) + "); are Y or E extremely large?");
    }
    return r;
}

double ImageObjective::gradientSigns(std::span<const double> Y, std::span<double> s) const {
    const size_t n = static_cast<size_t>(width_) * static_cast<size_t>(height_);
    if (Y.size() != n || s.size() != n) {
        throw std::invalid_argument("ImageObjective::gradientSigns: Y has " +
                                    std::to_string(Y.size()) + " and s " +
                                    std::to_string(s.size()) + " values, expected " +
                                    sizeStr(width_, height_) + " = " + std::to_string(n));
    }
    detail::checkFinite(Y, "Y", "gradientSigns");
    std::fill(s.begin(), s.end(), 0.0);
    const double G =
        accumulateG(width_, height_, mask_, Y.data(), s.data(), opt_.smoothAbs, opt_.smoothEps);
    if (!std::isfinite(G)) {
        throw std::range_error("ImageObjective::gradientSigns: G is not finite (" +
                               std::to_string(G) + "); are the values of Y extremely large?");
    }
    return G;
}

double ImageObjective::accumulateSignsRows(const double* Y, double* s, int y0, int y1,
                                           int firstRow) const {
    return accumulateG(width_, height_, mask_, Y, s, opt_.smoothAbs, opt_.smoothEps, y0, y1,
                       static_cast<size_t>(firstRow) * static_cast<size_t>(width_));
}

std::vector<uint8_t> intersectMasks(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
    if (a.size() != b.size()) {
        throw inputError("mask intersection",
                         "the masks have " + std::to_string(a.size()) + " and " +
                             std::to_string(b.size()) + " pixels",
                         "Use masks of the same image size");
    }
    std::vector<uint8_t> out(a.size());
    for (size_t i = 0; i < a.size(); ++i) out[i] = (a[i] && b[i]) ? 255 : 0;
    return out;
}

}  // namespace sl
