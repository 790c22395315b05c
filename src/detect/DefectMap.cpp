#include "detect/DefectMap.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <unsupported/Eigen/FFT>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Registry.h"
#include "core/Stopwatch.h"

namespace sl {

namespace {

constexpr DefectMethodRow kMethods[] = {
    {DefectMethod::Auto, "auto",
     "a simulator's part: remove the periodic tool-path texture (spectral notch) and a robust "
     "local level, mark what stands out (levels, edges, texture-change regions); a measurement "
     "(an instrument's file, or heightmap.measured): selfsim"},
    {DefectMethod::Lay, "lay",
     "measured textures: the median along the texture's own lay is its background; mark regions "
     "far above the residual's robust sigma and the texture's RMS, none along the border"},
    {DefectMethod::SelfSim, "selfsim",
     "what the texture does not repeat: each sample's background is the median of its copies at "
     "the texture's own offsets; mark what an a-contrario test finds in the residual"},
    {DefectMethod::Paper, "paper",
     "the paper's scratch map: patches whose moving-average-detrended range is large"},
};

}  // namespace

std::span<const DefectMethodRow> defectMethodTable() {
    return kMethods;
}

DefectMethod parseDefectMethod(std::string_view name, const std::string& where) {
    return parseRegistryName(defectMethodTable(), name, where).value;
}

const char* defectMethodName(DefectMethod method) {
    return registryRow(defectMethodTable(), method).name;
}

size_t DefectMap::markedCount() const {
    size_t n = 0;
    for (uint8_t v : map) n += v != 0;
    return n;
}

double DefectMap::markedFraction() const {
    return map.empty() ? 0.0 : static_cast<double>(markedCount()) / static_cast<double>(map.size());
}

namespace {

using Complex = std::complex<float>;

void checkOptions(const DefectMapOptions& o) {
    auto oddAtLeast3 = [](int v, const char* name, const char* fix) {
        if (v < 3 || v % 2 == 0)
            throw inputError(option(name), "must be odd and >= 3 (got " + std::to_string(v) + ")",
                             fix);
    };
    if (o.pad < 0)
        throw inputError(option("pad"), "must be >= 0 (got " + std::to_string(o.pad) + ")");
    oddAtLeast3(o.spectrumWindow, "spectrum-window", "The default is 9 bins");
    oddAtLeast3(o.levelWindow, "level-window", "The default is 31 samples");
    oddAtLeast3(o.macroWindow, "macro-window", "The default is 61 samples");
    if (o.edgeWindow < 5 || o.edgeWindow % 2 == 0)
        throw inputError(option("edge-window"),
                         "must be odd and >= 5 (got " + std::to_string(o.edgeWindow) + ")",
                         "A quadratic fits 3 samples exactly; the default is 7");
    if (o.energyWindow != 0) oddAtLeast3(o.energyWindow, "energy-window", "0 switches it off");
    if (!(o.notchRatio > 1.0))
        throw inputError(option("notch-ratio"),
                         "must be > 1 (got " + std::to_string(o.notchRatio) + ")");
    if (o.passes < 1)
        throw inputError(option("passes"), "must be >= 1 (got " + std::to_string(o.passes) + ")");
    if (o.notchSpread < 0) throw inputError(option("notch-spread"), "must be >= 0");
    if (!(o.notchGrow > 0.0 && o.notchGrow <= o.notchRatio))
        throw inputError(option("notch-grow"),
                         "must be in (0, notch-ratio] (got " + std::to_string(o.notchGrow) + ")");
    if (o.keepLowBins < 0) throw inputError(option("keep-low-bins"), "must be >= 0");
    if (!(o.seedSigma > 0.0))
        throw inputError(option("seed-sigma"),
                         "must be > 0 (got " + std::to_string(o.seedSigma) + ")");
    if (!(o.growSigma > 0.0 && o.growSigma <= o.seedSigma))
        throw inputError(option("grow-sigma"),
                         "must be in (0, seed-sigma] (got " + std::to_string(o.growSigma) + ")");
    if (!(o.edgeWeight >= 0.0))
        throw inputError(option("edge-weight"),
                         "must be >= 0 (got " + std::to_string(o.edgeWeight) + ")");
    if (o.border < 0)
        throw inputError(option("border"), "must be >= 0 (got " + std::to_string(o.border) + ")");
    if (o.minRegion < 1)
        throw inputError(option("min-region"),
                         "must be >= 1 (got " + std::to_string(o.minRegion) + ")");
    if (o.lineLength != 0 && (o.lineLength < 3 || o.lineLength % 2 == 0))
        throw inputError(option("line-length"),
                         "must be 0 or odd and >= 3 (got " + std::to_string(o.lineLength) + ")",
                         "0 switches the line-valley score off; the default is 15");
    if (o.lineOrientations < 1 || o.lineOrientations > 64)
        throw inputError(option("line-orientations"),
                         "must be in [1, 64] (got " + std::to_string(o.lineOrientations) + ")");
    if (!(o.lineOffset >= 1.0 && o.lineOffset <= 16.0))
        throw inputError(option("line-offset"),
                         "must be in [1, 16] samples (got " + std::to_string(o.lineOffset) + ")");
    if (!(o.seedTail >= 0.0) || !std::isfinite(o.seedTail))
        throw inputError(option("seed-tail"),
                         "must be >= 0 (got " + std::to_string(o.seedTail) + ")",
                         "0 switches the texture's-tail thresholds off");
    if (!(o.growTail >= 0.0) || !std::isfinite(o.growTail))
        throw inputError(option("grow-tail"),
                         "must be >= 0 (got " + std::to_string(o.growTail) + ")",
                         "0 scales the grow thresholds with the seed's");
    if (!(o.seedTailQuantile > 0.0 && o.seedTailQuantile < 1.0))
        throw inputError(option("seed-tail-quantile"),
                         "must be in (0, 1) (got " + std::to_string(o.seedTailQuantile) + ")");
    if (!(o.lineSeedSigma > 0.0))
        throw inputError(option("line-seed-sigma"),
                         "must be > 0 (got " + std::to_string(o.lineSeedSigma) + ")");
    if (!(o.lineGrowSigma > 0.0 && o.lineGrowSigma <= o.lineSeedSigma))
        throw inputError(option("line-grow-sigma"), "must be in (0, line-seed-sigma] (got " +
                                                        std::to_string(o.lineGrowSigma) + ")");
    if (!(o.textureEnergyRatio > 1.0))
        throw inputError(option("texture-energy-ratio"),
                         "must be > 1 (got " + std::to_string(o.textureEnergyRatio) + ")");
    if (o.textureSectors < 1 || o.textureSectors > 16)
        throw inputError(option("texture-sectors"),
                         "must be in [1, 16] (got " + std::to_string(o.textureSectors) + ")",
                         "1 takes the texture whole; the default is 2");
    if (o.stepWindow < 3 || o.stepWindow % 2 == 0)
        throw inputError(option("step-window"),
                         "must be odd and >= 3 (got " + std::to_string(o.stepWindow) + ")",
                         "The default is 11 samples");
    if (!(o.stepSigma > 0.0))
        throw inputError(option("step-sigma"),
                         "must be > 0 (got " + std::to_string(o.stepSigma) + ")");
    if (!(o.stepSharpness > 0.0 && o.stepSharpness <= 1.0))
        throw inputError(option("step-sharpness"),
                         "must be in (0, 1] (got " + std::to_string(o.stepSharpness) + ")");
    if (o.stepMinLength < 1)
        throw inputError(option("step-min-length"),
                         "must be >= 1 (got " + std::to_string(o.stepMinLength) + ")");
    if (!(o.stepRampHalf > 0.0))
        throw inputError(option("step-ramp-half"),
                         "must be > 0 (got " + std::to_string(o.stepRampHalf) + ")");
    if (!(o.stepBand >= o.stepRampHalf))
        throw inputError(option("step-band"),
                         "must be >= step-ramp-half (got " + std::to_string(o.stepBand) + ")");
    if (!(o.stepGap >= 0.0))
        throw inputError(option("step-gap"), "must be >= 0 (got " + std::to_string(o.stepGap) + ")",
                         "0 fills no gap; the default is 200 samples");
    if (!(o.stepRampMoved >= 0.0 && o.stepRampMoved < 0.5))
        throw inputError(option("step-ramp-moved"),
                         "must be in [0, 0.5) (got " + std::to_string(o.stepRampMoved) + ")",
                         "0 marks the whole ramp; the default is 0.02");
    if (o.ringWindow != 0) oddAtLeast3(o.ringWindow, "ring-window", "0 switches it off");
    if (!(o.ringIsotropy >= 0.0 && o.ringIsotropy <= 1.0))
        throw inputError(option("ring-isotropy"),
                         "must be in [0, 1] (got " + std::to_string(o.ringIsotropy) + ")");
    if (!(o.ringRatio > 0.0 && o.ringRatio <= 1.0))
        throw inputError(option("ring-ratio"),
                         "must be in (0, 1] (got " + std::to_string(o.ringRatio) + ")");
    if (!(o.ringResidual > 0.0))
        throw inputError(option("ring-residual"),
                         "must be > 0 (got " + std::to_string(o.ringResidual) + ")");
    if (!(o.energyRatio > 1.0))
        throw inputError(option("energy-ratio"),
                         "must be > 1 (got " + std::to_string(o.energyRatio) + ")");
}

void checkInput(std::span<const float> heights, int width, int height) {
    if (width < 2 || height < 2)
        throw inputError(
            "defect map",
            "height map is " + std::to_string(width) + "x" + std::to_string(height) + " samples",
            "It needs at least 2x2 samples");
    if (heights.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
        throw inputError("defect map", "height map has " + std::to_string(heights.size()) +
                                           " values, expected " + std::to_string(width) + "x" +
                                           std::to_string(height));
    for (size_t k = 0; k < heights.size(); ++k)
        if (!std::isfinite(heights[k]))
            throw inputError("defect map",
                             "height at row " + std::to_string(k / static_cast<size_t>(width)) +
                                 ", column " + std::to_string(k % static_cast<size_t>(width)) +
                                 " is not finite",
                             "Fill the holes first");
}

/// The smallest n' >= n whose prime factors are 2, 3 and 5 only.
int nextSmooth(int n) {
    for (int m = std::max(n, 1);; ++m) {
        int r = m;
        for (int p : {2, 3, 5})
            while (r % p == 0) r /= p;
        if (r == 1) return m;
    }
}

/// Mirror index into [0, n): reflection about the borders (… 2 1 0 1 2 …), any i.
int mirror(int i, int n) {
    if (n == 1) return 0;
    const int period = 2 * (n - 1);
    i %= period;
    if (i < 0) i += period;
    return i < n ? i : period - i;
}

/// Fills one padded line `out` (length np) from `in` (length n) starting `lead` samples before
/// in[0]: the map, then a tail cross-faded from the mirror at the end to the mirror at the start.
void padLine(const float* in, int n, int lead, float* out, int np) {
    const int tail = np - n;  // samples of extension (lead of them before, the rest after)
    for (int t = 0; t < np; ++t) {
        const int i = t - lead;
        if (i >= 0 && i < n) {
            out[t] = in[i];
            continue;
        }
        // position in the extension, 0 right after the map's end … tail−1 right before its start
        const int e = i >= n ? i - n : i + tail;
        const double s = (e + 0.5) / tail;        // 0 at the end border, 1 at the start border
        const float a = in[mirror(n + e, n)];     // mirror about the end
        const float b = in[mirror(e - tail, n)];  // mirror about the start (−1, −2, …)
        out[t] = static_cast<float>((1.0 - s) * a + s * b);
    }
}

/// Running median of x (length n) over windows of `w` (odd) samples, into out. periodic: the
/// index wraps (windows always full; w <= n); else the window shrinks at the borders.
void runningMedian(const float* x, int n, int w, bool periodic, float* out, std::vector<float>& win,
                   int stride = 1) {
    const int r = w / 2;
    win.clear();
    auto at = [&](int i) { return x[static_cast<size_t>(i) * stride]; };
    auto insert = [&](float v) { win.insert(std::upper_bound(win.begin(), win.end(), v), v); };
    auto erase = [&](float v) { win.erase(std::lower_bound(win.begin(), win.end(), v)); };
    if (periodic && w <= n) {
        for (int k = -r; k <= r; ++k) insert(at(((k % n) + n) % n));
    } else {
        periodic = false;
        for (int k = 0; k <= std::min(r, n - 1); ++k) insert(at(k));
    }
    for (int i = 0; i < n; ++i) {
        if (i > 0) {
            if (periodic) {
                erase(at(((i - 1 - r) % n + n) % n));
                insert(at((i + r) % n));
            } else {
                if (i - 1 - r >= 0) erase(at(i - 1 - r));
                if (i + r < n) insert(at(i + r));
            }
        }
        const size_t m = win.size();
        out[static_cast<size_t>(i) * stride] =
            m % 2 ? win[m / 2] : 0.5f * (win[m / 2 - 1] + win[m / 2]);
    }
}

/// Running medians along every row of a W×H image (windows shrink at the borders).
void rowMedians(const float* img, int W, int H, int w, float* out) {
    tbb::parallel_for(0, H, [&](int y) {
        thread_local std::vector<float> win;
        const size_t o = static_cast<size_t>(y) * W;
        runningMedian(img + o, W, w, false, out + o, win);
    });
}

/// Running medians along every column of a W×H image (periodic or shrinking at the borders);
/// columns are gathered in blocks of 16, a cache line of each row at a time.
void columnMedians(const float* img, int W, int H, int w, bool periodic, float* out) {
    constexpr int kBlock = 16;
    tbb::parallel_for(0, (W + kBlock - 1) / kBlock, [&](int b) {
        thread_local std::vector<float> win, cols, res;
        const int x0 = b * kBlock, nx = std::min(W, x0 + kBlock) - x0;
        cols.resize(static_cast<size_t>(kBlock) * H);
        res.resize(static_cast<size_t>(kBlock) * H);
        for (int y = 0; y < H; ++y)
            for (int c = 0; c < nx; ++c)
                cols[static_cast<size_t>(c) * H + y] = img[static_cast<size_t>(y) * W + x0 + c];
        for (int c = 0; c < nx; ++c)
            runningMedian(cols.data() + static_cast<size_t>(c) * H, H, w, periodic,
                          res.data() + static_cast<size_t>(c) * H, win);
        for (int y = 0; y < H; ++y)
            for (int c = 0; c < nx; ++c)
                out[static_cast<size_t>(y) * W + x0 + c] = res[static_cast<size_t>(c) * H + y];
    });
}

/// Separable running median of a W×H image: along x (rows), then along z (columns); windows
/// shrink at the borders.
std::vector<float> separableMedian(const std::vector<float>& img, int W, int H, int w) {
    std::vector<float> tmp(img.size()), out(img.size());
    rowMedians(img.data(), W, H, w, tmp.data());
    columnMedians(tmp.data(), W, H, w, false, out.data());
    return out;
}

/// The 2×2 mean of a W×H image: ⌈W/2⌉×⌈H/2⌉ (a border cell averages the samples it has).
std::vector<float> pool2(const float* img, int W, int H, int& W2, int& H2) {
    W2 = (W + 1) / 2;
    H2 = (H + 1) / 2;
    std::vector<float> p(static_cast<size_t>(W2) * H2);
    tbb::parallel_for(0, H2, [&](int y) {
        for (int x = 0; x < W2; ++x) {
            double sum = 0.0;
            int cnt = 0;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const int yy = 2 * y + dy, xx = 2 * x + dx;
                    if (yy < H && xx < W) {
                        sum += img[static_cast<size_t>(yy) * W + xx];
                        ++cnt;
                    }
                }
            p[static_cast<size_t>(y) * W2 + x] = static_cast<float>(sum / cnt);
        }
    });
    return p;
}

/// Separable quadratic Savitzky–Golay smoothing of a W×H image over w (odd) samples along x,
/// then along z: the local least-squares quadratic's value at the centre. Borders: mirrored.
/// alongX / alongZ false skips that pass.
std::vector<float> separableQuadratic(const std::vector<float>& img, int W, int H, int w,
                                      bool alongX = true, bool alongZ = true) {
    const int m = w / 2;
    std::vector<double> c(static_cast<size_t>(w));
    const double den = (2.0 * m + 1) * (4.0 * m * m + 4.0 * m - 3.0);
    for (int i = -m; i <= m; ++i)
        c[static_cast<size_t>(i + m)] = (3.0 * (3.0 * m * m + 3.0 * m - 1.0) - 15.0 * i * i) / den;
    std::vector<float> tmp(img.size()), out(img.size());
    auto line = [&c, m](const float* x, int n, size_t stride, float* y) {
        for (int i = 0; i < n; ++i) {
            double acc = 0.0;
            for (int k = -m; k <= m; ++k)
                acc += c[static_cast<size_t>(k + m)] *
                       x[static_cast<size_t>(mirror(i + k, n)) * stride];
            y[static_cast<size_t>(i) * stride] = static_cast<float>(acc);
        }
    };
    if (alongX)
        tbb::parallel_for(0, H, [&](int y) {
            const size_t o = static_cast<size_t>(y) * W;
            line(img.data() + o, W, 1, tmp.data() + o);
        });
    else
        tmp = img;
    if (!alongZ) return tmp;
    tbb::parallel_for(
        0, W, [&](int x) { line(tmp.data() + x, H, static_cast<size_t>(W), out.data() + x); });
    return out;
}

/// The residual of img against its local quadratic fit over w samples along one axis, the fit
/// taken without the samples whose least-squares residual `ls` exceeds `limit` (step 5,
/// edgeRobust). Where no sample of the window is left out, or fewer than 4 remain, the
/// least-squares residual stays.
std::vector<float> robustQuadraticResidual(const std::vector<float>& img,
                                           const std::vector<float>& ls, int W, int H, int w,
                                           bool alongX, double limit) {
    const int m = w / 2;
    std::vector<float> out(img.size());
    auto line = [&](const float* x, const float* r, int n, size_t stride, float* y) {
        for (int i = 0; i < n; ++i) {
            const size_t at = static_cast<size_t>(i) * stride;
            // the normal equations of a + b·t + c·t² over the kept samples
            double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, v0 = 0, v1 = 0, v2 = 0;
            int kept = 0;
            for (int k = -m; k <= m; ++k) {
                const size_t j = static_cast<size_t>(mirror(i + k, n)) * stride;
                if (std::abs(r[j]) > limit) continue;
                const double t = k, t2 = t * t, v = x[j];
                s0 += 1;
                s1 += t;
                s2 += t2;
                s3 += t2 * t;
                s4 += t2 * t2;
                v0 += v;
                v1 += v * t;
                v2 += v * t2;
                ++kept;
            }
            const double det =
                s0 * (s2 * s4 - s3 * s3) - s1 * (s1 * s4 - s3 * s2) + s2 * (s1 * s3 - s2 * s2);
            if (kept == w || kept < 4 || !(std::abs(det) > 1e-9)) {
                y[at] = r[at];
                continue;
            }
            // the fit's value at t = 0 (Cramer's rule)
            const double a =
                (v0 * (s2 * s4 - s3 * s3) - s1 * (v1 * s4 - s3 * v2) + s2 * (v1 * s3 - s2 * v2)) /
                det;
            y[at] = static_cast<float>(x[at] - a);
        }
    };
    if (alongX)
        tbb::parallel_for(0, H, [&](int y) {
            const size_t o = static_cast<size_t>(y) * W;
            line(img.data() + o, ls.data() + o, W, 1, out.data() + o);
        });
    else
        tbb::parallel_for(0, W, [&](int x) {
            line(img.data() + x, ls.data() + x, H, static_cast<size_t>(W), out.data() + x);
        });
    return out;
}

/// Median of |v| over at most ~4M samples taken at a fixed stride (deterministic).
double medianAbs(const std::vector<float>& v) {
    const size_t stride = std::max<size_t>(1, v.size() / (size_t{1} << 22));
    std::vector<float> s;
    s.reserve(v.size() / stride + 1);
    for (size_t k = 0; k < v.size(); k += stride) s.push_back(std::abs(v[k]));
    if (s.empty()) return 0.0;
    auto mid = s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2);
    std::nth_element(s.begin(), mid, s.end());
    return *mid;
}

struct Padded {
    int W = 0, H = 0, leadX = 0, leadY = 0;
    std::vector<float> data;  // H rows of W
};

Padded padMap(std::span<const float> h, int W, int H, int pad, double mean) {
    Padded p;
    p.W = nextSmooth(W + 2 * std::min(pad, W));
    p.H = nextSmooth(H + 2 * std::min(pad, H));
    p.leadX = std::min(pad, W);
    p.leadY = std::min(pad, H);
    // rows first (into the map's rows of the padded image), then every padded column
    std::vector<float> rows(static_cast<size_t>(p.W) * H);
    tbb::parallel_for(0, H, [&](int y) {
        thread_local std::vector<float> in;
        in.resize(W);
        for (int x = 0; x < W; ++x)
            in[x] = static_cast<float>(h[static_cast<size_t>(y) * W + x] - mean);
        padLine(in.data(), W, p.leadX, rows.data() + static_cast<size_t>(y) * p.W, p.W);
    });
    p.data.resize(static_cast<size_t>(p.W) * p.H);
    tbb::parallel_for(0, p.W, [&](int x) {
        thread_local std::vector<float> in, out;
        in.resize(H);
        out.resize(p.H);
        for (int y = 0; y < H; ++y) in[y] = rows[static_cast<size_t>(y) * p.W + x];
        padLine(in.data(), H, p.leadY, out.data(), p.H);
        for (int y = 0; y < p.H; ++y) p.data[static_cast<size_t>(y) * p.W + x] = out[y];
    });
    return p;
}

struct Spectrum {
    int W = 0, H = 0, Wh = 0;   // padded size, half width W/2 + 1
    std::vector<Complex> bins;  // H rows of Wh: row kz, column kx
};

using Fft = Eigen::FFT<float>;

Spectrum forward(const Padded& p) {
    Spectrum s;
    s.W = p.W;
    s.H = p.H;
    s.Wh = p.W / 2 + 1;
    s.bins.resize(static_cast<size_t>(s.Wh) * s.H);
    tbb::enumerable_thread_specific<Fft> ffts([] {
        Fft f;
        f.SetFlag(Fft::HalfSpectrum);
        return f;
    });
    tbb::parallel_for(0, s.H, [&](int y) {
        thread_local std::vector<float> in;
        thread_local std::vector<Complex> out;
        in.assign(p.data.begin() + static_cast<std::ptrdiff_t>(y) * p.W,
                  p.data.begin() + static_cast<std::ptrdiff_t>(y + 1) * p.W);
        ffts.local().fwd(out, in);
        std::copy(out.begin(), out.begin() + s.Wh,
                  s.bins.begin() + static_cast<std::ptrdiff_t>(y) * s.Wh);
    });
    tbb::parallel_for(0, s.Wh, [&](int kx) {
        thread_local std::vector<Complex> in, out;
        in.resize(s.H);
        for (int y = 0; y < s.H; ++y) in[y] = s.bins[static_cast<size_t>(y) * s.Wh + kx];
        ffts.local().fwd(out, in);
        for (int y = 0; y < s.H; ++y) s.bins[static_cast<size_t>(y) * s.Wh + kx] = out[y];
    });
    return s;
}

/// Inverse of forward(), cropped to the map (W×H at the padding's lead).
std::vector<float> inverse(Spectrum& s, const Padded& p, int W, int H) {
    tbb::enumerable_thread_specific<Fft> ffts([] {
        Fft f;
        f.SetFlag(Fft::HalfSpectrum);
        return f;
    });
    tbb::parallel_for(0, s.Wh, [&](int kx) {
        thread_local std::vector<Complex> in, out;
        in.resize(s.H);
        for (int y = 0; y < s.H; ++y) in[y] = s.bins[static_cast<size_t>(y) * s.Wh + kx];
        ffts.local().inv(out, in);
        for (int y = 0; y < s.H; ++y) s.bins[static_cast<size_t>(y) * s.Wh + kx] = out[y];
    });
    std::vector<float> r(static_cast<size_t>(W) * H);
    tbb::parallel_for(0, H, [&](int y) {
        thread_local std::vector<Complex> in;
        thread_local std::vector<float> out;
        const auto row = static_cast<std::ptrdiff_t>(y + p.leadY) * s.Wh;
        in.assign(s.bins.begin() + row, s.bins.begin() + row + s.Wh);
        ffts.local().inv(out, in, s.W);
        std::copy(out.begin() + p.leadX, out.begin() + p.leadX + W,
                  r.begin() + static_cast<std::ptrdiff_t>(y) * W);
    });
    return r;
}

/// Step 3's notch on the spectrum in place; returns the number of bins shrunk. With `wiener`
/// (the same size as s, zero-filled), each notched bin's F·(B²/|F|² − B/|F|) goes there: the
/// level's Wiener estimate minus the shrunk bin (header, step 4).
size_t notchTexture(Spectrum& s, const DefectMapOptions& o, Spectrum* wiener = nullptr) {
    const size_t n = s.bins.size();
    std::vector<float> mag(n);
    for (size_t k = 0; k < n; ++k) mag[k] = std::abs(s.bins[k]);
    // the background on the 2×2-pooled magnitude (windows halved): a quarter of the work
    int W2 = 0, H2 = 0;
    const std::vector<float> pooled = pool2(mag.data(), s.Wh, s.H, W2, H2);
    const int w = std::max(3, (o.spectrumWindow / 2) | 1);
    std::vector<float> medX(pooled.size()), medZ(pooled.size());
    rowMedians(pooled.data(), W2, H2, w, medX.data());
    columnMedians(pooled.data(), W2, H2, w, true, medZ.data());
    // the radial median: along the ray from DC through the cell, w cells centred on it (a
    // straight feature of the map puts its energy on such a ray, through DC)
    // Only where a bin could be notched: a bin with |F| <= notchGrow·max(med_x, med_z) is never
    // texture whatever med_r is (B only grows with it), so med_r is needed in the other cells
    // alone (the same result, a fraction of the work).
    std::vector<float> medR(pooled.size(), 0.0f);
    if (o.radial) {
        std::vector<uint8_t> needed(pooled.size(), 0);
        for (int y = 0; y < s.H; ++y)
            for (int kx = 0; kx < s.Wh; ++kx) {
                const size_t q = static_cast<size_t>(y / 2) * W2 + kx / 2;
                if (mag[static_cast<size_t>(y) * s.Wh + kx] >
                    o.notchGrow * std::max(medX[q], medZ[q]))
                    needed[q] = 1;
            }
        const int half = w / 2;
        tbb::parallel_for(0, H2, [&](int py) {
            thread_local std::vector<float> vals;
            const int y0 = 2 * py;
            const double kz = (y0 <= s.H / 2 ? y0 : y0 - s.H) + 0.5;
            for (int px = 0; px < W2; ++px) {
                if (!needed[static_cast<size_t>(py) * W2 + px]) continue;
                const double kx = 2.0 * px + 0.5, rho = std::hypot(kx, kz);
                const double ux = kx / rho, uz = kz / rho;
                vals.clear();
                for (int t = -half; t <= half; ++t) {
                    double qx = kx + 2.0 * t * ux, qz = kz + 2.0 * t * uz;
                    if (qx < 0) {  // Hermitian symmetry: |F(−k)| = |F(k)|
                        qx = -qx;
                        qz = -qz;
                    }
                    const int bx = static_cast<int>(qx), bz = static_cast<int>(std::floor(qz));
                    if (bx >= s.Wh || bz <= -s.H / 2 || bz > s.H / 2) continue;
                    const int yy = bz >= 0 ? bz : bz + s.H;
                    vals.push_back(pooled[static_cast<size_t>(yy / 2) * W2 + bx / 2]);
                }
                if (vals.empty()) continue;
                auto mid = vals.begin() + static_cast<std::ptrdiff_t>(vals.size() / 2);
                std::nth_element(vals.begin(), mid, vals.end());
                medR[static_cast<size_t>(py) * W2 + px] = *mid;
            }
        });
    }
    const double keep2 = static_cast<double>(o.keepLowBins) * o.keepLowBins;
    std::vector<float> b(n);
    std::vector<uint8_t> seed(n, 0), near(n, 0);
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const size_t k = static_cast<size_t>(y) * s.Wh + kx;
            const size_t q = static_cast<size_t>(y / 2) * W2 + kx / 2;
            b[k] = std::max({medX[q], medZ[q], medR[q]});
            const bool low = static_cast<double>(kx) * kx + static_cast<double>(kz) * kz <= keep2;
            seed[k] = !low && mag[k] > o.notchRatio * b[k];
        }
    }
    // bins within notchSpread of a seed (box; periodic along k_z, clamped along k_x)
    const int r = o.notchSpread;
    tbb::parallel_for(0, s.H, [&](int y) {
        const size_t off = static_cast<size_t>(y) * s.Wh;
        int count = 0;
        for (int kx = 0; kx <= std::min(r, s.Wh - 1); ++kx) count += seed[off + kx];
        for (int kx = 0; kx < s.Wh; ++kx) {
            if (kx > 0) {
                if (kx - 1 - r >= 0) count -= seed[off + kx - 1 - r];
                if (kx + r < s.Wh) count += seed[off + kx + r];
            }
            near[off + kx] = count > 0;
        }
    });
    std::vector<uint8_t> near2(n, 0);
    tbb::parallel_for(0, s.Wh, [&](int kx) {
        for (int y = 0; y < s.H; ++y) {
            bool any = false;
            for (int d = -r; d <= r && !any; ++d)
                any = near[static_cast<size_t>(((y + d) % s.H + s.H) % s.H) * s.Wh + kx] != 0;
            near2[static_cast<size_t>(y) * s.Wh + kx] = any;
        }
    });
    size_t notched = 0;
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const size_t k = static_cast<size_t>(y) * s.Wh + kx;
            if (static_cast<double>(kx) * kx + static_cast<double>(kz) * kz <= keep2) continue;
            if (seed[k] || (near2[k] && mag[k] > o.notchGrow * b[k])) {
                const float ratio = b[k] / mag[k];
                if (wiener) wiener->bins[k] = s.bins[k] * (ratio * ratio - ratio);
                s.bins[k] *= ratio;
                ++notched;
            }
        }
    }
    return notched;
}

