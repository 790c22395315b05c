#include "detect/StepLines.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "detect/Hysteresis.h"
#include "detect/ImageFilters.h"

namespace sl::defectmap {

namespace {

/// A direction of the step detector's lines: (dx, dz) in samples.
struct StepDir {
    int dx, dz;
};
constexpr StepDir kStepDirs[4] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};

/// The step detector's jump at (x, z) along u on G (W wide): each side's heights at offsets
/// gap … gap+2m−1 as two means of m samples, extrapolated linearly to (x, z); the + side's value
/// minus the − side's. The caller keeps every offset inside the map.
double jumpAlong(const std::vector<float>& G, int W, int x, int y, StepDir u, int m, int gap) {
    const double reach = gap + (m - 1) / 2.0;  // the near mean's distance from (x, z)
    auto side = [&](int sgn) {
        double nearSum = 0, farSum = 0;
        for (int i = 0; i < m; ++i) {
            const int k1 = sgn * (gap + i), k2 = sgn * (gap + m + i);
            nearSum += G[static_cast<size_t>(y + k1 * u.dz) * W + x + k1 * u.dx];
            farSum += G[static_cast<size_t>(y + k2 * u.dz) * W + x + k2 * u.dx];
        }
        const double nm = nearSum / m, fm = farSum / m;
        return nm + (nm - fm) * reach / m;
    };
    return side(1) - side(-1);
}

/// Step 4a's gaps along a curved step: a ring-shaped step (a tool change on a turned part) is
/// hidden from the centre tests where a steep wall crosses it, and the level term's smear of it
/// stays there. A line whose points lie on a circle (Kåsa's algebraic fit; RMS distance at most
/// 0.75 samples, radius at most 4× the map's larger side) takes every line's points within 1.5
/// samples of that circle; the arcs between consecutive ones (by angle) up to `maxGap` samples
/// long get points every half sample: on the circle, normal along the radius (to the side the
/// points' normals face), the points' median jump.
void fillCircleGaps(StepModel& m, const std::vector<std::pair<size_t, size_t>>& lines, int W, int H,
                    double maxGap) {
    constexpr double kFitRms = 0.75, kOnCircle = 1.5, kSpacing = 0.5;
    std::vector<uint8_t> taken(lines.size(), 0);
    std::vector<StepPoint> added;
    for (size_t li = 0; li < lines.size(); ++li) {
        if (taken[li]) continue;
        const auto [a, b] = lines[li];
        // x² + z² + D·x + E·z + F = 0 in least squares, about the points' mean
        double mx = 0, mz = 0;
        for (size_t i = a; i < b; ++i) mx += m.points[i].x, mz += m.points[i].z;
        mx /= static_cast<double>(b - a);
        mz /= static_cast<double>(b - a);
        Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (size_t i = a; i < b; ++i) {
            const double x = m.points[i].x - mx, z = m.points[i].z - mz;
            const Eigen::Vector3d row(x, z, 1.0);
            M += row * row.transpose();
            v -= row * (x * x + z * z);
        }
        const Eigen::Vector3d def = M.ldlt().solve(v);
        const double cx = -0.5 * def[0], cz = -0.5 * def[1];
        const double r2 = cx * cx + cz * cz - def[2];
        if (!std::isfinite(r2) || r2 <= 0) continue;
        const double R = std::sqrt(r2);
        if (R > 4.0 * std::max(W, H)) continue;
        double ss = 0;
        for (size_t i = a; i < b; ++i) {
            const double d = std::hypot(m.points[i].x - mx - cx, m.points[i].z - mz - cz) - R;
            ss += d * d;
        }
        if (std::sqrt(ss / static_cast<double>(b - a)) > kFitRms) continue;
        // every line's points on this circle, by angle
        std::vector<std::pair<double, size_t>> on;
        for (size_t lj = 0; lj < lines.size(); ++lj) {
            bool any = false;
            for (size_t i = lines[lj].first; i < lines[lj].second; ++i) {
                const double dx = m.points[i].x - mx - cx, dz = m.points[i].z - mz - cz;
                if (std::abs(std::hypot(dx, dz) - R) > kOnCircle) continue;
                on.emplace_back(std::atan2(dz, dx), i);
                any = true;
            }
            if (any) taken[lj] = 1;
        }
        std::sort(on.begin(), on.end());
        int outward = 0;
        std::vector<float> jumps;
        for (const auto& [t, i] : on) {
            const StepPoint& p = m.points[i];
            outward += (p.x - mx - cx) * p.nx + (p.z - mz - cz) * p.nz > 0 ? 1 : -1;
            jumps.push_back(p.jump);
        }
        const auto mid = jumps.begin() + static_cast<std::ptrdiff_t>(jumps.size() / 2);
        std::nth_element(jumps.begin(), mid, jumps.end());
        const double sign = outward >= 0 ? 1.0 : -1.0;
        for (size_t q = 0; q < on.size(); ++q) {
            const double t0 = on[q].first;
            const double t1 =
                q + 1 < on.size() ? on[q + 1].first : on[0].first + 2.0 * std::numbers::pi;
            const double arc = R * (t1 - t0);
            if (!(arc > 2.0 * kSpacing && arc <= maxGap)) continue;
            const int steps = static_cast<int>(std::floor(arc / kSpacing));
            for (int s = 1; s < steps; ++s) {
                const double t = t0 + (t1 - t0) * s / steps;
                StepPoint p;
                p.x = static_cast<float>(mx + cx + R * std::cos(t));
                p.z = static_cast<float>(mz + cz + R * std::sin(t));
                p.nx = static_cast<float>(sign * std::cos(t));
                p.nz = static_cast<float>(sign * std::sin(t));
                p.jump = *mid;
                if (p.x >= 0 && p.z >= 0 && p.x <= static_cast<float>(W - 1) &&
                    p.z <= static_cast<float>(H - 1))
                    added.push_back(p);
            }
        }
    }
    m.points.insert(m.points.end(), added.begin(), added.end());
}

}  // namespace

