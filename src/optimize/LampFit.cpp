#include "optimize/LampFit.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "core/Text.h"

namespace sl {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
constexpr double kForbidWeight = 1e3;  // penalty per rad² of a centre inside a forbidden range
constexpr double kPeakSeparation = 20 * kDeg;  // between the residual peaks tried
constexpr double kMomentRadius = 30 * kDeg;    // the residual's moments around a peak
constexpr double kOverWeight = 1e3;            // penalty per sr of (E_t − 1)² above E's box

/// How deep azimuth φ lies inside [from, to] (wrapping), 0 outside.
double forbiddenDepth(double phi, std::pair<double, double> range) {
    const double width = std::remainder(range.second - range.first - kPi, 2 * kPi) + kPi;
    double off = std::fmod(phi - range.first, 2 * kPi);
    if (off < 0) off += 2 * kPi;
    if (off > width) return 0;
    return std::min(off, width - off);
}

/// How deep the direction (azimuth φ, elevation ε) lies inside the camera's cone: margin minus
/// its angle to the camera, 0 outside (or without a camera).
double cameraDepth(double phi, double eps, const LampFitOptions& o) {
    if (!o.camera) return 0;
    const Vec3d a = lampDirection(phi, eps), c = lampDirection((*o.camera)[0], (*o.camera)[1]);
    const double angle = std::acos(std::clamp(dot(a, c), -1.0, 1.0));
    return std::max(0.0, o.cameraMargin - angle);
}

}  // namespace

std::array<double, 2> lampParamRange(LampKind kind, int p, const LampFitOptions& o) {
    const bool used = lampUsesParam(kind, p);
    switch (p) {
        case kRadiance:
            return {0.0, 1.0};
        case kAzimuth:
            return used ? std::array<double, 2>{-2 * kPi, 2 * kPi} : std::array<double, 2>{0, 0};
        case kElevation:
            return {o.minElevation, o.maxElevation};
        case kSize:
            switch (kind) {
                case LampKind::Disk:
                    return {4 * kDeg, 90 * kDeg};
                case LampKind::Bar:
                    return {4 * kDeg, 60 * kDeg};
                case LampKind::Ring:
                    return {2 * kDeg, 45 * kDeg};
            }
            break;
        case kWidth:
            return used ? std::array<double, 2>{2 * kDeg, 20 * kDeg}
                        : std::array<double, 2>{2 * kDeg, 2 * kDeg};
        case kRoll:
            return used ? std::array<double, 2>{-kPi, kPi} : std::array<double, 2>{0, 0};
        default:
            break;
    }
    return {0.0, 0.0};
}

LampProblem::LampProblem(const TransportLoss& loss, const LampRasterizer& raster,
                         std::vector<LampKind> kinds, const LampFitOptions& options,
                         const TransportColumns* columns)
    : loss_(loss),
      raster_(raster),
      kinds_(std::move(kinds)),
      options_(options),
      columns_(columns) {}

std::vector<Lamp> LampProblem::lamps(std::span<const double> x) const {
    std::vector<Lamp> out;
    for (size_t l = 0; l < kinds_.size(); ++l) {
        Lamp lamp;
        lamp.kind = kinds_[l];
        std::array<double, kLampParams> p{};
        for (int k = 0; k < kLampParams; ++k) {
            const auto r = lampParamRange(lamp.kind, k, options_);
            p[static_cast<size_t>(k)] =
                r[0] +
                (r[1] - r[0]) * std::clamp(x[l * kLampParams + static_cast<size_t>(k)], 0.0, 1.0);
        }
        lamp.setParams(p);
        out.push_back(lamp);
    }
    return out;
}

std::vector<double> LampProblem::encode(std::span<const Lamp> lamps) const {
    std::vector<double> x;
    for (const Lamp& lamp : lamps) {
        const auto p = lamp.params();
        for (int k = 0; k < kLampParams; ++k) {
            const auto r = lampParamRange(lamp.kind, k, options_);
            double v = p[static_cast<size_t>(k)];
            if (k == kAzimuth) v = std::remainder(v, 2 * kPi);
            x.push_back(r[1] > r[0] ? std::clamp((v - r[0]) / (r[1] - r[0]), 0.0, 1.0) : 0.5);
        }
    }
    return x;
}