/// The orientation sector (0 … sectors−1) of bin (kx, kz): sectors of π/sectors of the
/// wave-vector's orientation θ = atan2(kz, kx) ∈ [0, π), sector 0 centred on the k_x axis.
int sectorOf(int kx, int kz, int sectors) {
    constexpr double kPi = 3.14159265358979323846;
    double theta = std::atan2(static_cast<double>(kz), static_cast<double>(kx));
    if (theta < 0) theta += kPi;
    const double width = kPi / sectors;
    return static_cast<int>(std::floor(theta / width + 0.5)) % sectors;
}

/// The period (samples) of the bin of most gradient power |k|²·|F|² among periods below
/// maxPeriod, 0 when there is none: the ring model's pitch (step 4b). The weight keeps what the
/// macro median left at long wavelengths from outweighing the texture.
double dominantPeriod(const Spectrum& s, double maxPeriod) {
    double best = -1.0, period = 0.0;
    for (int y = 0; y < s.H; ++y) {
        const int kz = y <= s.H / 2 ? y : y - s.H;
        for (int kx = 0; kx < s.Wh; ++kx) {
            const double fx = static_cast<double>(kx) / s.W, fz = static_cast<double>(kz) / s.H;
            const double fr = std::hypot(fx, fz);
            if (!(fr * maxPeriod > 1.0)) continue;
            const double m = fr * fr * std::norm(s.bins[static_cast<size_t>(y) * s.Wh + kx]);
            if (m > best) {
                best = m;
                period = 1.0 / fr;
            }
        }
    }
    return period;
}