StepModel detectSteps(const std::vector<float>& G, int W, int H, const DefectMapOptions& o,
                      double floorSigma) {
    const size_t n = G.size();
    StepModel m;
    std::vector<float> bestZ(n, 0.0f), bestJ(n, 0.0f);
    // the jump at every sample along each direction, in that direction's robust σ
    const int m2 = o.stepWindow / 2, gap = 2, far = gap + 2 * m2 - 1;
    for (int d = 0; d < 4; ++d) {
        const StepDir u = kStepDirs[d];
        std::vector<float> J(n, 0.0f);
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                if (x - far * std::abs(u.dx) < 0 || x + far * std::abs(u.dx) >= W ||
                    y - far * std::abs(u.dz) < 0 || y + far * std::abs(u.dz) >= H)
                    continue;
                J[static_cast<size_t>(y) * W + x] =
                    static_cast<float>(jumpAlong(G, W, x, y, u, m2, gap));
            }
        });
        const double sigma = std::max(1.4826 * medianAbs(J), floorSigma);
        if (!(sigma > 0.0)) continue;
        for (size_t k = 0; k < n; ++k) {
            const auto z = static_cast<float>(std::abs(J[k]) / sigma);
            if (z > bestZ[k]) {
                bestZ[k] = z;
                bestJ[k] = J[k];
            }
        }
    }
    // centre candidates: a strong two-sided jump (in any direction) where the gradient of G
    // along the direction nearest its own peaks (non-maximum suppression), carries most of the
    // jump within 2 samples (sharpness) and separates two plateaus
    auto at = [&](int x, int y) { return G[static_cast<size_t>(y) * W + x]; };
    std::vector<uint8_t> cand(n, 0), candDir(n, 0);
    std::vector<float> offset(n, 0.0f), candJ(n, 0.0f), normX(n, 0.0f), normZ(n, 0.0f);
    const int b = std::max(o.border, far + 2);
    tbb::parallel_for(b, H - b, [&](int y) {
        for (int x = b; x < W - b; ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            if (!(bestZ[k] >= o.stepSigma)) continue;
            // the gradient (3×3 Sobel) and the detector direction nearest it
            float gx = (at(x + 1, y - 1) + 2 * at(x + 1, y) + at(x + 1, y + 1)) -
                       (at(x - 1, y - 1) + 2 * at(x - 1, y) + at(x - 1, y + 1));
            float gz = (at(x - 1, y + 1) + 2 * at(x, y + 1) + at(x + 1, y + 1)) -
                       (at(x - 1, y - 1) + 2 * at(x, y - 1) + at(x + 1, y - 1));
            // minus the local slope over ±6 samples (a wall's; 8× the derivative, as Sobel's)
            float wx = 0, wz = 0;
            for (int i = -1; i <= 1; ++i)
                for (int j = 4; j <= 6; ++j) {
                    wx += at(x + j, y + i) - at(x - j, y + i);
                    wz += at(x + i, y + j) - at(x + i, y - j);
                }
            gx -= wx * (8.0f / 90.0f);  // 9 differences over 10 samples on average
            gz -= wz * (8.0f / 90.0f);
            const float gl = std::hypot(gx, gz);
            if (!(gl > 0)) continue;
            int dir = 0;
            float best = -1;
            for (int d = 0; d < 4; ++d) {
                const StepDir v = kStepDirs[d];
                const float c =
                    std::abs(gx * static_cast<float>(v.dx) + gz * static_cast<float>(v.dz)) /
                    std::sqrt(static_cast<float>(v.dx * v.dx + v.dz * v.dz));
                if (c > best) {
                    best = c;
                    dir = d;
                }
            }
            const StepDir u = kStepDirs[dir];
            const auto jump = static_cast<float>(jumpAlong(G, W, x, y, u, m2, gap));
            const float s = jump > 0 ? 1.0f : -1.0f;
            const float ref = std::max(std::abs(jump), std::abs(bestJ[k]));  // the strongest
            auto grad = [&](int i) {  // G(q+(i+1)u) − G(q+(i−1)u), signed toward the high side
                return s * (at(x + (i + 1) * u.dx, y + (i + 1) * u.dz) -
                            at(x + (i - 1) * u.dx, y + (i - 1) * u.dz));
            };
            const float g0 = grad(0), gm = grad(-1), gp = grad(1);
            if (!(g0 > 0 && g0 >= gm && g0 > gp)) continue;
            if (!(g0 >= o.stepSharpness * ref)) continue;
            const int w = o.stepWindow / 2 + 1;  // the rise over a wider span: a wall's is
            const float gw = s * (at(x + w * u.dx, y + w * u.dz) - at(x - w * u.dx, y - w * u.dz));
            if (!(g0 >= o.stepSharpness * std::abs(gw))) continue;
            // the plateaus: the median of each side over the detector's samples must differ by
            // stepPlateau × the jump (a bump, a ridge of texture left over, comes back)
            {
                thread_local std::vector<float> side[2];
                for (int sg = 0; sg < 2; ++sg) {
                    side[sg].clear();
                    for (int i = gap; i < gap + 2 * m2; ++i) {
                        const int kk = sg ? i : -i;
                        side[sg].push_back(at(x + kk * u.dx, y + kk * u.dz));
                    }
                    std::nth_element(side[sg].begin(), side[sg].begin() + m2, side[sg].end());
                }
                const float plateau =
                    s * (side[1][static_cast<size_t>(m2)] - side[0][static_cast<size_t>(m2)]);
                if (!(plateau >= o.stepPlateau * ref)) continue;
            }
            const float den = gm - 2 * g0 + gp;
            const float delta = den < 0 ? 0.5f * (gm - gp) / den : 0.0f;
            cand[k] = 1;
            candDir[k] = static_cast<uint8_t>(dir);
            candJ[k] = std::abs(jump);
            normX[k] = gx / gl;  // toward the high side
            normZ[k] = gz / gl;
            offset[k] = std::clamp(delta, -0.5f, 0.5f);
        }
    });
    // connected centre lines (gaps up to kLink − 1 samples bridged) of fewer than stepMinLength
    // points are not steps
    constexpr int kLink = 3;
    std::vector<std::pair<size_t, size_t>> lines;  // each line's points in m.points
    const auto isCand = [&](size_t k) { return cand[k] != 0; };
    forEachRegion(W, H, kLink, isCand, isCand, [&](const std::vector<size_t>& comp) {
        if (comp.size() < static_cast<size_t>(o.stepMinLength)) return;
        // one jump per line: the median of its points' (a tool-change step is one offset)
        std::vector<float> jumps;
        for (size_t k : comp) jumps.push_back(candJ[k]);
        auto mid = jumps.begin() + static_cast<std::ptrdiff_t>(jumps.size() / 2);
        std::nth_element(jumps.begin(), mid, jumps.end());
        const size_t first = m.points.size();
        lines.emplace_back(first, first + comp.size());
        for (size_t k : comp) {
            const StepDir u = kStepDirs[candDir[k]];
            StepPoint p;
            p.x = static_cast<float>(k % static_cast<size_t>(W)) +
                  offset[k] * static_cast<float>(u.dx);
            p.z = static_cast<float>(k / static_cast<size_t>(W)) +
                  offset[k] * static_cast<float>(u.dz);
            p.nx = normX[k];
            p.nz = normZ[k];
            p.jump = *mid;
            m.points.push_back(p);
        }
        // each normal: across the line's principal direction among its points within
        // kNormalRadius samples, toward the side their gradients point to (the high side)
        constexpr float kNormalRadius = 6.0f;
        std::vector<StepPoint> line(m.points.begin() + static_cast<std::ptrdiff_t>(first),
                                    m.points.end());
        for (size_t i = 0; i < line.size(); ++i) {
            double sx = 0, sz = 0, cx = 0, cz = 0, cxx = 0, cxz = 0, czz = 0;
            int cnt = 0;
            for (const StepPoint& q : line)
                if (std::abs(q.x - line[i].x) <= kNormalRadius &&
                    std::abs(q.z - line[i].z) <= kNormalRadius) {
                    sx += q.nx;
                    sz += q.nz;
                    cx += q.x;
                    cz += q.z;
                    cxx += static_cast<double>(q.x) * q.x;
                    cxz += static_cast<double>(q.x) * q.z;
                    czz += static_cast<double>(q.z) * q.z;
                    ++cnt;
                }
            double nx = sx, nz = sz;
            if (cnt >= 3) {  // the covariance's minor axis
                cx /= cnt;
                cz /= cnt;
                const double a = cxx / cnt - cx * cx, c = czz / cnt - cz * cz,
                             bb = cxz / cnt - cx * cz;
                const double theta = 0.5 * std::atan2(2 * bb, a - c);  // major axis
                const double mx = -std::sin(theta), mz = std::cos(theta);
                const double sgn = mx * sx + mz * sz >= 0 ? 1.0 : -1.0;
                nx = sgn * mx;
                nz = sgn * mz;
            }
            const double l = std::hypot(nx, nz);
            if (l > 0) {
                m.points[first + i].nx = static_cast<float>(nx / l);
                m.points[first + i].nz = static_cast<float>(nz / l);
            }
        }
    });
    if (o.stepGap > 0) fillCircleGaps(m, lines, W, H, o.stepGap);
    if (m.points.empty()) return m;
    // nearest centre point of every sample within the band (splatted discs)
    const int reach = static_cast<int>(std::ceil(std::max(o.stepBand, o.stepRampHalf + 1.0)));
    std::vector<float> dist2(n, std::numeric_limits<float>::infinity());
    std::vector<int32_t> nearest(n, -1);
    for (size_t i = 0; i < m.points.size(); ++i) {
        const StepPoint& p = m.points[i];
        const int cx = static_cast<int>(std::lround(p.x)), cz = static_cast<int>(std::lround(p.z));
        for (int y = std::max(0, cz - reach); y <= std::min(H - 1, cz + reach); ++y)
            for (int x = std::max(0, cx - reach); x <= std::min(W - 1, cx + reach); ++x) {
                const float dx = static_cast<float>(x) - p.x, dz = static_cast<float>(y) - p.z;
                const float r2 = dx * dx + dz * dz;
                const size_t k = static_cast<size_t>(y) * W + x;
                if (r2 < dist2[k]) {
                    dist2[k] = r2;
                    nearest[k] = static_cast<int32_t>(i);
                }
            }
    }
    m.ramp.assign(n, 0);
    m.band.assign(n, 0);
    // the high side's end of the marked ramp: where a smoothstep ramp 2·stepRampHalf wide
    // centred on the line has moved the surface by stepRampMoved of the jump
    double highSide = o.stepRampHalf;
    if (o.stepRampMoved > 0) {
        double lo = 0, hi = 1;  // smoothstep(v) = stepRampMoved, v in [0, 0.5]
        for (int i = 0; i < 60; ++i) {
            const double v = 0.5 * (lo + hi);
            (v * v * (3 - 2 * v) < o.stepRampMoved ? lo : hi) = v;
        }
        highSide = (1.0 - 2.0 * lo) * o.stepRampHalf;
    }
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            if (nearest[k] < 0) continue;
            const StepPoint& p = m.points[static_cast<size_t>(nearest[k])];
            const double r = std::sqrt(static_cast<double>(dist2[k]));
            const double t = (x - static_cast<double>(p.x)) * p.nx +
                             (y - static_cast<double>(p.z)) * p.nz;  // along the normal
            if (t > -o.stepRampHalf && t < highSide && r < o.stepRampHalf + 1.0) m.ramp[k] = 255;
            if (r <= o.stepBand) m.band[k] = 1;
        }
    });
    return m;
}

}  // namespace sl::defectmap