double LampProblem::evaluate(std::span<const double> x, std::span<double> grad) const {
    const auto ls = lamps(x);
    const size_t texels = static_cast<size_t>(raster_.basis().texelCount());
    std::vector<double> E(texels, 0.0);
    std::vector<std::vector<double>> J(ls.size(), std::vector<double>(texels * kLampParams));
    std::vector<std::vector<double>> El(ls.size(), std::vector<double>(texels));
    tbb::parallel_for(size_t{0}, ls.size(),
                      [&](size_t l) { raster_.jacobian(ls[l], J[l], El[l]); });
    for (size_t l = 0; l < ls.size(); ++l)  // in lamp order: the sum does not depend on threads
        for (size_t t = 0; t < texels; ++t) E[t] += El[l][t];
    std::vector<double> gE(grad.empty() ? 0 : loss_.dimension());
    double value = 0;
    if (columns_) {
        // The texels any lamp touches: where E or a derivative of E is non-zero. Outside them
        // E is 0 and the chain rule needs no dLoss/dE.
        std::vector<uint16_t> active;
        for (size_t t = 0; t < texels; ++t) {
            bool touched = false;
            for (size_t l = 0; l < ls.size() && !touched; ++l) {
                touched = El[l][t] != 0;
                for (int k = 0; k < kLampParams && !touched; ++k)
                    touched = J[l][t * kLampParams + static_cast<size_t>(k)] != 0;
            }
            if (touched) active.push_back(static_cast<uint16_t>(t));
        }
        value = loss_.evaluateOnColumns(*columns_, E, active, gE).total;
    } else {
        value = loss_.evaluate(E, gE).total;
    }
    // Overlapping lamps may not exceed E's box [0, 1] (the same budget as E*): a smooth
    // quadratic penalty on the excess, weighted by the texel's solid angle.
    const std::vector<double>& omega = raster_.texelSolidAngles();
    for (size_t t = 0; t < texels; ++t) {
        const double over = E[t] - 1.0;
        if (over <= 0) continue;
        value += kOverWeight * omega[t] * over * over;
        if (!grad.empty()) gE[t] += 2 * kOverWeight * omega[t] * over;
    }
    if (!grad.empty()) std::fill(grad.begin(), grad.end(), 0.0);
    for (size_t l = 0; l < ls.size(); ++l) {
        if (!grad.empty())
            for (int k = 0; k < kLampParams; ++k) {
                const auto r = lampParamRange(ls[l].kind, k, options_);
                double g = 0;
                for (size_t t = 0; t < texels; ++t)
                    g += J[l][t * kLampParams + static_cast<size_t>(k)] * gE[t];
                grad[l * kLampParams + static_cast<size_t>(k)] = g * (r[1] - r[0]);
            }
        if (!lampUsesParam(ls[l].kind, kAzimuth)) continue;
        if (const double depth = cameraDepth(ls[l].azimuth, ls[l].elevation, options_); depth > 0) {
            value += kForbidWeight * depth * depth;
            if (!grad.empty()) {
                // d depth / d(φ, ε) by central differences (the depth is smooth inside the cone
                // away from its axis, where the gradient is any direction out).
                const double h = 1e-7;
                const double dPhi = (cameraDepth(ls[l].azimuth + h, ls[l].elevation, options_) -
                                     cameraDepth(ls[l].azimuth - h, ls[l].elevation, options_)) /
                                    (2 * h),
                             dEps = (cameraDepth(ls[l].azimuth, ls[l].elevation + h, options_) -
                                     cameraDepth(ls[l].azimuth, ls[l].elevation - h, options_)) /
                                    (2 * h);
                const auto ra = lampParamRange(ls[l].kind, kAzimuth, options_),
                           re = lampParamRange(ls[l].kind, kElevation, options_);
                grad[l * kLampParams + kAzimuth] +=
                    2 * kForbidWeight * depth * dPhi * (ra[1] - ra[0]);
                grad[l * kLampParams + kElevation] +=
                    2 * kForbidWeight * depth * dEps * (re[1] - re[0]);
            }
        }
        for (const auto& range : options_.forbiddenAzimuth) {
            const double depth = forbiddenDepth(ls[l].azimuth, range);
            if (depth <= 0) continue;
            value += kForbidWeight * depth * depth;
            if (grad.empty()) continue;
            // d depth/dφ: +1 in the first half of the range, −1 in the second.
            const double h = 1e-7;
            const double slope = (forbiddenDepth(ls[l].azimuth + h, range) -
                                  forbiddenDepth(ls[l].azimuth - h, range)) /
                                 (2 * h);
            const auto r = lampParamRange(ls[l].kind, kAzimuth, options_);
            grad[l * kLampParams + kAzimuth] += 2 * kForbidWeight * depth * slope * (r[1] - r[0]);
        }
    }
    return value;
}

