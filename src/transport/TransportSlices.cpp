#include "transport/TransportSlices.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "core/Color.h"
#include "core/Error.h"

namespace sl {

namespace {

constexpr int L = TransportSlices::kLanes;
// The luminance weights of core/Color.h (its one rule), each exact: w·1 + 0 + 0.
constexpr double kLum[3] = {luminance(1.0, 0.0, 0.0), luminance(0.0, 1.0, 0.0),
                            luminance(0.0, 0.0, 1.0)};

/// The floats of slot u for a plane: x[channel][lane]. blk points at the slot's planes·CH·L
/// floats; offset selects a plane's block (Mean: the mean of the two planes, in float, as
/// TransportMatrix's PlaneReader).
template <int CH, bool Mean>
inline void laneValues(const float* blk, size_t offset, float (&x)[CH][L]) {
    for (int k = 0; k < CH; ++k)
        for (int l = 0; l < L; ++l)
            x[k][l] = Mean ? 0.5f * (blk[k * L + l] + blk[(CH + k) * L + l])
                           : blk[offset + static_cast<size_t>(k * L + l)];
}

/// One lane's float of channel k (as laneValues).
template <int CH, bool Mean>
inline float laneValue(const float* blk, size_t offset, int k, int l) {
    return Mean ? 0.5f * (blk[k * L + l] + blk[(CH + k) * L + l])
                : blk[offset + static_cast<size_t>(k * L + l)];
}

struct SliceData {
    const uint16_t* col;
    const float* val;
    size_t block;  // floats per slot: stride·L
};

/// acc[lane] = lum(T_plane·E) of the slice's rows, slots [u0, u1): each lane adds its row's
/// entries in order, as TransportMatrix::applyLuminanceRows.
template <int CH, bool Mean, bool RgbE>
inline void sliceApply(const SliceData& d, uint64_t u0, uint64_t u1, size_t offset, const double* e,
                       double (&acc)[L]) {
    for (int l = 0; l < L; ++l) acc[l] = 0.0;
    for (uint64_t u = u0; u < u1; ++u) {
        float x[CH][L];
        laneValues<CH, Mean>(d.val + u * d.block, offset, x);
        const uint16_t* c = d.col + u * L;
        if constexpr (CH == 1) {
            for (int l = 0; l < L; ++l) acc[l] += double(x[0][l]) * e[c[l]];
        } else if constexpr (!RgbE) {
            for (int l = 0; l < L; ++l)
                acc[l] += (kLum[0] * x[0][l] + kLum[1] * x[1][l] + kLum[2] * x[2][l]) * e[c[l]];
        } else {
            for (int l = 0; l < L; ++l) {
                const size_t i = 3 * static_cast<size_t>(c[l]);
                acc[l] += kLum[0] * x[0][l] * e[i] + kLum[1] * x[1][l] * e[i + 1] +
                          kLum[2] * x[2][l] * e[i + 2];
            }
        }
    }
}

/// out8[i·8 + lane] += (lane's row)ᵀ·g[lane] over slots [u0, u1), slot by slot: the products
/// of a slot are formed lane-parallel, and each lane adds into its own sums, so no two lanes
/// of a slot write the same place (padding adds 0 to the lane's last column).
template <int CH, bool Mean, bool RgbE>
inline void sliceTranspose(const SliceData& d, uint64_t u0, uint64_t u1, size_t offset,
                           const double (&g)[L], double* out8) {
    for (uint64_t u = u0; u < u1; ++u) {
        float x[CH][L];
        laneValues<CH, Mean>(d.val + u * d.block, offset, x);
        const uint16_t* c = d.col + u * L;
        if constexpr (CH == 1) {
            double p[L];
            for (int l = 0; l < L; ++l) p[l] = double(x[0][l]) * g[l];
            for (int l = 0; l < L; ++l) out8[size_t(c[l]) * L + size_t(l)] += p[l];
        } else if constexpr (!RgbE) {
            double p[L];
            for (int l = 0; l < L; ++l)
                p[l] = (kLum[0] * x[0][l] + kLum[1] * x[1][l] + kLum[2] * x[2][l]) * g[l];
            for (int l = 0; l < L; ++l) out8[size_t(c[l]) * L + size_t(l)] += p[l];
        } else {
            for (int k = 0; k < 3; ++k) {
                double p[L];
                for (int l = 0; l < L; ++l) p[l] = kLum[k] * x[k][l] * g[l];
                for (int l = 0; l < L; ++l)
                    out8[(3 * size_t(c[l]) + size_t(k)) * L + size_t(l)] += p[l];
            }
        }
    }
}

/// A thread's lane sums for accumulateTransposeRows: n·L zeros.
double* laneBuffer(size_t n) {
    thread_local std::vector<double> buf;
    buf.assign(n * L, 0.0);
    return buf.data();
}

/// Runs f(chunk, y0, y1) over the fixed chunks [k·chunk, (k+1)·chunk) of image rows.
template <typename F>
void forImageRowChunks(size_t height, size_t chunk, int threads, F&& f) {
    const size_t chunks = (height + chunk - 1) / chunk;
    auto body = [&] {
        tbb::parallel_for(size_t(0), chunks,
                          [&](size_t k) { f(k, k * chunk, std::min(height, (k + 1) * chunk)); });
    };
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(body);
    } else {
        body();
    }
}

/// Image rows per chunk of a transposed product: at most 32 chunks (each keeps a partial sum of
/// the output, and its lanes' sums), at least ~16 k pixels each.
size_t transposeChunkRows(size_t width, size_t height) {
    return std::max((height + 31) / 32, (16384 + width - 1) / width);
}

}  // namespace