/// One notch pass: the periodic texture of d (W×H). With `sectorsOut`, also the texture split
/// by the orientation of its wave-vector into textureSectors parts (their sum is the texture);
/// with `periodOut`, d's dominantPeriod below macroWindow/2 (from the same spectrum); with
/// `levelDeltaOut` (and levelWiener), the level's Wiener residual minus d − texture (step 4).
std::vector<float> notchPass(const std::vector<float>& d, int W, int H, const DefectMapOptions& o,
                             DefectMap* info, std::vector<std::vector<float>>* sectorsOut,
                             double* periodOut, std::vector<float>* levelDeltaOut) {
    const Padded p = padMap(d, W, H, o.pad, 0.0);
    Spectrum s = forward(p);
    if (periodOut) *periodOut = dominantPeriod(s, 0.5 * o.macroWindow);
    // the texture alone: the spectrum minus its shrunk version
    Spectrum kept = s;
    Spectrum wiener;
    const bool wantWiener = levelDeltaOut && o.levelWiener;
    if (wantWiener) {
        wiener.W = s.W;
        wiener.H = s.H;
        wiener.Wh = s.Wh;
        wiener.bins.assign(s.bins.size(), Complex(0.0f, 0.0f));
    }
    const size_t notched = notchTexture(kept, o, wantWiener ? &wiener : nullptr);
    if (wantWiener) {
        *levelDeltaOut = inverse(wiener, p, W, H);
        wiener = {};
    }
    for (size_t k = 0; k < s.bins.size(); ++k) s.bins[k] -= kept.bins[k];
    kept = {};
    if (info) {
        info->notchedBins = notched;
        info->spectrumBins = s.bins.size();
        info->fftWidth = p.W;
        info->fftHeight = p.H;
    }
    if (!sectorsOut || o.textureSectors < 2) return inverse(s, p, W, H);
    // sectors 0 … K−2 from their bins; the last is the texture minus them (one FFT fewer)
    sectorsOut->clear();
    for (int c = 0; c + 1 < o.textureSectors; ++c) {
        Spectrum part = s;
        for (int y = 0; y < s.H; ++y) {
            const int kz = y <= s.H / 2 ? y : y - s.H;
            for (int kx = 0; kx < s.Wh; ++kx)
                if ((kx != 0 || kz != 0 ? sectorOf(kx, kz, o.textureSectors) : 0) != c)
                    part.bins[static_cast<size_t>(y) * s.Wh + kx] = 0;
        }
        sectorsOut->push_back(inverse(part, p, W, H));
    }
    std::vector<float> texture = inverse(s, p, W, H);
    std::vector<float> last = texture;
    for (const std::vector<float>& t : *sectorsOut)
        for (size_t k = 0; k < last.size(); ++k) last[k] -= t[k];
    sectorsOut->push_back(std::move(last));
    return texture;
}