Problem LampProblem::problem() const {
    Problem p;
    p.dimension = dimension();
    p.lower = 0;
    p.upper = 1;
    p.evaluate = [this](std::span<const double> x, std::span<double> g) { return evaluate(x, g); };
    return p;
}

namespace {

/// The candidate start lamps for the next lamp: at the residual's brightest direction and at
/// the most negative dLoss/dE, each of the allowed kinds.
std::vector<Lamp> candidates(const LampRasterizer& raster, std::span<const double> residual,
                             std::span<const double> dLdE, const LampFitOptions& o) {
    const EnvMapBasis& b = raster.basis();
    const int W = b.width(), H = b.height();
    auto elevationOf = [&](int j) { return kPi / 2 - kPi * j / (H - 1); };
    auto allowed = [&](int j, int i) {
        const double el = elevationOf(j);
        if (el < o.minElevation || el > o.maxElevation) return false;
        const double az = 2 * kPi * (i + 0.5) / W;
        for (const auto& r : o.forbiddenAzimuth)
            if (forbiddenDepth(az, r) > 0) return false;
        return cameraDepth(az, el, o) <= 0;
    };
    // The residual's peaks: the brightest allowed texels at least kPeakSeparation apart (up to
    // o.residualPeaks, each above a tenth of the brightest), then the most negative dLoss/dE.
    std::vector<std::array<int, 2>> order;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            if (allowed(j, i)) order.push_back({j, i});
    auto at = [&](std::span<const double> v, const std::array<int, 2>& p) {
        return v[static_cast<size_t>(p[0] * W + p[1])];
    };
    std::stable_sort(order.begin(), order.end(), [&](const auto& p, const auto& q) {
        return at(residual, p) > at(residual, q);
    });
    std::vector<std::array<int, 2>> places;
    const double top = order.empty() ? 0.0 : at(residual, order.front());
    for (const auto& p : order) {
        if (static_cast<int>(places.size()) >= o.residualPeaks || at(residual, p) <= 0.1 * top)
            break;
        bool apart = true;
        for (const auto& q : places)
            apart &= dot(b.texelDirection(p[0], p[1]), b.texelDirection(q[0], q[1])) <
                     std::cos(kPeakSeparation);
        if (apart) places.push_back(p);
    }
    if (!dLdE.empty() && !order.empty()) {
        const auto g = *std::min_element(
            order.begin(), order.end(),
            [&](const auto& a, const auto& c) { return at(dLdE, a) < at(dLdE, c); });
        if (std::find(places.begin(), places.end(), g) == places.end()) places.push_back(g);
    }
    if (places.empty()) {  // nothing allowed by the texel centres: the middle of the band
        places.push_back(
            {std::clamp(static_cast<int>(std::lround(
                            (kPi / 2 - 0.5 * (o.minElevation + o.maxElevation)) / kPi * (H - 1))),
                        0, H - 1),
             0});
    }
    // At each place a fixed shape (disk 8°, bar 15°×3°, ring ±5°), and at the first place also
    // the shape of the residual's moments within kMomentRadius of it, in the tangent plane
    // (e_φ, e_ε): the centre at the mean, a disk of the same second moment (R² = 2·tr Σ), a bar
    // along the principal axis (a² = 3λ₁, b² = 3λ₂, uniform rectangle), a ring of the same
    // elevation spread. Neither start is better on every part (measured on three).
    const std::vector<double>& omega = raster.texelSolidAngles();
    std::vector<Lamp> out;
    for (const auto& pl : places) {
        const double level = std::clamp(residual[static_cast<size_t>(pl[0] * W + pl[1])], 0.2, 1.0);
        const double az0 = 2 * kPi * (pl[1] + 0.5) / W, el0 = elevationOf(pl[0]);
        const auto f = lamp_detail::frame<double>(az0, el0, 0.0);
        const Vec3d c{f.c[0], f.c[1], f.c[2]}, ex{f.e1[0], f.e1[1], f.e1[2]},
            ey{f.e2[0], f.e2[1], f.e2[2]};
        double m = 0, mx = 0, my = 0, mxx = 0, myy = 0, mxy = 0;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const Vec3d d = b.texelDirection(j, i);
                if (dot(d, c) < std::cos(kMomentRadius)) continue;
                const size_t t = static_cast<size_t>(j * W + i);
                const double w = residual[t] * omega[t];
                const double x = dot(d, ex), y = dot(d, ey);
                m += w;
                mx += w * x;
                my += w * y;
                mxx += w * x * x;
                myy += w * y * y;
                mxy += w * x * y;
            }
        double az = az0, el = el0, sxx = 0, syy = 0, sxy = 0;
        if (m > 0) {
            mx /= m;
            my /= m;
            sxx = std::max(mxx / m - mx * mx, 0.0);
            syy = std::max(myy / m - my * my, 0.0);
            sxy = mxy / m - mx * my;
            const Vec3d d = c + ex * mx + ey * my;
            az = std::atan2(d.x, -d.z);
            el = std::asin(std::clamp(d.y / std::sqrt(dot(d, d)), -1.0, 1.0));
        }
        const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
        const double l1 = 0.5 * tr + std::sqrt(std::max(0.25 * tr * tr - det, 0.0)),
                     l2 = std::max(tr - l1, 0.0);
        for (LampKind kind : o.kinds) {  // a fixed shape at the texel
            Lamp l;
            l.kind = kind;
            l.radiance = level;
            l.azimuth = kind == LampKind::Ring ? 0.0 : az0;
            l.elevation = std::clamp(el0, o.minElevation, o.maxElevation);
            l.size = kind == LampKind::Disk  ? 8 * kDeg
                     : kind == LampKind::Bar ? 15 * kDeg
                                             : 5 * kDeg;
            l.width = kind == LampKind::Bar ? 3 * kDeg : 2 * kDeg;
            out.push_back(l);
        }
        if (&pl != &places.front()) continue;
        for (LampKind kind : o.kinds) {  // the moments' shape, at the first peak only
            Lamp l;
            l.kind = kind;
            l.radiance = level;
            l.azimuth = kind == LampKind::Ring ? 0.0 : az;
            l.elevation = std::clamp(el, o.minElevation, o.maxElevation);
            switch (kind) {
                case LampKind::Disk:
                    l.size = std::clamp(std::sqrt(2 * tr), 5 * kDeg, 40 * kDeg);
                    break;
                case LampKind::Bar:
                    l.size = std::clamp(std::sqrt(3 * l1), 6 * kDeg, 50 * kDeg);
                    l.width = std::clamp(std::sqrt(3 * l2), 3 * kDeg, 15 * kDeg);
                    l.roll = 0.5 * std::atan2(2 * sxy, sxx - syy);  // principal axis from e_φ
                    break;
                case LampKind::Ring:
                    l.size = std::clamp(std::sqrt(3 * syy), 3 * kDeg, 30 * kDeg);
                    break;
            }
            out.push_back(l);
        }
    }
    return out;
}

