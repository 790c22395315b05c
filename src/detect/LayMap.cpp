#include "detect/LayMap.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "detect/ImageFilters.h"

namespace sl {

void checkLayMapOptions(const LayMapOptions& o) {
    auto oddAtLeast3 = [](int v, const char* name, const char* fix) {
        if (v < 3 || v % 2 == 0)
            throw inputError(option(name), "must be odd and >= 3 (got " + std::to_string(v) + ")",
                             fix);
    };
    oddAtLeast3(o.layLength, "lay-length", "The default is 81 samples");
    oddAtLeast3(o.levelWindow, "lay-level-window", "The default is 31 samples");
    oddAtLeast3(o.macroWindow, "lay-macro-window", "The default is 61 samples");
    if (!(o.clipQuantile > 0.0 && o.clipQuantile <= 1.0))
        throw inputError(option("lay-clip-quantile"), "must be in (0, 1]", "The default is 0.95");
    if (!(o.seedSigma > 0.0))
        throw inputError(option("lay-seed-sigma"), "must be > 0", "The default is 6");
    if (!(o.growSigma > 0.0 && o.growSigma <= o.seedSigma))
        throw inputError(option("lay-grow-sigma"), "must be > 0 and <= the seed threshold",
                         "The default is 3");
    if (!(o.textureRms >= 0.0))
        throw inputError(option("lay-texture-rms"), "must be >= 0 (0: off)", "The default is 1.5");
    if (!(o.borderRegrow >= 0.0 && o.borderRegrow <= 1.0))
        throw inputError(option("lay-border-regrow"), "must be in [0, 1]", "The default is 0.5");
    if (!(o.fieldSigma >= 0.0))
        throw inputError(option("lay-field-sigma"), "must be >= 0 (0: one lay for the map)",
                         "The default is 0; 16 follows curved lays");
    if (!(o.fieldCoherence >= 0.0 && o.fieldCoherence <= 1.0))
        throw inputError(option("lay-field-coherence"), "must be in [0, 1]", "The default is 0.1");
    if (o.layPasses < 1)
        throw inputError(option("lay-passes"),
                         "must be >= 1 (got " + std::to_string(o.layPasses) + ")",
                         "The default is 1");
    if (o.fieldExclude < 0)
        throw inputError(option("lay-field-exclude"),
                         "must be >= 0 (got " + std::to_string(o.fieldExclude) + ")",
                         "The default is 4 samples");
    if (o.border < 0)
        throw inputError(option("lay-border"),
                         "must be >= 0 (got " + std::to_string(o.border) + ")");
    if (o.minRegion < 1)
        throw inputError(option("lay-min-region"),
                         "must be >= 1 (got " + std::to_string(o.minRegion) + ")");
}

namespace {

/// A position mirrored into [0, n − 1] (reflection without repeating the edge sample).
double mirrorInto(double v, int n) {
    if (n == 1) return 0.0;
    const double period = 2.0 * (n - 1);
    v = std::fmod(std::abs(v), period);
    return v > n - 1 ? period - v : v;
}

float bilinearMirrored(std::span<const float> h, int W, int H, double x, double z) {
    x = mirrorInto(x, W);
    z = mirrorInto(z, H);
    const int x0 = std::min(static_cast<int>(x), W - 1), z0 = std::min(static_cast<int>(z), H - 1);
    const int x1 = std::min(x0 + 1, W - 1), z1 = std::min(z0 + 1, H - 1);
    const double fx = x - x0, fz = z - z0;
    auto at = [&](int i, int j) { return static_cast<double>(h[static_cast<size_t>(j) * W + i]); };
    return static_cast<float>((1 - fz) * ((1 - fx) * at(x0, z0) + fx * at(x1, z0)) +
                              fz * ((1 - fx) * at(x0, z1) + fx * at(x1, z1)));
}

/// A separable Gaussian blur of σ samples (radius 3σ, edges clamped), in place.
void gaussianBlur(std::vector<float>& v, int W, int H, double sigma) {
    const int R = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
    std::vector<double> kernel(static_cast<size_t>(2 * R + 1));
    double sum = 0;
    for (int i = -R; i <= R; ++i)
        sum += kernel[static_cast<size_t>(i + R)] = std::exp(-i * i / (2 * sigma * sigma));
    for (double& k : kernel) k /= sum;
    std::vector<float> tmp(v.size());
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            double s = 0;
            for (int i = -R; i <= R; ++i)
                s += kernel[static_cast<size_t>(i + R)] *
                     v[static_cast<size_t>(y) * W + std::clamp(x + i, 0, W - 1)];
            tmp[static_cast<size_t>(y) * W + x] = static_cast<float>(s);
        }
    });
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            double s = 0;
            for (int i = -R; i <= R; ++i)
                s += kernel[static_cast<size_t>(i + R)] *
                     tmp[static_cast<size_t>(std::clamp(y + i, 0, H - 1)) * W + x];
            v[static_cast<size_t>(y) * W + x] = static_cast<float>(s);
        }
    });
}

}  // namespace