/// Steps 1–3: returns R = h − macro − texture; `macroOut` and `textureOut` (if given) receive
/// the macro shape and the texture T, `periodOut` the dominant period of h − macro,
/// `levelDeltaOut` (with levelWiener) what step 4 adds to the level for the Wiener estimate.
/// With `prior` (a texture found before), `passes` passes (default o.passes) all start from h
/// minus the texture found so far.
std::vector<float> textureResidual(std::span<const float> h, int W, int H,
                                   const DefectMapOptions& o, DefectMap* info,
                                   std::vector<float>* macroOut = nullptr,
                                   std::vector<float>* textureOut = nullptr,
                                   std::vector<std::vector<float>>* sectorsOut = nullptr,
                                   double* periodOut = nullptr,
                                   std::vector<float>* levelDeltaOut = nullptr,
                                   std::vector<float>* prior = nullptr, int passes = 0) {
    const size_t n = h.size();
    if (passes <= 0) passes = o.passes;
    std::vector<float> macro(h.begin(), h.end()), d(n), texture;
    if (prior) texture = std::move(*prior);
    for (int pass = 0; pass < passes; ++pass) {
        // the macro shape: the separable running median of h minus the texture found so far
        if (!texture.empty())
            for (size_t k = 0; k < n; ++k) macro[k] = h[k] - texture[k];
        macro = separableMedian(macro, W, H, o.macroWindow);
        for (size_t k = 0; k < n; ++k) d[k] = h[k] - macro[k];
        const bool last = pass + 1 == passes;
        texture = notchPass(d, W, H, o, info, last ? sectorsOut : nullptr,
                            last ? periodOut : nullptr, last ? levelDeltaOut : nullptr);
    }
    if (textureOut) *textureOut = texture;
    for (size_t k = 0; k < n; ++k) texture[k] = d[k] - texture[k];
    if (macroOut) *macroOut = std::move(macro);
    return texture;
}

// ---- Step 4b: the ring model of a rotational texture -------------------------------------

struct RingFit {
    double cx = 0, cz = 0;  // centre (samples: x = column, z = row)
    double pitch = 0;       // samples per revolution (0: circles)
    int hand = 1;           // the spiral's radius grows by hand·pitch per turn of +angle
    double isotropy = 0, residual = 1;
};

constexpr double kTwoPi = 6.28318530717958647692;
constexpr int kGrooveStep = 3;  // grooves between the arcs of grooveMedian

/// Bilinear value of img at (x, z); false outside [0, W−1]×[0, H−1].
bool bilinear(const float* img, int W, int H, double x, double z, float& v) {
    if (!(x >= 0.0 && z >= 0.0 && x <= W - 1 && z <= H - 1)) return false;
    const int x0 = std::min(static_cast<int>(x), W - 2), z0 = std::min(static_cast<int>(z), H - 2);
    const double fx = x - x0, fz = z - z0;
    const float* a = img + static_cast<size_t>(z0) * W + x0;
    v = static_cast<float>((1 - fz) * ((1 - fx) * a[0] + fx * a[1]) +
                           fz * ((1 - fx) * a[W] + fx * a[W + 1]));
    return true;
}