TransportSlices::TransportSlices(const TransportMatrix& t)
    : width_(t.width),
      height_(t.height),
      channels_(t.channels),
      planes_(t.planes),
      cols_(t.cols()) {
    if (channels_ != 1 && channels_ != 3)
        throw std::invalid_argument("TransportSlices: T has " + std::to_string(channels_) +
                                    " channels");
    if (planes_ != 1 && planes_ != 2)
        throw std::invalid_argument("TransportSlices: T has " + std::to_string(planes_) +
                                    " planes");
    if (width_ > 65536)
        throw std::invalid_argument("TransportSlices: images wider than 65536 pixels");
    const size_t w = static_cast<size_t>(width_), h = static_cast<size_t>(height_);
    const size_t st = stride();
    slicesPerRow_ = (width_ + L - 1) / L;
    const size_t spr = static_cast<size_t>(slicesPerRow_), nSlices = spr * h;
    const bool sparse = t.storage == TransportStorage::Sparse;
    // f(col, v) for every entry of row r with a non-zero (a dense T's zeros are skipped).
    auto forEntries = [&](size_t r, auto&& f) {
        if (sparse) {
            for (uint64_t k = t.rowPtr[r]; k < t.rowPtr[r + 1]; ++k)
                f(t.colIdx[k], t.values.data() + k * st);
        } else {
            const float* v = t.values.data() + r * cols_ * st;
            for (size_t c = 0; c < cols_; ++c) {
                bool any = false;
                for (size_t i = 0; i < st; ++i) any |= v[c * st + i] != 0.0f;
                if (any) f(static_cast<uint16_t>(c), v + c * st);
            }
        }
    };
    // Pass 1: each image row's order (longest rows first) and its slices' lengths.
    order_.resize(rows());
    std::vector<uint64_t> ptr(nSlices + 1, 0);
    std::vector<size_t> rowNnz(h, 0);
    tbb::parallel_for(size_t(0), h, [&](size_t y) {
        std::vector<size_t> len(w, 0);
        for (size_t x = 0; x < w; ++x)
            forEntries(y * w + x, [&](uint16_t, const float*) { ++len[x]; });
        uint16_t* order = order_.data() + y * w;
        for (size_t x = 0; x < w; ++x) order[x] = static_cast<uint16_t>(x);
        std::stable_sort(order, order + w, [&](uint16_t a, uint16_t b) { return len[a] > len[b]; });
        size_t n = 0;
        for (size_t x = 0; x < w; ++x) n += len[x];
        rowNnz[y] = n;
        for (size_t k = 0; k < spr; ++k) ptr[y * spr + k + 1] = len[order[k * L]];
    });
    for (size_t s = 0; s < nSlices; ++s) ptr[s + 1] += ptr[s];
    for (size_t n : rowNnz) nnz_ += n;
    slicePtr_ = std::move(ptr);
    col_.assign(slicePtr_.back() * L, 0);
    values_.assign(slicePtr_.back() * st * L, 0.0f);
    // Pass 2: the entries, lane by lane; padding repeats the lane's last column with 0.
    tbb::parallel_for(size_t(0), h, [&](size_t y) {
        for (size_t k = 0; k < spr; ++k) {
            const uint64_t base = slicePtr_[y * spr + k], end = slicePtr_[y * spr + k + 1];
            for (size_t l = 0; l < L && k * L + l < w; ++l) {
                uint64_t u = base;
                uint16_t last = 0;
                forEntries(y * w + order_[y * w + k * L + l], [&](uint16_t c, const float* v) {
                    col_[u * L + l] = c;
                    float* blk = values_.data() + u * st * L;
                    for (size_t i = 0; i < st; ++i) blk[i * L + l] = v[i];
                    last = c;
                    ++u;
                });
                for (; u < end; ++u) col_[u * L + l] = last;
            }
        }
    });
}

