#include "detect/ImageFilters.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace sl::defectmap {

namespace {

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

}  // namespace

int mirror(int i, int n) {
    if (n == 1) return 0;
    const int period = 2 * (n - 1);
    i %= period;
    if (i < 0) i += period;
    return i < n ? i : period - i;
}

void rowMedians(const float* img, int W, int H, int w, float* out) {
    tbb::parallel_for(0, H, [&](int y) {
        thread_local std::vector<float> win;
        const size_t o = static_cast<size_t>(y) * W;
        runningMedian(img + o, W, w, false, out + o, win);
    });
}

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

std::vector<float> separableMedian(const std::vector<float>& img, int W, int H, int w) {
    std::vector<float> tmp(img.size()), out(img.size());
    rowMedians(img.data(), W, H, w, tmp.data());
    columnMedians(tmp.data(), W, H, w, false, out.data());
    return out;
}

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

std::vector<float> separableQuadratic(const std::vector<float>& img, int W, int H, int w,
                                      bool alongX, bool alongZ) {
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

}  // namespace sl::defectmap

namespace sl {

std::vector<float> separableRunningMedian(const std::vector<float>& img, int W, int H, int w) {
    return defectmap::separableMedian(img, W, H, w);
}

}  // namespace sl