/// The median of img along the ring (the spiral of constant r − hand·pitch·φ/2π) through
/// sample (x, z): `half` samples of arc length on either side, inward until the spiral reaches
/// the centre. NaN at the centre (r < 1) or with fewer than half + 1 of the arc's samples on
/// the map.
float arcMedian(const float* img, int W, int H, const RingFit& f, double x, double z, int half,
                std::vector<float>& buf) {
    const double dx = x - f.cx, dz = z - f.cz;
    const double r = std::hypot(dx, dz);
    if (r < 1.0) return std::numeric_limits<float>::quiet_NaN();
    const double phi0 = std::atan2(dz, dx);
    const double grow = f.hand * f.pitch / kTwoPi;  // radius per radian along the spiral
    buf.clear();
    float v = 0.0f;
    if (bilinear(img, W, H, x, z, v)) buf.push_back(v);
    for (int dir = -1; dir <= 1; dir += 2) {
        double a = 0.0, rr = r;
        for (int j = 1; j <= half; ++j) {
            a += dir / std::hypot(rr, grow);  // one sample of arc length
            rr = r + grow * a;
            if (rr < 0.5) break;
            if (bilinear(img, W, H, f.cx + rr * std::cos(phi0 + a), f.cz + rr * std::sin(phi0 + a),
                         v))
                buf.push_back(v);
        }
    }
    if (buf.size() < static_cast<size_t>(half) + 1) return std::numeric_limits<float>::quiet_NaN();
    auto mid = buf.begin() + static_cast<std::ptrdiff_t>(buf.size() / 2);
    std::nth_element(buf.begin(), mid, buf.end());
    return *mid;
}

/// The periodic part of the ring model at sample (x, z): the median of the arc medians
/// (arcMedian) through it and through the points kGrooveStep pitches further out and in along
/// its radius (the same phase of the spiral on other grooves; the mean of two where one lies
/// past the centre). A ring-shaped change of level (a step) differs between the grooves and
/// stays out of it, as does a defect along a groove narrower than kGrooveStep pitches.
float grooveMedian(const float* img, int W, int H, const RingFit& f, int x, int z, int half,
                   std::vector<float>& buf) {
    const double dx = x - f.cx, dz = z - f.cz;
    const double r = std::hypot(dx, dz);
    if (r < 1.0) return std::numeric_limits<float>::quiet_NaN();
    float m[3];
    int n = 0;
    for (int k = -kGrooveStep; k <= kGrooveStep; k += kGrooveStep) {
        const double s = (r + k * f.pitch) / r;
        if (r + k * f.pitch < 1.0) continue;
        const float v = arcMedian(img, W, H, f, f.cx + s * dx, f.cz + s * dz, half, buf);
        if (!std::isnan(v)) m[n++] = v;
    }
    if (n == 0) return std::numeric_limits<float>::quiet_NaN();
    if (n == 1) return m[0];
    if (n == 2) return 0.5f * (m[0] + m[1]);
    return std::max(std::min(m[0], m[1]), std::min(std::max(m[0], m[1]), m[2]));
}

/// Mean |d − arc median of d| over the samples `pts` (flat indices); +inf with none valid.
/// Summed in the points' order (the result does not depend on the thread count).
double arcCost(const std::vector<float>& d, int W, int H, const RingFit& f, int half,
               const std::vector<size_t>& pts) {
    std::vector<float> res(pts.size());
    tbb::parallel_for(size_t{0}, pts.size(), [&](size_t i) {
        thread_local std::vector<float> buf;
        const size_t k = pts[i];
        const int x = static_cast<int>(k % static_cast<size_t>(W));
        const int z = static_cast<int>(k / static_cast<size_t>(W));
        const float m = arcMedian(d.data(), W, H, f, x, z, half, buf);
        res[i] = std::isnan(m) ? -1.0f : std::abs(d[k] - m);
    });
    double sum = 0.0;
    size_t cnt = 0;
    for (float v : res)
        if (v >= 0.0f) {
            sum += v;
            ++cnt;
        }
    return cnt ? sum / static_cast<double>(cnt) : std::numeric_limits<double>::infinity();
}

/// Fits the ring model to d = h − macro (W×H): centre, hand and the two decision statistics
/// (header, step 4b); `pitch` is d's dominantPeriod, which the notch pass found.
RingFit fitRings(const std::vector<float>& d, int W, int H, const DefectMapOptions& o,
                 double pitch) {
    RingFit f;
    f.residual = std::numeric_limits<double>::infinity();
    // structure tensor per 16×16 block: the line through the block along its gradient
    constexpr int kB = 16;
    struct Line {
        double px, pz, tx, tz, w;
    };
    std::vector<Line> lines;
    for (int by = 0; by + kB <= H; by += kB)
        for (int bx = 0; bx + kB <= W; bx += kB) {
            double jxx = 0, jxz = 0, jzz = 0;
            for (int y = std::max(by, 1); y < std::min(by + kB, H - 1); ++y)
                for (int x = std::max(bx, 1); x < std::min(bx + kB, W - 1); ++x) {
                    const size_t k = static_cast<size_t>(y) * W + x;
                    const double gx = 0.5 * (d[k + 1] - d[k - 1]);
                    const double gz = 0.5 * (d[k + W] - d[k - W]);
                    jxx += gx * gx;
                    jxz += gx * gz;
                    jzz += gz * gz;
                }
            const double tr = jxx + jzz;
            if (!(tr > 0.0)) continue;
            const double coh = std::hypot(jxx - jzz, 2.0 * jxz) / tr;
            const double phi = 0.5 * std::atan2(2.0 * jxz, jxx - jzz);  // the gradient's
            lines.push_back({bx + 0.5 * (kB - 1), by + 0.5 * (kB - 1), -std::sin(phi),
                             std::cos(phi), coh * coh});
        }
    if (lines.size() < 4) return f;
    auto solve = [&](const std::vector<double>& w, double& cx, double& cz, double& iso) {
        double a = 0, b = 0, c = 0, u = 0, v = 0;  // Σ w t tᵀ = [a b; b c], Σ w (t·p) t
        for (size_t i = 0; i < lines.size(); ++i) {
            const Line& l = lines[i];
            const double tp = l.tx * l.px + l.tz * l.pz;
            a += w[i] * l.tx * l.tx;
            b += w[i] * l.tx * l.tz;
            c += w[i] * l.tz * l.tz;
            u += w[i] * tp * l.tx;
            v += w[i] * tp * l.tz;
        }
        const double det = a * c - b * b, half = 0.5 * (a + c);
        const double disc = std::sqrt(std::max(0.0, 0.25 * (a - c) * (a - c) + b * b));
        iso = half + disc > 0.0 ? (half - disc) / (half + disc) : 0.0;
        if (!(det > 1e-12 * (a + c) * (a + c))) return false;
        cx = (c * u - b * v) / det;
        cz = (a * v - b * u) / det;
        return true;
    };
    std::vector<double> w0(lines.size()), w(lines.size());
    for (size_t i = 0; i < lines.size(); ++i) w0[i] = lines[i].w;
    double iso = 0.0, isoRobust = 0.0;
    if (!solve(w0, f.cx, f.cz, iso)) return f;
    f.isotropy = iso;
    if (iso < o.ringIsotropy) return f;  // parallel paths: no centre to find
    const double delta = 2.0 * kB;       // Cauchy scale of a line's distance from the centre
    for (int it = 0; it < 6; ++it) {
        for (size_t i = 0; i < lines.size(); ++i) {
            const Line& l = lines[i];
            const double dist = (f.cx - l.px) * l.tx + (f.cz - l.pz) * l.tz;
            w[i] = w0[i] / (1.0 + (dist / delta) * (dist / delta));
        }
        double cx = 0, cz = 0;
        if (!solve(w, cx, cz, isoRobust)) break;
        f.cx = cx;
        f.cz = cz;
    }
    f.pitch = pitch;
    const int half = o.ringWindow / 2;
    // the hand: the one that explains more of d where the rings curve most (10–120 samples
    // from the centre; the whole map's grid when too few of those lie on the map)
    auto grid = [&](int step, double rMin, double rMax) {
        std::vector<size_t> pts;
        for (int z = step / 2; z < H; z += step)
            for (int x = step / 2; x < W; x += step) {
                const double r = std::hypot(x - f.cx, z - f.cz);
                if (r >= rMin && r <= rMax) pts.push_back(static_cast<size_t>(z) * W + x);
            }
        return pts;
    };
    std::vector<size_t> pts = grid(6, 10.0, 120.0);
    if (pts.size() < 200)
        pts = grid(std::max(2, static_cast<int>(std::sqrt(W * 1.0 * H / 4000))), 0.0,
                   std::numeric_limits<double>::infinity());
    f.hand = 1;
    {
        RingFit g = f;
        g.hand = -1;
        if (arcCost(d, W, H, g, half, pts) < arcCost(d, W, H, f, half, pts)) f.hand = -1;
    }
    // the decision statistic ρ on a grid over the whole map
    {
        const int step = std::max(2, static_cast<int>(std::sqrt(W * 1.0 * H / 16000)));
        const std::vector<size_t> all = grid(step, 0.0, std::numeric_limits<double>::infinity());
        std::vector<float> res(all.size()), mag(all.size());
        tbb::parallel_for(size_t{0}, all.size(), [&](size_t i) {
            thread_local std::vector<float> buf;
            const size_t k = all[i];
            const float m = arcMedian(d.data(), W, H, f, static_cast<double>(k % W),
                                      static_cast<double>(k / W), half, buf);
            res[i] = std::isnan(m) ? -1.0f : std::abs(d[k] - m);
            mag[i] = std::isnan(m) ? -1.0f : std::abs(d[k]);
        });
        auto med = [](std::vector<float>& v) {
            v.erase(std::remove(v.begin(), v.end(), -1.0f), v.end());
            if (v.empty()) return 0.0;
            auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
            std::nth_element(v.begin(), mid, v.end());
            return static_cast<double>(*mid);
        };
        const double mr = med(res), mm = med(mag);
        if (mm > 0.0) f.residual = mr / mm;
    }
    return f;
}