double TransportSlices::padding() const {
    return nnz_ > 0 ? static_cast<double>(col_.size()) / static_cast<double>(nnz_) : 1.0;
}

size_t TransportSlices::bytes() const {
    return slicePtr_.size() * sizeof(uint64_t) + order_.size() * sizeof(uint16_t) +
           col_.size() * sizeof(uint16_t) + values_.size() * sizeof(float);
}

bool TransportSlices::checkE(size_t size, const char* who) const {
    if (size == cols_) return false;
    if (size == 3 * cols_) {
        if (channels_ != 3)
            throw std::invalid_argument(std::string(who) +
                                        ": an RGB env map needs an RGB transport matrix "
                                        "(precompute with " +
                                        option("rgb") + ")");
        return true;
    }
    throw std::invalid_argument(std::string(who) + ": env-map size does not match T's columns");
}

template <typename F>
void TransportSlices::forSlices(size_t r0, size_t r1, F&& f) const {
    if (r0 >= r1) return;
    const size_t w = static_cast<size_t>(width_), spr = static_cast<size_t>(slicesPerRow_);
    for (size_t y = r0 / w; y * w < r1; ++y) {
        const size_t first = y * w;
        const bool whole = r0 <= first && first + w <= r1;
        for (size_t k = 0; k < spr; ++k) {
            SliceLanes ln;
            bool any = false;
            for (size_t l = 0; l < L; ++l) {
                const size_t i = k * L + l;
                ln.in[l] = false;
                ln.row[l] = 0;
                if (i < w) {
                    ln.row[l] = first + order_[first + i];
                    ln.in[l] = whole || (ln.row[l] >= r0 && ln.row[l] < r1);
                }
                any = any || ln.in[l];
            }
            if (any) f(y * spr + k, ln);
        }
    }
}

namespace {

/// The plane a product reads: Mean, or the float offset of one plane's block.
struct PlaneChoice {
    bool mean = false;
    size_t offset = 0;
};

PlaneChoice choosePlane(int plane, int planes, int channels) {
    if (plane != TransportMatrix::kMeanPlane && (plane < 0 || plane >= planes))
        throw std::invalid_argument("TransportSlices: no plane " + std::to_string(plane));
    PlaneChoice p;
    p.mean = plane == TransportMatrix::kMeanPlane && planes == 2;
    p.offset = plane > 0 ? static_cast<size_t>(plane * channels * L) : 0;
    return p;
}

/// Calls f.template operator()<CH, Mean, RgbE>() for the runtime choice.
template <typename F>
void dispatch(int channels, bool mean, bool rgbE, F&& f) {
    if (channels == 1) {
        if (mean)
            f.template operator()<1, true, false>();
        else
            f.template operator()<1, false, false>();
    } else if (!rgbE) {
        if (mean)
            f.template operator()<3, true, false>();
        else
            f.template operator()<3, false, false>();
    } else {
        if (mean)
            f.template operator()<3, true, true>();
        else
            f.template operator()<3, false, true>();
    }
}

}  // namespace

void TransportSlices::applyLuminanceRows(const double* E, bool rgbE, double* Y, size_t r0,
                                         size_t r1, int plane) const {
    const PlaneChoice pc = choosePlane(plane, planes_, channels_);
    const SliceData d{col_.data(), values_.data(), stride() * L};
    dispatch(channels_, pc.mean, rgbE, [&]<int CH, bool Mean, bool RgbE>() {
        forSlices(r0, r1, [&](size_t s, const SliceLanes& ln) {
            double acc[L];
            sliceApply<CH, Mean, RgbE>(d, slicePtr_[s], slicePtr_[s + 1], pc.offset, E, acc);
            for (size_t l = 0; l < L; ++l)
                if (ln.in[l]) Y[ln.row[l] - r0] = acc[l];
        });
    });
}

