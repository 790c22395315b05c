#include "objective/UnbiasedObjective.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/Error.h"

namespace sl {

UnbiasedObjective::UnbiasedObjective(int width, int height, std::vector<uint8_t> mask,
                                     ObjectiveOptions options)
    : base_(width, height, std::move(mask), options) {}

double UnbiasedObjective::energy(std::span<const double> Ya, std::span<const double> Yb) const {
    double G = 0;
    detail::forEachMaskedPair(width(), height(), mask().data(),
                              [&](size_t p, size_t q) { G += (Ya[q] - Ya[p]) * (Yb[q] - Yb[p]); });
    return G;
}

double UnbiasedObjective::energyStandardError(std::span<const double> Ya,
                                              std::span<const double> Yb) const {
    const size_t n = static_cast<size_t>(width()) * static_cast<size_t>(height());
    if (Ya.size() != n || Yb.size() != n)
        throw std::invalid_argument("UnbiasedObjective: half images must have width*height values");
    // M·Y_a, M·Y_b (∂G/∂Y_b and ∂G/∂Y_a) and each pixel's pair count; the pairs' σ²σ² term.
    std::vector<double> ma(n, 0.0), mb(n, 0.0), degree(n, 0.0);
    auto v = [&](size_t p) { return 0.5 * (Ya[p] - Yb[p]) * (Ya[p] - Yb[p]); };
    double pairs = 0;
    detail::forEachMaskedPair(width(), height(), mask().data(), [&](size_t p, size_t q) {
        const double da = Ya[q] - Ya[p], db = Yb[q] - Yb[p];
        ma[q] += da;
        ma[p] -= da;
        mb[q] += db;
        mb[p] -= db;
        degree[p] += 1;
        degree[q] += 1;
        pairs += v(p) * v(q);
    });
    double var = 2.0 * pairs;
    for (size_t p = 0; p < n; ++p)
        if (degree[p] > 0) {
            const double vp = v(p);
            var += 2.0 * vp * ma[p] * mb[p] + degree[p] * degree[p] * vp * vp;
        }
    return var > 0 ? std::sqrt(var) : 0.0;
}

double UnbiasedObjective::lossStandardError(std::span<const double> Ya,
                                            std::span<const double> Yb) const {
    const double G = energy(Ya, Yb);
    if (options().reg != RegTarget::EnvMap || G < base_.gFloor())
        return std::numeric_limits<double>::quiet_NaN();
    return 0.5 * std::sqrt(maskSize()) / (G * std::sqrt(G)) * energyStandardError(Ya, Yb);
}

LossParts UnbiasedObjective::evaluate(std::span<const double> Ya, std::span<const double> Yb,
                                      std::span<const double> E, std::span<double> dLdYa,
                                      std::span<double> dLdYb, std::span<double> dLdE) const {
    const size_t n = static_cast<size_t>(width()) * static_cast<size_t>(height());
    if (Ya.size() != n || Yb.size() != n)
        throw std::invalid_argument("UnbiasedObjective: half images must have width*height values");
    if ((!dLdYa.empty() && dLdYa.size() != n) || (!dLdYb.empty() && dLdYb.size() != n) ||
        (!dLdE.empty() && dLdE.size() != E.size()))
        throw std::invalid_argument("UnbiasedObjective: gradient spans have the wrong size");
    detail::checkFinite(Ya, "Ya", "evaluate");
    detail::checkFinite(Yb, "Yb", "evaluate");
    double R = 0;
    if (usesProducts())
        for (size_t i = 0; i < n; ++i) R += Ya[i] * Yb[i];
    double dLdG = 0, dLdR = 0;
    const LossParts r = fromForms(energy(Ya, Yb), R, E, dLdG, dLdR, dLdE);
    if (!dLdYa.empty() && !dLdYb.empty()) {
        std::fill(dLdYa.begin(), dLdYa.end(), 0.0);
        std::fill(dLdYb.begin(), dLdYb.end(), 0.0);
        detail::forEachMaskedPair(width(), height(), mask().data(), [&](size_t p, size_t q) {
            const double da = Ya[q] - Ya[p], db = Yb[q] - Yb[p];
            dLdYa[q] += dLdG * db;
            dLdYa[p] -= dLdG * db;
            dLdYb[q] += dLdG * da;
            dLdYb[p] -= dLdG * da;
        });
        if (usesProducts())
            for (size_t i = 0; i < n; ++i) {
                dLdYa[i] += dLdR * Yb[i];
                dLdYb[i] += dLdR * Ya[i];
            }
    }
    return r;
}

LossParts UnbiasedObjective::fromForms(double G, double R, std::span<const double> E, double& dLdG,
                                       double& dLdR, std::span<double> dLdE) const {
    const ObjectiveOptions& opt = options();
    const double S = maskSize();
    if (opt.reg == RegTarget::EnvMap && E.empty())
        throw std::invalid_argument(
            "UnbiasedObjective: E is empty but the regulariser is mean(E^2)");
    if (!dLdE.empty() && dLdE.size() != E.size())
        throw std::invalid_argument("UnbiasedObjective: gradient spans have the wrong size");
    detail::checkFinite(E, "E", "evaluate");

    LossParts r;
    r.S = S;
    r.G = G;
    // Above the floor: sqrt(S/G). Below it (G_u <= 0 is possible): the tangent line at the
    // floor, so the loss stays finite, C¹ and strictly decreasing in G_u, and its gradient
    // still points toward more gradient energy (see the header).
    const double floor = base_.gFloor();
    r.clamped = r.G < floor;
    const double Gc = r.clamped ? floor : r.G;
    dLdG = -0.5 * std::sqrt(S) / (Gc * std::sqrt(Gc));
    r.lGrad = std::sqrt(S / Gc) + (r.clamped ? dLdG * (r.G - floor) : 0.0);
    const double lambda = opt.lambda;
    dLdR = 0;
    if (opt.reg == RegTarget::EnvMap) {
        r.lReg = base_.envMapRegulariser(E, dLdE);
    } else {
        const double N = static_cast<double>(width()) * static_cast<double>(height());
        r.lReg = R / N;
        dLdR = lambda / N;
        std::fill(dLdE.begin(), dLdE.end(), 0.0);
    }
    r.total = r.lGrad + lambda * r.lReg;
    if (!std::isfinite(r.total))
        throw std::range_error("UnbiasedObjective: the loss is not finite (" +
                               std::to_string(r.total) + ")");
    return r;
}

void UnbiasedObjective::formCurvature(double G, size_t texels, double& d2LdG2,
                                      double& regCurvature) const {
    const double S = maskSize();
    d2LdG2 = G < base_.gFloor() ? 0.0 : 0.75 * std::sqrt(S) / (G * G * std::sqrt(G));
    regCurvature = options().reg == RegTarget::EnvMap && texels > 0
                       ? 2.0 * options().lambda / static_cast<double>(texels)
                       : 0.0;
}

}  // namespace sl