/// Step 4b's fit and decision on d = h − macro (fitRings); fills info's ring fields.
RingFit ringFit(std::span<const float> h, const std::vector<float>& macro, int W, int H,
                const DefectMapOptions& o, double pitch, DefectMap& info) {
    std::vector<float> d(h.size());
    for (size_t k = 0; k < d.size(); ++k) d[k] = h[k] - macro[k];
    const RingFit f = fitRings(d, W, H, o, pitch);
    info.ringCentreX = f.cx;
    info.ringCentreZ = f.cz;
    info.ringPitch = f.pitch;
    info.ringHand = f.hand;
    info.ringIsotropy = f.isotropy;
    info.ringResidual = f.residual;
    info.ringUsed = f.pitch > 0.0 && f.isotropy >= o.ringIsotropy && f.residual <= o.ringResidual;
    return f;
}

/// Step 4b where the rings are used (info.ringUsed): A (the level) becomes A_ring = d −
/// grooveMedian(d), d = h − macro, at samples with |A| >= growSigma·σ_A and |A_ring| <=
/// ringRatio·|A|, no smaller in magnitude than the median of |A| (so σ_A stays as it was).
void ringLevel(std::span<const float> h, const std::vector<float>& macro, std::vector<float>& A,
               int W, int H, const DefectMapOptions& o, double floorSigma, const RingFit& f,
               DefectMap& info) {
    if (!info.ringUsed) return;
    std::vector<float> d(h.size());
    for (size_t k = 0; k < d.size(); ++k) d[k] = h[k] - macro[k];
    const float medA = static_cast<float>(medianAbs(A));
    const float limit = static_cast<float>(o.growSigma * std::max(1.4826 * medA, floorSigma));
    const float ratio = static_cast<float>(o.ringRatio);
    const int half = o.ringWindow / 2;
    tbb::enumerable_thread_specific<size_t> lowered(size_t{0});
    tbb::parallel_for(0, H, [&](int z) {
        thread_local std::vector<float> buf;
        for (int x = 0; x < W; ++x) {
            const size_t k = static_cast<size_t>(z) * W + x;
            if (!(std::abs(A[k]) >= limit)) continue;
            const float m = grooveMedian(d.data(), W, H, f, x, z, half, buf);
            if (std::isnan(m)) continue;
            const float ar = d[k] - m;
            if (std::abs(ar) <= ratio * std::abs(A[k])) {
                A[k] = std::copysign(std::max(std::abs(ar), medA), ar);
                ++lowered.local();
            }
        }
    });
    for (size_t c : lowered) info.ringLowered += c;
}

/// The connected regions of a W×H map: each starts at a sample `seed` accepts (in row-major
/// order) and takes every sample `grow` accepts within `reach` samples (a (2·reach+1)² box) of
/// one it holds; `region` gets each one's samples in the order they were reached. A sample
/// belongs to one region at most.
template <class Seed, class Grow, class Region>
void forEachRegion(int W, int H, int reach, Seed seed, Grow grow, Region region) {
    const size_t n = static_cast<size_t>(W) * H;
    std::vector<uint8_t> seen(n, 0);
    std::vector<size_t> stack, samples;
    for (size_t k0 = 0; k0 < n; ++k0) {
        if (seen[k0] || !seed(k0)) continue;
        samples.clear();
        stack.assign(1, k0);
        seen[k0] = 1;
        while (!stack.empty()) {
            const size_t k = stack.back();
            stack.pop_back();
            samples.push_back(k);
            const int x = static_cast<int>(k % static_cast<size_t>(W));
            const int y = static_cast<int>(k / static_cast<size_t>(W));
            for (int dy = -reach; dy <= reach; ++dy)
                for (int dx = -reach; dx <= reach; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    const size_t q = static_cast<size_t>(yy) * W + xx;
                    if (seen[q] || !grow(q)) continue;
                    seen[q] = 1;
                    stack.push_back(q);
                }
        }
        region(samples);
    }
}

/// Step 6: hysteresis on the score, regions below minRegion dropped. Sets map to 255.
size_t hysteresis(const std::vector<float>& score, int W, int H, double seed, double grow,
                  int minRegion, std::vector<uint8_t>& map) {
    size_t marked = 0;
    forEachRegion(
        W, H, 1, [&](size_t k) { return score[k] >= seed; },
        [&](size_t k) { return score[k] >= grow; },
        [&](const std::vector<size_t>& region) {
            if (region.size() < static_cast<size_t>(minRegion)) return;
            for (size_t k : region) map[k] = 255;
            marked += region.size();
        });
    return marked;
}

// ---- Step 4a: the tool-change step model ------------------------------------------------------

/// A direction of the step detector's lines: (dx, dz) in samples.
struct StepDir {
    int dx, dz;
};
constexpr StepDir kStepDirs[4] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};

/// One point of a detected step's centre line.
struct StepPoint {
    float x, z;    // the centre (samples, sub-sample along the detector's direction)
    float nx, nz;  // unit normal, pointing to the side that is higher by `jump`
    float jump;    // > 0, height units
};

struct StepModel {
    std::vector<StepPoint> points;
    std::vector<uint8_t> ramp;  // the samples within stepRampHalf of a centre line
    std::vector<uint8_t> band;  // the samples within stepBand of a centre line
};

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

/// Step 4a's lines on G = h − T (DefectMap.h): their points, ramps and bands.
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

/// The mean of A over a digital segment through every sample, of direction (c, s): along the
/// major axis (x when |c| >= |s|) round(m·|major component|) samples to each side, the minor
/// coordinate following round(major·slope) (a sheared line: one running sum per line, O(1)
/// per sample). Samples past the map's edges are clamped to it.
void segmentMeans(const std::vector<float>& A, int W, int H, double c, double s, int m,
                  std::vector<float>& L) {
    const bool xMajor = std::abs(c) >= std::abs(s);
    const int Nm = xMajor ? W : H, Nn = xMajor ? H : W;  // major / minor lengths
    const size_t sm = xMajor ? 1 : static_cast<size_t>(W), sn = xMajor ? static_cast<size_t>(W) : 1;
    const double slope = xMajor ? s / c : c / s;
    const int half = static_cast<int>(std::lround(m * std::abs(xMajor ? c : s)));
    std::vector<int> r(static_cast<size_t>(Nm));
    for (int i = 0; i < Nm; ++i)
        r[static_cast<size_t>(i)] = static_cast<int>(std::lround(i * slope));
    const int rMin = std::min(r.front(), r.back()), rMax = std::max(r.front(), r.back());
    tbb::parallel_for(-rMax, Nn - rMin, [&](int line) {
        thread_local std::vector<double> prefix;
        prefix.assign(static_cast<size_t>(Nm + 2 * half + 1), 0.0);
        // values along the sheared line, the ends replicated `half` samples beyond the map
        for (int e = -half; e < Nm + half; ++e) {
            const int i = std::clamp(e, 0, Nm - 1);
            const int j = std::clamp(line + r[static_cast<size_t>(i)], 0, Nn - 1);
            prefix[static_cast<size_t>(e + half + 1)] =
                prefix[static_cast<size_t>(e + half)] + A[i * sm + static_cast<size_t>(j) * sn];
        }
        const double inv = 1.0 / (2 * half + 1);
        for (int i = 0; i < Nm; ++i) {
            const int j = line + r[static_cast<size_t>(i)];
            if (j < 0 || j >= Nn) continue;
            L[i * sm + static_cast<size_t>(j) * sn] = static_cast<float>(
                (prefix[static_cast<size_t>(i + 2 * half + 1)] - prefix[static_cast<size_t>(i)]) *
                inv);
        }
    });
}