struct LampFitRun {
    std::vector<Lamp> lamps;
    double loss = 0;
    int evaluations = 0;
};

/// The lamps optimized jointly from `start` on `raster` for up to `iterations` iterations.
LampFitRun fitRun(const TransportLoss& loss, const TransportColumns* columns,
                  const LampRasterizer& raster, std::span<const Lamp> start,
                  const LampFitOptions& o, int iterations) {
    std::vector<LampKind> kinds;
    for (const Lamp& l : start) kinds.push_back(l.kind);
    const LampProblem problem(loss, raster, kinds, o, columns);
    std::vector<double> x = problem.encode(start);
    OptimizerOptions opt;
    opt.method = o.method;
    opt.iterations = iterations;
    opt.relativeFunctionTolerance = o.relativeTolerance;
    const OptimizerSummary s = minimize(problem.problem(), x, opt);
    return {problem.lamps(x), s.finalLoss, s.evaluations};
}

}  // namespace

void checkLampFitOptions(const LampFitOptions& o) {
    if (o.count < 1 || o.count > 8)
        throw inputError(option("count"), "must be between 1 and 8, not " + std::to_string(o.count),
                         "use e.g. 3");
    if (o.kinds.empty())
        throw inputError(option("kinds"), "no lamp kind given", "use e.g. disk,bar,ring");
    if (!(o.minElevation < o.maxElevation) || o.minElevation < -kPi / 2 - 1e-12 ||
        o.maxElevation > kPi / 2 + 1e-12)
        throw inputError(option("min-elevation"),
                         "the elevation range must be a non-empty part of [-90, 90] degrees",
                         "use e.g. 0 and 90");
    if (!(o.cameraMargin >= 0 && o.cameraMargin < kPi / 2))
        throw inputError(option("camera-margin"),
                         "must be in [0, 90) degrees, not " + formatNumber(o.cameraMargin / kDeg),
                         "use e.g. 10");
    for (const auto& [from, to] : o.forbiddenAzimuth) {
        const std::string range =
            formatNumber(from / kDeg) + ":" + formatNumber(to / kDeg) + " (degrees)";
        if (!std::isfinite(from) || !std::isfinite(to) || std::abs(from) > 2 * kPi + 1e-12 ||
            std::abs(to) > 2 * kPi + 1e-12)
            throw inputError(option("forbid-azimuth") + " " + range,
                             "each end must be in [-360, 360] degrees", "use e.g. 150:210");
        if (std::abs(to - from) >= 2 * kPi - 1e-12)
            throw inputError(option("forbid-azimuth") + " " + range,
                             "forbids every azimuth: no lamp could be placed",
                             "give a range narrower than 360 degrees, e.g. 150:210");
        if (std::abs(std::remainder(to - from, 2 * kPi)) < 1e-12)
            throw inputError(option("forbid-azimuth") + " " + range, "is empty",
                             "give FROM:TO with FROM != TO, e.g. 150:210");
    }
}