namespace {

/// One pass of the method; with `exclude` (1 where a sample is left out of the local lay
/// field's tensor) and o.fieldSigma > 0 the background follows the local field.
/// Steps 1–2 on src: the lay (global, and the local field with `exclude`) and
/// src − its median along the lay.
struct LayPass {
    std::vector<float> res;
    double layX = 1, layZ = 0, coherence = 0;
};

LayPass removeLay(std::span<const float> heights, int W, int H, const LayMapOptions& o,
                  const std::vector<uint8_t>* exclude) {
    const size_t n = heights.size();
    const int b = o.border;
    LayPass r;
    // 1. the lay: the clipped structure tensor's minor eigenvector, on the heights smoothed by a
    // Gaussian of σ = 1.5 samples (central differences of waves a few samples long are damped
    // differently along x and z, which tilts the tensor; the smoothing removes those waves)
    std::vector<float> g(heights.begin(), heights.end());
    {
        constexpr int kR = 5;
        double kernel[2 * kR + 1], sum = 0;
        for (int i = -kR; i <= kR; ++i) sum += kernel[i + kR] = std::exp(-i * i / (2 * 1.5 * 1.5));
        for (double& v : kernel) v /= sum;
        std::vector<float> tmp(n);
        auto clampi = [](int i, int m) { return std::clamp(i, 0, m - 1); };
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                double v = 0;
                for (int i = -kR; i <= kR; ++i)
                    v += kernel[i + kR] * g[static_cast<size_t>(y) * W + clampi(x + i, W)];
                tmp[static_cast<size_t>(y) * W + x] = static_cast<float>(v);
            }
        });
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                double v = 0;
                for (int i = -kR; i <= kR; ++i)
                    v += kernel[i + kR] * tmp[static_cast<size_t>(clampi(y + i, H)) * W + x];
                g[static_cast<size_t>(y) * W + x] = static_cast<float>(v);
            }
        });
    }
    // central differences of the smoothed heights at every sample (one-sided at the edges):
    // the local lay field (step 1b) needs them everywhere
    std::vector<float> fgx(n), fgz(n);
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            const int xl = std::max(x - 1, 0), xr = std::min(x + 1, W - 1);
            const int yu = std::max(y - 1, 0), yd = std::min(y + 1, H - 1);
            fgx[k] = (g[static_cast<size_t>(y) * W + xr] - g[static_cast<size_t>(y) * W + xl]) /
                     static_cast<float>(std::max(xr - xl, 1));
            fgz[k] = (g[static_cast<size_t>(yd) * W + x] - g[static_cast<size_t>(yu) * W + x]) /
                     static_cast<float>(std::max(yd - yu, 1));
        }
    });
    double clipAll = 0.0;
    std::vector<float> gx, gz, mag;
    for (int y = std::max(b, 1); y < std::min(H - b, H - 1); ++y)
        for (int x = std::max(b, 1); x < std::min(W - b, W - 1); ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            gx.push_back(0.5f * (g[k + 1] - g[k - 1]));
            gz.push_back(0.5f * (g[k + W] - g[k - W]));
            mag.push_back(std::hypot(gx.back(), gz.back()));
        }
    g = {};
    if (!mag.empty()) {
        std::vector<float> sorted = mag;
        const size_t q =
            std::min(sorted.size() - 1,
                     static_cast<size_t>(o.clipQuantile * static_cast<double>(sorted.size() - 1)));
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(q),
                         sorted.end());
        const double clip = sorted[q];
        clipAll = clip;
        double jxx = 0, jxz = 0, jzz = 0;
        for (size_t k = 0; k < mag.size(); ++k) {
            const double f = mag[k] > clip && mag[k] > 0 ? clip / mag[k] : 1.0;
            const double ux = f * gx[k], uz = f * gz[k];
            jxx += ux * ux;
            jxz += ux * uz;
            jzz += uz * uz;
        }
        const double trace = jxx + jzz;
        if (trace > 0) {
            // the dominant gradient's angle phi: the mode of the clipped gradients' doubled
            // angles (weights |g|², 720 bins, smoothed by a Gaussian of 6 bins), not the tensor's
            // mean, which a long deep scratch across the lay tilts by degrees
            constexpr int kBins = 720;
            std::vector<double> hist(kBins, 0.0), smooth(kBins, 0.0);
            for (size_t k = 0; k < mag.size(); ++k) {
                if (!(mag[k] > 0)) continue;
                const double f = mag[k] > clip ? clip / mag[k] : 1.0;
                const double a = 2.0 * std::atan2(static_cast<double>(gz[k]), gx[k]);  // (-2π, 2π]
                int bin = static_cast<int>(std::floor((a + 2 * M_PI) / (2 * M_PI) * kBins)) % kBins;
                hist[static_cast<size_t>(bin)] += f * f * mag[k] * mag[k];
            }
            for (int i = 0; i < kBins; ++i)
                for (int j = -18; j <= 18; ++j)
                    smooth[static_cast<size_t>(i)] +=
                        std::exp(-j * j / 72.0) *
                        hist[static_cast<size_t>((i + j + kBins) % kBins)];
            const int top =
                static_cast<int>(std::max_element(smooth.begin(), smooth.end()) - smooth.begin());
            const double ym = smooth[static_cast<size_t>((top + kBins - 1) % kBins)],
                         y0 = smooth[static_cast<size_t>(top)],
                         yp = smooth[static_cast<size_t>((top + 1) % kBins)];
            const double den = ym - 2 * y0 + yp;
            const double off = den < 0 ? 0.5 * (ym - yp) / den : 0.0;  // parabola's vertex
            const double phi = 0.5 * ((top + 0.5 + off) / kBins * 2 * M_PI);
            r.layX = -std::sin(phi);
            r.layZ = std::cos(phi);
            r.coherence = std::hypot(jxx - jzz, 2.0 * jxz) / trace;
        }
    }
    gx = {};
    gz = {};
    mag = {};

    // 1b. the local lay field: the clipped structure tensor smoothed by a Gaussian of
    // σ = fieldSigma samples, its minor eigenvector at every sample; where its coherence is
    // below fieldCoherence the global lay. Off (fieldSigma 0): the global lay everywhere.
    std::vector<float> tx, tz;
    if (exclude && o.fieldSigma > 0 && clipAll > 0) {
        std::vector<float> a(n), c(n), e(n);  // jxx − jzz, 2·jxz, jxx + jzz
        for (size_t k = 0; k < n; ++k) {
            const double m = std::hypot(fgx[k], fgz[k]);
            const double f = (*exclude)[k] ? 0.0 : m > clipAll ? clipAll / m : 1.0;
            const double ux = f * fgx[k], uz = f * fgz[k];
            a[k] = static_cast<float>(ux * ux - uz * uz);
            c[k] = static_cast<float>(2 * ux * uz);
            e[k] = static_cast<float>(ux * ux + uz * uz);
        }
        gaussianBlur(a, W, H, o.fieldSigma);
        gaussianBlur(c, W, H, o.fieldSigma);
        gaussianBlur(e, W, H, o.fieldSigma);
        tx.resize(n);
        tz.resize(n);
        for (size_t k = 0; k < n; ++k) {
            const double coh = e[k] > 0 ? std::hypot(a[k], c[k]) / e[k] : 0.0;
            if (coh < o.fieldCoherence) {
                tx[k] = static_cast<float>(r.layX);
                tz[k] = static_cast<float>(r.layZ);
                continue;
            }
            const double phi = 0.5 * std::atan2(static_cast<double>(c[k]), a[k]);
            tx[k] = static_cast<float>(-std::sin(phi));
            tz[k] = static_cast<float>(std::cos(phi));
        }
    }
    fgx = {};
    fgz = {};

    // 2. the background: the median along the lay (a straight line along the global lay, or
    // the streamline of the local field through the sample, unit steps each way)
    std::vector<float> res(n);
    const int half = o.layLength / 2;
    tbb::parallel_for(0, H, [&](int y) {
        if (interruptRequested()) return;  // a row at a time: the whole loop takes seconds
        thread_local std::vector<float> line;
        line.resize(static_cast<size_t>(o.layLength));
        for (int x = 0; x < W; ++x) {
            if (tx.empty()) {
                for (int s = -half; s <= half; ++s)
                    line[static_cast<size_t>(s + half)] =
                        bilinearMirrored(heights, W, H, x + s * r.layX, y + s * r.layZ);
            } else {
                line[static_cast<size_t>(half)] = heights[static_cast<size_t>(y) * W + x];
                for (int sign = -1; sign <= 1; sign += 2) {
                    double px = x, pz = y;
                    const size_t k0 = static_cast<size_t>(y) * W + x;
                    double dx = static_cast<double>(sign) * tx[k0],
                           dz = static_cast<double>(sign) * tz[k0];
                    for (int s = 1; s <= half; ++s) {
                        px += dx;
                        pz += dz;
                        line[static_cast<size_t>(half + sign * s)] =
                            bilinearMirrored(heights, W, H, px, pz);
                        const int ix = static_cast<int>(std::lround(mirrorInto(px, W)));
                        const int iz = static_cast<int>(std::lround(mirrorInto(pz, H)));
                        const size_t q = static_cast<size_t>(iz) * W + ix;
                        double nx = tx[q], nz = tz[q];
                        if (nx * dx + nz * dz < 0) {
                            nx = -nx;
                            nz = -nz;
                        }
                        dx = nx;
                        dz = nz;
                    }
                }
            }
            auto mid = line.begin() + half;
            std::nth_element(line.begin(), mid, line.end());
            const size_t k = static_cast<size_t>(y) * W + x;
            res[k] = heights[k] - *mid;
        }
    });
    throwIfInterrupted();
    r.res = std::move(res);
    return r;
}