/// Step 7a, the line-valley score: a scratch is a long, straight, narrow groove, lower than the
/// surface on both of its sides. For each of `lineOrientations` directions θ = πk/K, L_θ = the
/// mean of A over a segment about `lineLength` samples long along θ (segmentMeans), and
/// V_θ = min(L_θ(p + o·n) − L_θ(p), L_θ(p − o·n) − L_θ(p)) / σ_θ with n the normal,
/// o = `lineOffset` (rounded to samples) and σ_θ = 1.4826 × the median of both differences'
/// magnitudes. V = max over θ of V_θ, 0 within `border`. Returns 1 on the regions of
/// V ≥ lineGrowSigma (8-connected) that reach V ≥ lineSeedSigma, 0 elsewhere.
/// Step 7b: the seed and grow thresholds from the texture's own tail. q = the seedTailQuantile
/// quantile of `score` over the samples outside the border (score is 0 in the border); the seed
/// is max(seed, seedTail·q), the grow threshold max(grow, growTail·q) with growTail > 0, else
/// grow scaled by the seed's factor; never above the seed.
struct Thresholds {
    double seed, grow;
};
Thresholds tailThresholds(const std::vector<float>& score, int W, int H, const DefectMapOptions& o,
                          double seed, double grow) {
    if (!(o.seedTail > 0.0)) return {seed, grow};
    std::vector<float> v;
    v.reserve(score.size());
    for (int y = o.border; y < H - o.border; ++y)
        for (int x = o.border; x < W - o.border; ++x)
            v.push_back(score[static_cast<size_t>(y) * W + x]);
    if (v.empty()) return {seed, grow};
    const size_t k = std::min(
        v.size() - 1, static_cast<size_t>(o.seedTailQuantile * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    const double q = static_cast<double>(v[k]);
    const double s = std::max(seed, o.seedTail * q);
    const double g = o.growTail > 0.0 ? std::max(grow, o.growTail * q) : grow * s / seed;
    return {s, std::min(g, s)};
}

std::vector<uint8_t> lineValleyRegions(const std::vector<float>& A, int W, int H,
                                       const DefectMapOptions& o, double* seedUsed) {
    constexpr double kPi = 3.14159265358979323846;
    const size_t n = A.size();
    const int m = o.lineLength / 2;
    std::vector<float> L(n), V(n, -std::numeric_limits<float>::infinity());
    for (int k = 0; k < o.lineOrientations; ++k) {
        const double th = kPi * k / o.lineOrientations, c = std::cos(th), s = std::sin(th);
        segmentMeans(A, W, H, c, s, m, L);
        const int nx = static_cast<int>(std::lround(-s * o.lineOffset));
        const int ny = static_cast<int>(std::lround(c * o.lineOffset));
        auto side = [&](int x, int y, int sign) {
            const int xx = std::clamp(x + sign * nx, 0, W - 1);
            const int yy = std::clamp(y + sign * ny, 0, H - 1);
            return L[static_cast<size_t>(yy) * W + xx];
        };
        // σ_θ from both differences at a fixed stride (deterministic)
        std::vector<float> diffs;
        const size_t stride = std::max<size_t>(1, n / (size_t{1} << 17)) | 1;
        diffs.reserve(2 * (n / stride + 1));
        for (size_t q = 0; q < n; q += stride) {
            const int x = static_cast<int>(q % static_cast<size_t>(W));
            const int y = static_cast<int>(q / static_cast<size_t>(W));
            diffs.push_back(side(x, y, 1) - L[q]);
            diffs.push_back(side(x, y, -1) - L[q]);
        }
        const double sigma = 1.4826 * medianAbs(diffs);
        if (!(sigma > 0.0)) continue;
        tbb::parallel_for(0, H, [&](int y) {
            for (int x = 0; x < W; ++x) {
                const size_t q = static_cast<size_t>(y) * W + x;
                const float v = static_cast<float>(
                    std::min(side(x, y, 1) - L[q], side(x, y, -1) - L[q]) / sigma);
                V[q] = std::max(V[q], v);
            }
        });
    }
    L = {};
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const size_t q = static_cast<size_t>(y) * W + x;
            const bool inside = y >= o.border && y < H - o.border && x >= o.border &&
                                x < W - o.border && std::isfinite(V[q]);
            V[q] = inside ? std::max(V[q], 0.0f) : 0.0f;
        }
    });
    std::vector<uint8_t> regions(n, 0);
    const Thresholds t = tailThresholds(V, W, H, o, o.lineSeedSigma, o.lineGrowSigma);
    if (seedUsed) *seedUsed = t.seed;
    hysteresis(V, W, H, t.seed, t.grow, 1, regions);
    for (uint8_t& v : regions) v = v != 0;
    return regions;
}

}  // namespace

std::vector<float> separableRunningMedian(const std::vector<float>& img, int W, int H, int w) {
    return separableMedian(img, W, H, w);
}

std::vector<float> removeTexture(std::span<const float> heights, int width, int height,
                                 const DefectMapOptions& options) {
    checkOptions(options);
    checkInput(heights, width, height);
    std::vector<float> delta;
    std::vector<float> r =
        textureResidual(heights, width, height, options, nullptr, nullptr, nullptr, nullptr,
                        nullptr, options.levelWiener ? &delta : nullptr);
    for (size_t k = 0; k < delta.size(); ++k) r[k] += delta[k];
    return r;
}

namespace {

// The selfsim method's map and statistics into r (the selfsim method, and auto on a measured
// texture).
void selfSimInto(DefectMap& r, std::span<const float> heights, int width, int height,
                 const SelfSimMapOptions& o) {
    SelfSimMap m = detectSelfSimDefects(heights, width, height, o);
    r.method = DefectMethod::SelfSim;
    r.map = std::move(m.map);
    r.sigmaLevel = m.sigma;
    r.selfsimOffsets = m.offsetX.size();
    r.selfsimDetections = m.detections;
    r.selfsimRegions = m.regions;
    r.selfsimDropped = m.droppedBorder;
    r.selfsimThreshold = m.threshold;
    r.markedScore = r.markedCount();
}

}  // namespace