void TransportSlices::accumulateTransposeRows(const double* g, bool rgbE, double* out, size_t r0,
                                              size_t r1, int plane) const {
    const size_t n = (rgbE ? 3 : 1) * cols_;
    double* out8 = laneBuffer(n);
    accumulateTransposeLanes(g, rgbE, out8, r0, r1, plane);
    addLanes(out8, out, n);
}

void TransportSlices::accumulateTransposeLanes(const double* g, bool rgbE, double* out8, size_t r0,
                                               size_t r1, int plane) const {
    const PlaneChoice pc = choosePlane(plane, planes_, channels_);
    const SliceData d{col_.data(), values_.data(), stride() * L};
    dispatch(channels_, pc.mean, rgbE, [&]<int CH, bool Mean, bool RgbE>() {
        forSlices(r0, r1, [&](size_t s, const SliceLanes& ln) {
            double gl[L];
            bool any = false;
            for (size_t l = 0; l < L; ++l) {
                gl[l] = ln.in[l] ? g[ln.row[l] - r0] : 0.0;
                any = any || gl[l] != 0.0;
            }
            if (any)
                sliceTranspose<CH, Mean, RgbE>(d, slicePtr_[s], slicePtr_[s + 1], pc.offset, gl,
                                               out8);
        });
    });
}

void TransportSlices::addLanes(const double* out8, double* out, size_t n) {
    for (size_t i = 0; i < n; ++i) {
        const double* p = out8 + i * L;
        out[i] += ((p[0] + p[4]) + (p[2] + p[6])) + ((p[1] + p[5]) + (p[3] + p[7]));
    }
}

void TransportSlices::applyHalvesRows(const double* E, bool rgbE, double* Ya, double* Yb, size_t r0,
                                      size_t r1) const {
    if (planes_ != 2) throw std::invalid_argument("TransportSlices: T has no halves");
    if (channels_ != 1) {
        applyLuminanceRows(E, rgbE, Ya, r0, r1, 0);
        applyLuminanceRows(E, rgbE, Yb, r0, r1, 1);
        return;
    }
    forSlices(r0, r1, [&](size_t s, const SliceLanes& ln) {
        double a[L], b[L];
        for (size_t l = 0; l < L; ++l) a[l] = b[l] = 0.0;
        for (uint64_t u = slicePtr_[s], end = slicePtr_[s + 1]; u < end; ++u) {
            const float* blk = values_.data() + u * 2 * L;
            const uint16_t* c = col_.data() + u * L;
            for (size_t l = 0; l < L; ++l) {
                const double ec = E[c[l]];
                a[l] += double(blk[l]) * ec;
                b[l] += double(blk[L + l]) * ec;
            }
        }
        for (size_t l = 0; l < L; ++l) {
            if (!ln.in[l]) continue;
            Ya[ln.row[l] - r0] = a[l];
            Yb[ln.row[l] - r0] = b[l];
        }
    });
}

void TransportSlices::accumulateTransposeHalvesRows(const double* ga, const double* gb, bool rgbE,
                                                    double* out, size_t r0, size_t r1) const {
    if (planes_ != 2) throw std::invalid_argument("TransportSlices: T has no halves");
    if (channels_ != 1) {
        accumulateTransposeRows(ga, rgbE, out, r0, r1, 0);
        accumulateTransposeRows(gb, rgbE, out, r0, r1, 1);
        return;
    }
    double* out8 = laneBuffer(cols_);
    forSlices(r0, r1, [&](size_t s, const SliceLanes& ln) {
        double a[L], b[L];
        bool any = false;
        for (size_t l = 0; l < L; ++l) {
            a[l] = ln.in[l] ? ga[ln.row[l] - r0] : 0.0;
            b[l] = ln.in[l] ? gb[ln.row[l] - r0] : 0.0;
            any = any || a[l] != 0.0 || b[l] != 0.0;
        }
        if (!any) return;
        for (uint64_t u = slicePtr_[s], end = slicePtr_[s + 1]; u < end; ++u) {
            const float* blk = values_.data() + u * 2 * L;
            const uint16_t* c = col_.data() + u * L;
            double p[L];
            for (size_t l = 0; l < L; ++l) p[l] = double(blk[l]) * a[l] + double(blk[L + l]) * b[l];
            for (size_t l = 0; l < L; ++l) out8[size_t(c[l]) * L + l] += p[l];
        }
    });
    addLanes(out8, out, cols_);
}

