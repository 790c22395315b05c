#include "detect/Spectrum.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <unsupported/Eigen/FFT>

#include "detect/ImageFilters.h"

namespace sl::defectmap {

namespace {

/// The smallest n' >= n whose prime factors are 2, 3 and 5 only.
int nextSmooth(int n) {
    for (int m = std::max(n, 1);; ++m) {
        int r = m;
        for (int p : {2, 3, 5})
            while (r % p == 0) r /= p;
        if (r == 1) return m;
    }
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

using Fft = Eigen::FFT<float>;

}  // namespace

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

}  // namespace sl::defectmap
