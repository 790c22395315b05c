#include "objective/DefectMap.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <unsupported/Eigen/FFT>

#include "core/Error.h"
#include "core/Registry.h"
#include "core/Stopwatch.h"

namespace sl {

namespace {

constexpr DefectMethodRow kMethods[] = {
    {DefectMethod::Auto, "auto",
     "remove the periodic tool-path texture (spectral notch) and a robust local level; mark what "
     "stands out (levels, edges, texture-change regions)"},
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

/// Step 2's notch on the spectrum in place; returns the number of bins shrunk.
size_t notchTexture(Spectrum& s, const DefectMapOptions& o) {
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
                s.bins[k] *= b[k] / mag[k];
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

/// One notch pass: the periodic texture of d (W×H). With `sectorsOut`, also the texture split
/// by the orientation of its wave-vector into textureSectors parts (their sum is the texture).
std::vector<float> notchPass(const std::vector<float>& d, int W, int H, const DefectMapOptions& o,
                             DefectMap* info, std::vector<std::vector<float>>* sectorsOut) {
    const Padded p = padMap(d, W, H, o.pad, 0.0);
    Spectrum s = forward(p);
    // the texture alone: the spectrum minus its shrunk version
    Spectrum kept = s;
    const size_t notched = notchTexture(kept, o);
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
/// the macro shape and the texture T.
std::vector<float> textureResidual(std::span<const float> h, int W, int H,
                                   const DefectMapOptions& o, DefectMap* info,
                                   std::vector<float>* macroOut = nullptr,
                                   std::vector<float>* textureOut = nullptr,
                                   std::vector<std::vector<float>>* sectorsOut = nullptr) {
    const size_t n = h.size();
    std::vector<float> macro(h.begin(), h.end()), d(n), texture;
    for (int pass = 0; pass < o.passes; ++pass) {
        // the macro shape: the separable running median of h minus the texture found so far
        if (pass > 0)
            for (size_t k = 0; k < n; ++k) macro[k] = h[k] - texture[k];
        macro = separableMedian(macro, W, H, o.macroWindow);
        for (size_t k = 0; k < n; ++k) d[k] = h[k] - macro[k];
        texture = notchPass(d, W, H, o, info, pass + 1 == o.passes ? sectorsOut : nullptr);
    }
    if (textureOut) *textureOut = texture;
    for (size_t k = 0; k < n; ++k) texture[k] = d[k] - texture[k];
    if (macroOut) *macroOut = std::move(macro);
    return texture;
}

/// Step 6: hysteresis on the score, regions below minRegion dropped. Sets map to 255.
size_t hysteresis(const std::vector<float>& score, int W, int H, double seed, double grow,
                  int minRegion, std::vector<uint8_t>& map) {
    std::vector<uint8_t> seen(score.size(), 0);
    std::vector<size_t> stack, region;
    size_t marked = 0;
    for (size_t k0 = 0; k0 < score.size(); ++k0) {
        if (seen[k0] || !(score[k0] >= seed)) continue;
        region.clear();
        stack.assign(1, k0);
        seen[k0] = 1;
        while (!stack.empty()) {
            const size_t k = stack.back();
            stack.pop_back();
            region.push_back(k);
            const int x = static_cast<int>(k % static_cast<size_t>(W));
            const int y = static_cast<int>(k / static_cast<size_t>(W));
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= W || yy >= H) continue;
                    const size_t q = static_cast<size_t>(yy) * W + xx;
                    if (seen[q] || !(score[q] >= grow)) continue;
                    seen[q] = 1;
                    stack.push_back(q);
                }
        }
        if (region.size() < static_cast<size_t>(minRegion)) continue;
        for (size_t k : region) map[k] = 255;
        marked += region.size();
    }
    return marked;
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
std::vector<uint8_t> lineValleyRegions(const std::vector<float>& A, int W, int H,
                                       const DefectMapOptions& o) {
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
    hysteresis(V, W, H, o.lineSeedSigma, o.lineGrowSigma, 1, regions);
    for (uint8_t& v : regions) v = v != 0;
    return regions;
}

}  // namespace

std::vector<float> removeTexture(std::span<const float> heights, int width, int height,
                                 const DefectMapOptions& options) {
    checkOptions(options);
    checkInput(heights, width, height);
    return textureResidual(heights, width, height, options, nullptr);
}

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
        case DefectMethod::Auto:
            break;
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
    std::vector<float> R = textureResidual(
        heights, W, H, o, &r, &macro, wantTexture && o.textureSectors == 1 ? &texture : nullptr,
        wantTexture && o.textureSectors > 1 ? &sectors : nullptr);
    std::vector<float> A = separableMedian(R, W, H, o.levelWindow);
    for (size_t k = 0; k < n; ++k) A[k] = R[k] - A[k];
    for (size_t k = 0; k < n; ++k) R[k] += macro[k];
    // the edge residual: both axes at once, or (edgeAxes) one per axis, each with its own σ
    std::vector<float> N = separableQuadratic(R, W, H, o.edgeWindow, true, !o.edgeAxes);
    for (size_t k = 0; k < n; ++k) N[k] = R[k] - N[k];
    std::vector<float> Nz;
    if (o.edgeAxes) {
        Nz = separableQuadratic(R, W, H, o.edgeWindow, false, true);
        for (size_t k = 0; k < n; ++k) Nz[k] = R[k] - Nz[k];
    }
    R = {};
    macro = {};
    r.sigmaLevel = 1.4826 * medianAbs(A);
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
        if (o.lineLength > 0) {
            // step 7a: the line-valley regions seed the hysteresis and are grown through
            const std::vector<uint8_t> lines = lineValleyRegions(A, W, H, o);
            for (size_t k = 0; k < n; ++k)
                if (lines[k]) S[k] = std::max(S[k], static_cast<float>(o.seedSigma));
        }
        r.markedScore = hysteresis(S, W, H, o.seedSigma, o.growSigma, o.minRegion, r.map);
    }
    N = {};
    Nz = {};
    if (o.energyWindow > 0) {
        // step 8 on |A| and, with textureEnergy, on |T|
        auto inside = [&](size_t k) {
            const int x = static_cast<int>(k % static_cast<size_t>(W));
            const int y = static_cast<int>(k / static_cast<size_t>(W));
            return x >= o.border && x < W - o.border && y >= o.border && y < H - o.border;
        };
        auto markTextureChange = [&](std::vector<float>& v, double ratio) {
            for (float& x : v) x = std::abs(x);
            // on the 2×2-pooled values (window halved): a quarter of the work
            int W2 = 0, H2 = 0;
            const std::vector<float> pooled = pool2(v.data(), W, H, W2, H2);
            v = {};
            const std::vector<float> E2 =
                separableMedian(pooled, W2, H2, std::max(3, (o.energyWindow / 2) | 1));
            const double medE = std::max(medianAbs(E2), floorSigma);
            if (!(medE > 0.0)) return;
            for (size_t k = 0; k < n; ++k) {
                const int x = static_cast<int>(k % static_cast<size_t>(W));
                const int y = static_cast<int>(k / static_cast<size_t>(W));
                if (E2[static_cast<size_t>(y / 2) * W2 + x / 2] >= ratio * medE && inside(k)) {
                    if (!r.map[k]) ++r.markedEnergy;
                    r.map[k] = 255;
                }
            }
        };
        markTextureChange(A, o.energyRatio);
        if (o.textureEnergy) {
            if (sectors.empty()) markTextureChange(texture, o.textureEnergyRatio);
            for (std::vector<float>& t : sectors) markTextureChange(t, o.textureEnergyRatio);
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