void TransportSlices::applyLuminance(std::span<const double> E, std::span<double> Y, int plane,
                                     int threads) const {
    const bool rgbE = checkE(E.size(), "TransportSlices::applyLuminance");
    if (Y.size() != rows()) throw std::invalid_argument("applyLuminance: Y size != rows");
    const size_t w = static_cast<size_t>(width_);
    const size_t chunk = std::max<size_t>(1, 4096 / std::max<size_t>(w, 1));
    forImageRowChunks(
        static_cast<size_t>(height_), chunk, threads, [&](size_t, size_t y0, size_t y1) {
            applyLuminanceRows(E.data(), rgbE, Y.data() + y0 * w, y0 * w, y1 * w, plane);
        });
}

void TransportSlices::applyLuminanceHalves(std::span<const double> E, std::span<double> Ya,
                                           std::span<double> Yb, int threads) const {
    if (planes_ != 2) throw std::invalid_argument("applyLuminanceHalves: T has no halves");
    const bool rgbE = checkE(E.size(), "TransportSlices::applyLuminanceHalves");
    if (Ya.size() != rows() || Yb.size() != rows())
        throw std::invalid_argument("applyLuminanceHalves: Y size != rows");
    const size_t w = static_cast<size_t>(width_);
    const size_t chunk = std::max<size_t>(1, 4096 / std::max<size_t>(w, 1));
    forImageRowChunks(
        static_cast<size_t>(height_), chunk, threads, [&](size_t, size_t y0, size_t y1) {
            applyHalvesRows(E.data(), rgbE, Ya.data() + y0 * w, Yb.data() + y0 * w, y0 * w, y1 * w);
        });
}

void TransportSlices::applyTransposeLuminance(std::span<const double> g, std::span<double> out,
                                              int plane, int threads) const {
    const bool rgbE = checkE(out.size(), "TransportSlices::applyTransposeLuminance");
    if (g.size() != rows()) throw std::invalid_argument("applyTranspose: g size != rows");
    const size_t w = static_cast<size_t>(width_), h = static_cast<size_t>(height_);
    const size_t chunk = transposeChunkRows(w, h), nChunks = (h + chunk - 1) / chunk;
    const size_t n = out.size();
    std::vector<double> partial(nChunks * n, 0.0);
    forImageRowChunks(h, chunk, threads, [&](size_t k, size_t y0, size_t y1) {
        accumulateTransposeRows(g.data() + y0 * w, rgbE, partial.data() + k * n, y0 * w, y1 * w,
                                plane);
    });
    std::fill(out.begin(), out.end(), 0.0);
    for (size_t k = 0; k < nChunks; ++k)
        for (size_t i = 0; i < n; ++i) out[i] += partial[k * n + i];
}

void TransportSlices::applyTransposeLuminanceHalves(std::span<const double> ga,
                                                    std::span<const double> gb,
                                                    std::span<double> out, int threads) const {
    if (planes_ != 2) throw std::invalid_argument("applyTransposeLuminanceHalves: no halves");
    const bool rgbE = checkE(out.size(), "TransportSlices::applyTransposeLuminanceHalves");
    if (ga.size() != rows() || gb.size() != rows())
        throw std::invalid_argument("applyTransposeLuminanceHalves: g size != rows");
    const size_t w = static_cast<size_t>(width_), h = static_cast<size_t>(height_);
    const size_t chunk = transposeChunkRows(w, h), nChunks = (h + chunk - 1) / chunk;
    const size_t n = out.size();
    std::vector<double> partial(nChunks * n, 0.0);
    forImageRowChunks(h, chunk, threads, [&](size_t k, size_t y0, size_t y1) {
        accumulateTransposeHalvesRows(ga.data() + y0 * w, gb.data() + y0 * w, rgbE,
                                      partial.data() + k * n, y0 * w, y1 * w);
    });
    std::fill(out.begin(), out.end(), 0.0);
    for (size_t k = 0; k < nChunks; ++k)
        for (size_t i = 0; i < n; ++i) out[i] += partial[k * n + i];
}

}  // namespace sl