LayMap detectOnce(std::span<const float> heights, int width, int height, const LayMapOptions& o,
                  const std::vector<uint8_t>* exclude) {
    const int W = width, H = height;
    const size_t n = heights.size();
    LayMap r;
    r.map.assign(n, 0);
    const int b = o.border;
    auto inside = [&](int x, int y) { return x >= b && y >= b && x < W - b && y < H - b; };
    if (W - 2 * b < 1 || H - 2 * b < 1) return r;  // nothing outside the border

    // 1–2, then again on the residual: where two lays cross (a face mill's two passes) the
    // first takes one out, the second the other
    std::vector<float> res;
    {
        LayPass p = removeLay(heights, W, H, o, exclude);
        r.layX = p.layX;
        r.layZ = p.layZ;
        r.coherence = p.coherence;
        res = std::move(p.res);
        for (int pass = 1; pass < o.layPasses; ++pass) res = removeLay(res, W, H, o, exclude).res;
    }
    throwIfInterrupted();
    // 3. the residual, levelled
    {
        const std::vector<float> level = separableRunningMedian(res, W, H, o.levelWindow);
        for (size_t k = 0; k < n; ++k) res[k] -= level[k];
    }
    std::vector<float> d(heights.begin(), heights.end());
    {
        const std::vector<float> macro = separableRunningMedian(d, W, H, o.macroWindow);
        for (size_t k = 0; k < n; ++k) d[k] -= macro[k];
    }
    std::vector<float> in;
    double sum2 = 0.0;
    size_t count = 0;
    for (int y = b; y < H - b; ++y)
        for (int x = b; x < W - b; ++x) {
            const size_t k = static_cast<size_t>(y) * W + x;
            in.push_back(std::abs(res[k]));
            sum2 += static_cast<double>(d[k]) * d[k];
            ++count;
        }
    d = {};
    r.textureRms = std::sqrt(sum2 / static_cast<double>(count));
    {
        auto mid = in.begin() + static_cast<std::ptrdiff_t>(in.size() / 2);
        std::nth_element(in.begin(), mid, in.end());
        r.sigma = 1.4826 * *mid;
    }
    in = {};
    // a noise-free texture leaves rounding in r: σ no smaller than 1e-6 of the texture's RMS
    const double sigma = std::max(r.sigma, 1e-6 * r.textureRms);
    if (!(sigma > 0.0)) return r;  // a constant map

    // 4. regions: hysteresis, the texture's RMS, the border's inner line
    const double grow = o.growSigma * sigma, seed = o.seedSigma * sigma;
    const double shallow = o.textureRms * r.textureRms;
    // a region that reaches the border is split once more at the higher grow threshold
    const double regrow = std::max(grow, o.borderRegrow * shallow);
    std::vector<uint8_t> seen(n, 0);  // 1: visited at grow, 2: visited at regrow
    std::vector<size_t> region, stack;
    // the region of `start` among samples with |r| >= level (and allowed), visited marked
    auto collect = [&](size_t start, double level, uint8_t mark, const std::vector<uint8_t>* allow,
                       double& peak, bool& touchesBorder) {
        region.clear();
        stack.assign(1, start);
        seen[start] = mark;
        peak = 0.0;
        touchesBorder = false;
        while (!stack.empty()) {
            const size_t k = stack.back();
            stack.pop_back();
            region.push_back(k);
            const int x = static_cast<int>(k % static_cast<size_t>(W));
            const int y = static_cast<int>(k / static_cast<size_t>(W));
            peak = std::max(peak, static_cast<double>(std::abs(res[k])));
            if (x == b || y == b || x == W - 1 - b || y == H - 1 - b) touchesBorder = true;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (!inside(xx, yy)) continue;
                    const size_t q = static_cast<size_t>(yy) * W + xx;
                    if (seen[q] >= mark || std::abs(res[q]) < level || (allow && !(*allow)[q]))
                        continue;
                    seen[q] = mark;
                    stack.push_back(q);
                }
        }
    };
    // the rules (seed, size, texture's RMS); true when the region is kept
    auto judge = [&](double peak) {
        if (peak < seed || region.size() < static_cast<size_t>(o.minRegion)) return false;
        if (peak < shallow) {
            ++r.droppedShallow;
            return false;
        }
        return true;
    };
    auto keep = [&]() {
        ++r.regions;
        for (size_t k : region) r.map[k] = 255;
    };
    std::vector<uint8_t> allow;
    std::vector<size_t> outer;
    for (size_t start = 0; start < n; ++start) {
        const int sx = static_cast<int>(start % static_cast<size_t>(W));
        const int sy = static_cast<int>(start / static_cast<size_t>(W));
        if (seen[start] || !inside(sx, sy) || std::abs(res[start]) < grow) continue;
        double peak = 0.0;
        bool touches = false;
        collect(start, grow, 1, nullptr, peak, touches);
        if (!judge(peak)) continue;
        if (!o.dropBorderRegions || !touches) {
            keep();
            continue;
        }
        // split at the higher threshold: what is kept is what stands out of the region's own
        // texture and does not reach the border
        outer = region;
        if (allow.empty()) allow.assign(n, 0);
        for (size_t k : outer) allow[k] = 1;
        for (size_t k : outer) {
            if (seen[k] == 2 || std::abs(res[k]) < regrow) continue;
            double p = 0.0;
            bool t = false;
            collect(k, regrow, 2, &allow, p, t);
            if (!judge(p)) continue;
            if (t) {
                ++r.droppedBorder;
                continue;
            }
            keep();
        }
        for (size_t k : outer) allow[k] = 0;
    }
    return r;
}

}  // namespace

LayMap detectLayDefects(std::span<const float> heights, int width, int height,
                        const LayMapOptions& o) {
    checkLayMapOptions(o);
    LayMap first = detectOnce(heights, width, height, o, nullptr);
    if (!(o.fieldSigma > 0)) return first;
    // the local field leaves out what the first pass (one lay for the map) marked, grown by
    // fieldExclude samples: a deep scratch across the lay would otherwise turn the field
    // along itself and become its own background
    const int W = width, H = height, g = o.fieldExclude;
    std::vector<uint8_t> exclude(first.map.size(), 0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (!first.map[static_cast<size_t>(y) * W + x]) continue;
            for (int yy = std::max(0, y - g); yy <= std::min(H - 1, y + g); ++yy)
                for (int xx = std::max(0, x - g); xx <= std::min(W - 1, x + g); ++xx)
                    exclude[static_cast<size_t>(yy) * W + xx] = 1;
        }
    throwIfInterrupted();
    return detectOnce(heights, width, height, o, &exclude);
}

}  // namespace sl