LampFitResult fitLamps(const TransportLoss& loss, std::span<const double> target,
                       const LampFitOptions& o) {
    checkLampFitOptions(o);
    const Stopwatch clock;
    const CpuStopwatch cpu;
    // The lamps are rasterized on T's own env-map grid.
    const EnvMapBasis basis(loss.matrix().envWidth, loss.matrix().envHeight);
    if (loss.dimension() != static_cast<size_t>(basis.texelCount()) ||
        target.size() != loss.dimension())
        throw inputError("lamps", "the transport matrix is not gray, or E* is not on its grid",
                         "use a gray T and E* on its env-map grid");
    const LampRasterizer raster(basis, o.raster);
    LampRasterOptions coarse = o.raster;
    coarse.subsamples = std::min(coarse.subsamples, o.screenSubsamples);
    const LampRasterizer screen(basis, coarse);
    LampRasterOptions medium = o.raster;
    medium.subsamples = std::min(medium.subsamples, o.polishSubsamples);
    const LampRasterizer polishRaster(basis, medium);
    std::optional<TransportColumns> columnCopy;
    if (o.columnProducts) columnCopy.emplace(loss.matrix());
    const TransportColumns* columns = columnCopy ? &*columnCopy : nullptr;
    LampFitResult result;
    std::vector<double> gTarget(loss.dimension());
    result.targetLoss = loss.evaluate(target, gTarget).total;

    std::vector<Lamp> lamps;
    std::vector<double> E(loss.dimension(), 0.0), gE(loss.dimension());
    loss.evaluate(E, gE);
    // Each extra lamp costs more than the last (more parameters to polish): the bar counts lamps.
    ProgressTask task("fitting lamps", o.count);
    for (int k = 1; k <= o.count; ++k) {
        // Ctrl-C (core/Interrupt.h): stop before each lamp and each candidate's fit; the job
        // writes nothing (its output directory is staged).
        throwIfInterrupted();
        task.detail("lamp " + std::to_string(k));
        std::vector<double> residual(E.size());
        for (size_t t = 0; t < E.size(); ++t) residual[t] = std::max(target[t] - E[t], 0.0);
        // Screen every candidate (a few iterations on the coarse quadrature), then polish the
        // best o.polished on the full one and keep the lowest polished loss: the screened order
        // is not always the polished one.
        const std::vector<Lamp> cands = candidates(raster, residual, gE, o);
        // The candidates are independent: screened in parallel, each on its own copy of the
        // loss (TransportLoss keeps scratch buffers), results kept by index (deterministic).
        std::vector<std::pair<double, std::vector<Lamp>>> screened(cands.size());
        std::vector<int> screenEvaluations(cands.size(), 0);
        tbb::parallel_for(size_t{0}, cands.size(), [&](size_t c) {
            throwIfInterrupted();
            const TransportLoss own = loss;
            std::vector<Lamp> trial = lamps;
            trial.push_back(cands[c]);
            const LampFitRun run = fitRun(own, columns, screen, trial, o, o.candidateIterations);
            screenEvaluations[c] = run.evaluations;
            screened[c] = {run.loss, run.lamps};
        });
        int evaluations = 0;
        for (int e : screenEvaluations) evaluations += e;
        std::vector<size_t> order(screened.size());
        for (size_t c = 0; c < order.size(); ++c) order[c] = c;
        std::stable_sort(order.begin(), order.end(),
                         [&](size_t a, size_t b) { return screened[a].first < screened[b].first; });
        double bestLoss = std::numeric_limits<double>::infinity();
        std::vector<Lamp> best;
        const size_t polish = std::min(order.size(), static_cast<size_t>(std::max(o.polished, 1)));
        std::vector<LampFitRun> polishedRuns(polish);
        throwIfInterrupted();
        tbb::parallel_for(size_t{0}, polish, [&](size_t c) {
            throwIfInterrupted();
            const TransportLoss own = loss;
            polishedRuns[c] =
                fitRun(own, columns, polishRaster, screened[order[c]].second, o, o.finalIterations);
        });
        for (const LampFitRun& run : polishedRuns) {  // in screened order: ties keep the better
            evaluations += run.evaluations;
            if (run.loss < bestLoss) {
                bestLoss = run.loss;
                best = run.lamps;
            }
        }
        // A k-th lamp that cannot help: keep the k−1 and this one off, when that scores better
        // on the same problem the polished runs minimized (the objective with its penalties, on
        // the polish's quadrature). Not for the first lamp: no lamp at all is a black image.
        std::vector<Lamp> keep = lamps;
        Lamp off = cands.front();
        off.radiance = 0;
        keep.push_back(off);
        std::vector<LampKind> keepKinds;
        for (const Lamp& l : keep) keepKinds.push_back(l.kind);
        const LampProblem keepProblem(loss, polishRaster, keepKinds, o, columns);
        if (best.empty() ||
            (k > 1 && keepProblem.evaluate(keepProblem.encode(keep), {}) < bestLoss))
            best = keep;
        lamps = best;
        E = raster.rasterize(lamps);
        LampFitStep step;
        step.count = k;
        step.lamps = lamps;
        step.loss = loss.evaluate(E, gE).total;
        step.seconds = clock.seconds();
        step.evaluations = evaluations;
        result.steps.push_back(step);
        task.set(k);
    }
    result.envMap = E;
    result.seconds = clock.seconds();
    result.cpuSeconds = cpu.seconds();
    return result;
}

}  // namespace sl