DefectMap detectDefects(std::span<const float> heights, int width, int height,
                        const DefectMapOptions& o) {
    const Stopwatch clock;
    DefectMap r;
    r.method = o.method;
    r.width = width;
    r.height = height;
    switch (o.method) {
        case DefectMethod::Paper: {
            checkInput(heights, width, height);
            ScratchMap m = computeScratchMap(heights, width, height, o.paper);
            r.map = std::move(m.map);
            r.seconds = clock.seconds();
            return r;
        }
        case DefectMethod::Lay: {
            checkInput(heights, width, height);
            LayMap m = detectLayDefects(heights, width, height, o.lay);
            r.map = std::move(m.map);
            r.sigmaLevel = m.sigma;
            r.layX = m.layX;
            r.layZ = m.layZ;
            r.layCoherence = m.coherence;
            r.layTextureRms = m.textureRms;
            r.layRegions = m.regions;
            r.layDroppedShallow = m.droppedShallow;
            r.layDroppedBorder = m.droppedBorder;
            r.markedScore = r.markedCount();
            r.seconds = clock.seconds();
            return r;
        }
        case DefectMethod::SelfSim:
            checkInput(heights, width, height);
            selfSimInto(r, heights, width, height, o.selfsim);
            r.seconds = clock.seconds();
            return r;
        case DefectMethod::Auto:
            if (!o.measured) break;
            // a measured texture: the map is the selfsim method's (header, "auto")
            checkInput(heights, width, height);
            selfSimInto(r, heights, width, height, o.selfsim);
            r.measuredTexture = true;
            r.seconds = clock.seconds();
            return r;
    }
    checkOptions(o);
    checkInput(heights, width, height);
    const int W = width, H = height;
    const size_t n = heights.size();
    r.map.assign(n, 0);

    // scale floor: 1e-3 of the heights' own robust spread (a noise-free texture leaves only
    // rounding in A and N; this keeps rounding from being an anomaly)
    double hmean = 0.0;
    for (float v : heights) hmean += v;
    hmean /= static_cast<double>(n);
    std::vector<float> centred(n);
    for (size_t k = 0; k < n; ++k) centred[k] = static_cast<float>(heights[k] - hmean);
    const double floorSigma = 1e-3 * 1.4826 * medianAbs(centred);
    centred = {};
    std::vector<float> macro;

    std::vector<float> texture;
    std::vector<std::vector<float>> sectors;
    const bool wantTexture = o.energyWindow > 0 && o.textureEnergy;
    double period = 0.0;            // of h − macro, the ring model's pitch
    std::vector<float> levelDelta;  // step 4: the Wiener estimate's level minus A (levelWiener)
    std::vector<float> R = textureResidual(
        heights, W, H, o, &r, &macro, wantTexture && o.textureSectors == 1 ? &texture : nullptr,
        wantTexture && o.textureSectors > 1 ? &sectors : nullptr,
        o.ringWindow > 0 ? &period : nullptr, o.levelWiener ? &levelDelta : nullptr);
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    RingFit rings;
    if (o.ringWindow > 0) {
        rings = ringFit(heights, macro, W, H, o, period, r);
        if (r.ringUsed && o.ringRepass) {
            // steps 1–3 once more, the macro shape the running median of h − T: the texture
            // left the first macro shape biased where its window straddles a corner of the
            // macro shape (the pocket wall's foot and top)
            std::vector<float> T(n);
            for (size_t k = 0; k < n; ++k) T[k] = heights[k] - macro[k] - R[k];
            texture.clear();
            sectors.clear();
            levelDelta.clear();
            R = textureResidual(heights, W, H, o, &r, &macro,
                                wantTexture && o.textureSectors == 1 ? &texture : nullptr,
                                wantTexture && o.textureSectors > 1 ? &sectors : nullptr, nullptr,
                                o.levelWiener ? &levelDelta : nullptr, &T, 1);
        }
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    StepModel steps;
    if (o.stepModel) {  // step 4a: the steps of h − T
        std::vector<float> G(n);
        for (size_t k = 0; k < n; ++k) G[k] = macro[k] + R[k];
        steps = detectSteps(G, W, H, o, floorSigma);
        r.stepPoints = steps.points.size();
    }
    std::vector<float> A = separableMedian(R, W, H, o.levelWindow);
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    for (size_t k = 0; k < n; ++k) A[k] = R[k] - A[k];
    if (o.ringWindow > 0) ringLevel(heights, macro, A, W, H, o, floorSigma, rings, r);  // 4b
    for (size_t k = 0; k < n; ++k) R[k] += macro[k];
    // the edge residual: both axes at once, or (edgeAxes) one per axis, each with its own σ
    std::vector<float> N = separableQuadratic(R, W, H, o.edgeWindow, true, !o.edgeAxes);
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    for (size_t k = 0; k < n; ++k) N[k] = R[k] - N[k];
    std::vector<float> Nz;
    if (o.edgeAxes) {
        Nz = separableQuadratic(R, W, H, o.edgeWindow, false, true);
        for (size_t k = 0; k < n; ++k) Nz[k] = R[k] - Nz[k];
    }
    if (o.edgeRobust && o.edgeAxes) {
        // step 5: the fits again without the samples that alone would seed the map
        const double sx = std::max(1.4826 * medianAbs(N), floorSigma);
        const double sz = std::max(1.4826 * medianAbs(Nz), floorSigma);
        N = robustQuadraticResidual(R, N, W, H, o.edgeWindow, true, o.seedSigma * sx);
        Nz = robustQuadraticResidual(R, Nz, W, H, o.edgeWindow, false, o.seedSigma * sz);
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    R = {};
    macro = {};
    r.sigmaLevel = 1.4826 * medianAbs(A);
    // the level's Wiener estimate in the notched bins, for the score and the line valleys; σ_A
    // above and step 8 below keep the background-magnitude residual
    for (size_t k = 0; k < levelDelta.size(); ++k) A[k] += levelDelta[k];
    r.sigmaEdge = 1.4826 * medianAbs(N);
    const double sa = std::max(r.sigmaLevel, floorSigma), sn = std::max(r.sigmaEdge, floorSigma);
    const double snz = o.edgeAxes ? std::max(1.4826 * medianAbs(Nz), floorSigma) : 1.0;
    if (sa > 0.0 && sn > 0.0 && snz > 0.0) {
        std::vector<float> S(n);
        tbb::parallel_for(size_t{0}, n, [&](size_t k) {
            double e = std::abs(N[k]) / sn;
            if (o.edgeAxes) e = std::max(e, std::abs(Nz[k]) / snz);
            S[k] = static_cast<float>(std::max(std::abs(A[k]) / sa, o.edgeWeight * e));
        });
        if (o.border > 0)
            tbb::parallel_for(0, H, [&](int y) {
                for (int x = 0; x < W; ++x)
                    if (y < o.border || y >= H - o.border || x < o.border || x >= W - o.border)
                        S[static_cast<size_t>(y) * W + x] = 0.0f;
            });
        // step 7b: the texture's own tail raises the thresholds
        const Thresholds t = tailThresholds(S, W, H, o, o.seedSigma, o.growSigma);
        const double seed = t.seed;
        r.seedUsed = seed;
        r.growUsed = t.grow;
        if (o.lineLength > 0) {
            // step 7a: the line-valley regions seed the hysteresis and are grown through
            const std::vector<uint8_t> lines = lineValleyRegions(A, W, H, o, &r.lineSeedUsed);
            for (size_t k = 0; k < n; ++k)
                if (lines[k]) S[k] = std::max(S[k], static_cast<float>(seed));
        }
        r.markedScore = hysteresis(S, W, H, seed, t.grow, o.minRegion, r.map);
    }
    for (size_t k = 0; k < steps.ramp.size(); ++k) {  // step 4a: a step's band is its ramp
        if (!steps.band[k]) continue;
        if (steps.ramp[k] && !r.map[k]) ++r.markedStep;
        if (!steps.ramp[k] && r.map[k]) --r.markedScore;
        r.map[k] = steps.ramp[k];
    }
    throwIfInterrupted();  // Ctrl-C between the steps (core/Interrupt.h)
    N = {};
    Nz = {};
    if (o.energyWindow > 0) {
        // step 8 on |A| and, with textureEnergy, on |T|
        // the distance of a sample to the map's nearest edge (its layer of the border)
        auto layer = [&](int x, int y) {
            return std::min(std::min(x, W - 1 - x), std::min(y, H - 1 - y));
        };
        // lineExcess: the threshold in the border is raised by the excess of the median of E
        // along the sample's pooled row (top and bottom border) or column (left and right) over
        // median(E)
        auto markTextureChange = [&](std::vector<float>& v, double ratio, bool lineExcess) {
            for (float& x : v) x = std::abs(x);
            // on the 2×2-pooled values (window halved): a quarter of the work
            int W2 = 0, H2 = 0;
            const std::vector<float> pooled = pool2(v.data(), W, H, W2, H2);
            v = {};
            const std::vector<float> E2 =
                separableMedian(pooled, W2, H2, std::max(3, (o.energyWindow / 2) | 1));
            const double medE = std::max(medianAbs(E2), floorSigma);
            if (!(medE > 0.0)) return;
            double base = ratio * medE;  // the threshold on E
            auto energy = [&](int x, int y) { return E2[static_cast<size_t>(y / 2) * W2 + x / 2]; };
            const bool grow = o.energyGrowBorder && o.border > 0;
            std::vector<uint8_t> own(n, 0);  // this test's marks
            for (size_t k = 0; k < n; ++k) {
                const int x = static_cast<int>(k % static_cast<size_t>(W));
                const int y = static_cast<int>(k / static_cast<size_t>(W));
                if (layer(x, y) >= o.border && energy(x, y) >= base) own[k] = 1;
            }
            if (grow) {
                std::vector<double> rowExcess(H2, 0.0), colExcess(W2, 0.0);
                if (lineExcess) {
                    std::vector<float> line;
                    for (int py = 0; py < H2; ++py)
                        if (2 * py < o.border || 2 * py + 1 >= H - o.border) {
                            line.assign(E2.begin() + static_cast<size_t>(py) * W2,
                                        E2.begin() + static_cast<size_t>(py + 1) * W2);
                            rowExcess[py] = std::max(0.0, medianAbs(line) - medE);
                        }
                    line.resize(H2);
                    for (int px = 0; px < W2; ++px)
                        if (2 * px < o.border || 2 * px + 1 >= W - o.border) {
                            for (int py = 0; py < H2; ++py)
                                line[py] = E2[static_cast<size_t>(py) * W2 + px];
                            colExcess[px] = std::max(0.0, medianAbs(line) - medE);
                        }
                }
                // grow outward, layer by layer: a sample at distance j from the edge joins when
                // its E passes and an 8-neighbour at distance j + 1 is marked by this test
                auto visit = [&](int x, int y, int j) {
                    const size_t k = static_cast<size_t>(y) * W + x;
                    double excess = 0.0;
                    if (y < o.border || y >= H - o.border) excess = rowExcess[y / 2];
                    if (x < o.border || x >= W - o.border)
                        excess = std::max(excess, colExcess[x / 2]);
                    const double threshold = base + excess;
                    if (own[k] || energy(x, y) < threshold) return;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int xx = x + dx, yy = y + dy;
                            if (xx < 0 || yy < 0 || xx >= W || yy >= H || layer(xx, yy) != j + 1 ||
                                !own[static_cast<size_t>(yy) * W + xx])
                                continue;
                            own[k] = 1;
                            return;
                        }
                };
                for (int j = o.border - 1; j >= 0; --j) {
                    if (2 * j + 1 >= W || 2 * j + 1 >= H) continue;  // no sample at distance j
                    for (int x = j; x < W - j; ++x) {
                        visit(x, j, j);
                        visit(x, H - 1 - j, j);
                    }
                    for (int y = j + 1; y < H - 1 - j; ++y) {
                        visit(j, y, j);
                        visit(W - 1 - j, y, j);
                    }
                }
            }
            for (size_t k = 0; k < n; ++k)
                if (own[k]) {
                    if (!r.map[k]) ++r.markedEnergy;
                    r.map[k] = 255;
                }
        };
        for (size_t k = 0; k < levelDelta.size(); ++k) A[k] -= levelDelta[k];
        levelDelta = {};
        markTextureChange(A, o.energyRatio, true);
        if (o.textureEnergy) {
            if (sectors.empty()) markTextureChange(texture, o.textureEnergyRatio, false);
            for (std::vector<float>& t : sectors) markTextureChange(t, o.textureEnergyRatio, false);
        }
    }
    r.seconds = clock.seconds();
    return r;
}

DefectScore scoreDefectMap(std::span<const uint8_t> map, std::span<const uint8_t> labels,
                           std::span<const RegionLabel> legend,
                           std::span<const uint8_t> negatives) {
    if (map.size() != labels.size())
        throw inputError("defect score",
                         "the map has " + std::to_string(map.size()) + " samples, the truth " +
                             std::to_string(labels.size()),
                         "Score a map against the truth of the same height map");
    bool negative[256] = {};
    for (uint8_t v : negatives) negative[v] = true;
    size_t count[256] = {}, hit[256] = {};
    size_t marked = 0;
    for (size_t k = 0; k < map.size(); ++k) {
        ++count[labels[k]];
        if (map[k]) {
            ++hit[labels[k]];
            ++marked;
        }
    }
    auto ratio = [](size_t a, size_t b) {
        return b ? static_cast<double>(a) / static_cast<double>(b)
                 : std::numeric_limits<double>::quiet_NaN();
    };
    auto f1 = [](double p, double r) {
        return std::isfinite(p) && std::isfinite(r) && p + r > 0 ? 2 * p * r / (p + r) : 0.0;
    };
    size_t negMarked = hit[0];
    for (int v = 1; v < 256; ++v)
        if (negative[v]) negMarked += hit[v];
    DefectScore s;
    s.marked = marked;
    s.samples = map.size();
    DefectScoreRow& all = s.overall;
    all.name = "all";
    for (int v = 1; v < 256; ++v)
        if (!negative[v]) {
            all.truth += count[v];
            all.hits += hit[v];
        }
    all.marked = marked;
    all.precision = ratio(all.hits, all.marked);
    all.recall = ratio(all.hits, all.truth);
    all.f1 = f1(all.precision, all.recall);
    for (const RegionLabel& l : legend) {
        DefectScoreRow row;
        row.value = l.value;
        row.name = l.name;
        row.truth = count[l.value];
        row.hits = hit[l.value];
        row.marked = row.hits + (negative[l.value] ? negMarked - hit[l.value] : negMarked);
        row.precision = ratio(row.hits, row.marked);
        row.recall = ratio(row.hits, row.truth);
        row.f1 = f1(row.precision, row.recall);
        s.kinds.push_back(row);
    }
    return s;
}

}  // namespace sl
