#include "transport/TransportMatrix.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <stdexcept>

#include "core/Color.h"
#include "core/Error.h"

namespace sl {

namespace {

// The luminance weights of core/Color.h (its one rule), each exact: w·1 + 0 + 0.
constexpr double kLum[3] = {luminance(1.0, 0.0, 0.0), luminance(0.0, 1.0, 0.0),
                            luminance(0.0, 0.0, 1.0)};

/// Runs f(chunk, rowBegin, rowEnd) over the fixed chunks [k·chunkRows, (k+1)·chunkRows) of
/// rows, in parallel. (A blocked_range with a grain size would split anywhere, not at
/// multiples of the grain, so chunks are enumerated explicitly.)
template <typename F>
void forRowChunks(const TransportMatrix& t, size_t chunkRows, F&& f) {
    const size_t n = t.rows(), chunks = (n + chunkRows - 1) / chunkRows;
    auto body = [&] {
        tbb::parallel_for(size_t(0), chunks,
                          [&](size_t k) { f(k, k * chunkRows, std::min(n, (k + 1) * chunkRows)); });
    };
    if (t.threads > 0) {
        tbb::task_arena arena(t.threads);
        arena.execute(body);
    } else {
        body();
    }
}

/// Calls f(col, v) for every stored entry of row r; v points at the entry's `stride()` floats.
template <typename F>
inline void forRow(const TransportMatrix& t, size_t r, F&& f) {
    const size_t st = static_cast<size_t>(t.stride());
    if (t.storage == TransportStorage::Sparse) {
        const uint64_t b = t.rowPtr[r], e = t.rowPtr[r + 1];
        const uint16_t* col = t.colIdx.data();
        const float* v = t.values.data();
        for (uint64_t k = b; k < e; ++k) f(static_cast<size_t>(col[k]), v + k * st);
    } else {
        const size_t cols = t.cols();
        const float* v = t.values.data() + r * cols * st;
        for (size_t c = 0; c < cols; ++c) f(c, v + c * st);
    }
}

/// Reads channel c of an entry for a plane: one plane, or the mean of the two halves.
struct PlaneReader {
    int offset = 0, channels = 1;
    bool mean = false;
    PlaneReader(const TransportMatrix& t, int plane) : channels(t.channels) {
        if (plane != TransportMatrix::kMeanPlane && (plane < 0 || plane >= t.planes))
            throw std::invalid_argument("TransportMatrix: no plane " + std::to_string(plane));
        mean = plane == TransportMatrix::kMeanPlane && t.planes == 2;
        offset = plane > 0 ? plane * t.channels : 0;
    }
    float operator()(const float* v, int c) const {
        return mean ? 0.5f * (v[c] + v[channels + c]) : v[offset + c];
    }
};

enum class EKind { Gray, Rgb };

EKind checkE(const TransportMatrix& t, size_t size, const char* what) {
    if (size == t.cols()) return EKind::Gray;
    if (size == 3 * t.cols()) {
        if (t.channels != 3)
            throw std::invalid_argument(std::string(what) +
                                        ": an RGB env map needs an RGB transport matrix "
                                        "(precompute with " +
                                        option("rgb") + ")");
        return EKind::Rgb;
    }
    throw std::invalid_argument(std::string(what) + ": env-map size does not match T's columns");
}

}  // namespace

bool sameShape(const TransportMatrix& a, const TransportMatrix& b) {
    return a.width == b.width && a.height == b.height && a.envWidth == b.envWidth &&
           a.envHeight == b.envHeight && a.channels == b.channels && a.planes == b.planes;
}

TransportMatrix emptySparseOfShape(const TransportMatrix& shape) {
    TransportMatrix t;
    t.width = shape.width;
    t.height = shape.height;
    t.envWidth = shape.envWidth;
    t.envHeight = shape.envHeight;
    t.channels = shape.channels;
    t.planes = shape.planes;
    t.storage = TransportStorage::Sparse;
    t.rowPtr.assign(t.rows() + 1, 0);
    t.objectMask.assign(t.rows(), 0);
    return t;
}

size_t TransportMatrix::nnz() const {
    return storage == TransportStorage::Sparse ? colIdx.size() : rows() * cols();
}

double TransportMatrix::density() const {
    if (rows() == 0 || cols() == 0) return 0;
    if (storage == TransportStorage::Dense) {
        size_t nz = 0;
        const size_t st = static_cast<size_t>(stride());
        for (size_t i = 0; i < values.size(); i += st) {
            bool any = false;
            for (size_t c = 0; c < st; ++c) any |= values[i + c] != 0.0f;
            nz += any;
        }
        return static_cast<double>(nz) /
               (static_cast<double>(rows()) * static_cast<double>(cols()));
    }
    return static_cast<double>(colIdx.size()) /
           (static_cast<double>(rows()) * static_cast<double>(cols()));
}

size_t TransportMatrix::bytes() const {
    return rowPtr.size() * sizeof(uint64_t) + colIdx.size() * sizeof(uint16_t) +
           values.size() * sizeof(float);
}

void TransportMatrix::applyLuminanceRows(const double* e, bool rgbE, double* Y, size_t r0,
                                         size_t r1, int plane) const {
    const PlaneReader pv(*this, plane);
    for (size_t r = r0; r < r1; ++r) {
        double acc = 0;
        if (channels == 1) {
            forRow(*this, r, [&](size_t c, const float* v) { acc += double(pv(v, 0)) * e[c]; });
        } else if (!rgbE) {
            forRow(*this, r, [&](size_t c, const float* v) {
                acc += (kLum[0] * pv(v, 0) + kLum[1] * pv(v, 1) + kLum[2] * pv(v, 2)) * e[c];
            });
        } else {
            forRow(*this, r, [&](size_t c, const float* v) {
                acc += kLum[0] * pv(v, 0) * e[3 * c] + kLum[1] * pv(v, 1) * e[3 * c + 1] +
                       kLum[2] * pv(v, 2) * e[3 * c + 2];
            });
        }
        Y[r - r0] = acc;
    }
}

void TransportMatrix::accumulateTransposeRows(const double* g, bool rgbE, double* acc, size_t r0,
                                              size_t r1, int plane) const {
    const PlaneReader pv(*this, plane);
    for (size_t r = r0; r < r1; ++r) {
        const double gr = g[r - r0];
        if (gr == 0.0) continue;
        if (channels == 1) {
            forRow(*this, r, [&](size_t c, const float* v) { acc[c] += double(pv(v, 0)) * gr; });
        } else if (!rgbE) {
            forRow(*this, r, [&](size_t c, const float* v) {
                acc[c] += (kLum[0] * pv(v, 0) + kLum[1] * pv(v, 1) + kLum[2] * pv(v, 2)) * gr;
            });
        } else {
            forRow(*this, r, [&](size_t c, const float* v) {
                for (int k = 0; k < 3; ++k) acc[3 * c + k] += kLum[k] * pv(v, k) * gr;
            });
        }
    }
}

void TransportMatrix::applyLuminance(std::span<const double> E, std::span<double> Y,
                                     int plane) const {
    const bool rgbE = checkE(*this, E.size(), "TransportMatrix::applyLuminance") == EKind::Rgb;
    if (Y.size() != rows()) throw std::invalid_argument("applyLuminance: Y size != rows");
    forRowChunks(*this, 256, [&](size_t, size_t r0, size_t r1) {
        applyLuminanceRows(E.data(), rgbE, Y.data() + r0, r0, r1, plane);
    });
}

void TransportMatrix::applyRgb(std::span<const double> E, std::span<double> rgb) const {
    if (channels != 3)
        throw std::invalid_argument("applyRgb: needs an RGB transport matrix (" + option("rgb") +
                                    ")");
    EKind kind = checkE(*this, E.size(), "TransportMatrix::applyRgb");
    if (rgb.size() != 3 * rows()) throw std::invalid_argument("applyRgb: output size != 3*rows");
    const double* e = E.data();
    const PlaneReader pv(*this, kMeanPlane);
    forRowChunks(*this, 256, [&](size_t, size_t r0, size_t r1) {
        for (size_t r = r0; r < r1; ++r) {
            double a[3] = {0, 0, 0};
            forRow(*this, r, [&](size_t c, const float* v) {
                for (int k = 0; k < 3; ++k)
                    a[k] += double(pv(v, k)) * (kind == EKind::Gray ? e[c] : e[3 * c + k]);
            });
            for (int k = 0; k < 3; ++k) rgb[3 * r + k] = a[k];
        }
    });
}

void TransportMatrix::applyTransposeLuminance(std::span<const double> g, std::span<double> out,
                                              int plane) const {
    const bool rgbE =
        checkE(*this, out.size(), "TransportMatrix::applyTransposeLuminance") == EKind::Rgb;
    if (g.size() != rows()) throw std::invalid_argument("applyTranspose: g size != rows");
    // Fixed chunks with one partial sum each, reduced in chunk order: the result does not
    // depend on the number of threads.
    const size_t chunkRows = std::max<size_t>(1024, (rows() + 63) / 64);
    const size_t nChunks = (rows() + chunkRows - 1) / chunkRows;
    const size_t n = out.size();
    std::vector<double> partial(nChunks * n, 0.0);
    forRowChunks(*this, chunkRows, [&](size_t k, size_t r0, size_t r1) {
        accumulateTransposeRows(g.data() + r0, rgbE, partial.data() + k * n, r0, r1, plane);
    });
    std::fill(out.begin(), out.end(), 0.0);
    for (size_t k = 0; k < nChunks; ++k)
        for (size_t i = 0; i < n; ++i) out[i] += partial[k * n + i];
}

void TransportMatrix::applyLuminanceHalves(std::span<const double> E, std::span<double> Ya,
                                           std::span<double> Yb) const {
    if (planes != 2) throw std::invalid_argument("applyLuminanceHalves: T has no halves");
    checkE(*this, E.size(), "TransportMatrix::applyLuminanceHalves");
    if (Ya.size() != rows() || Yb.size() != rows())
        throw std::invalid_argument("applyLuminanceHalves: Y size != rows");
    if (channels != 1 || storage != TransportStorage::Sparse) {
        applyLuminance(E, Ya, 0);
        applyLuminance(E, Yb, 1);
        return;
    }
    // A gray T (checkE refuses an RGB E for it): E holds one value per texel.
    const double* e = E.data();
    const uint16_t* col = colIdx.data();
    const float* v = values.data();
    forRowChunks(*this, 256, [&](size_t, size_t r0, size_t r1) {
        for (size_t r = r0; r < r1; ++r) {
            double a = 0, b = 0;
            for (uint64_t k = rowPtr[r], end = rowPtr[r + 1]; k < end; ++k) {
                const double ek = e[col[k]];
                a += double(v[2 * k]) * ek;
                b += double(v[2 * k + 1]) * ek;
            }
            Ya[r] = a;
            Yb[r] = b;
        }
    });
}

void TransportMatrix::applyTransposeLuminanceHalves(std::span<const double> ga,
                                                    std::span<const double> gb,
                                                    std::span<double> out) const {
    if (planes != 2) throw std::invalid_argument("applyTransposeLuminanceHalves: no halves");
    checkE(*this, out.size(), "TransportMatrix::applyTransposeLuminanceHalves");
    if (ga.size() != rows() || gb.size() != rows())
        throw std::invalid_argument("applyTransposeLuminanceHalves: g size != rows");
    if (channels != 1 || storage != TransportStorage::Sparse) {
        std::vector<double> tmp(out.size());
        applyTransposeLuminance(ga, out, 0);
        applyTransposeLuminance(gb, tmp, 1);
        for (size_t i = 0; i < out.size(); ++i) out[i] += tmp[i];
        return;
    }
    const size_t chunkRows = std::max<size_t>(1024, (rows() + 63) / 64);
    const size_t nChunks = (rows() + chunkRows - 1) / chunkRows;
    const size_t n = out.size();
    std::vector<double> partial(nChunks * n, 0.0);
    const uint16_t* col = colIdx.data();
    const float* v = values.data();
    forRowChunks(*this, chunkRows, [&](size_t c, size_t r0, size_t r1) {
        double* acc = partial.data() + c * n;
        for (size_t r = r0; r < r1; ++r) {
            const double a = ga[r], b = gb[r];
            if (a == 0.0 && b == 0.0) continue;
            for (uint64_t k = rowPtr[r], end = rowPtr[r + 1]; k < end; ++k)
                acc[col[k]] += double(v[2 * k]) * a + double(v[2 * k + 1]) * b;
        }
    });
    std::fill(out.begin(), out.end(), 0.0);
    for (size_t k = 0; k < nChunks; ++k)
        for (size_t i = 0; i < n; ++i) out[i] += partial[k * n + i];
}

void TransportMatrix::toDense() {
    if (storage == TransportStorage::Dense) return;
    const size_t cols_ = cols(), st = static_cast<size_t>(stride());
    std::vector<float> dense(rows() * cols_ * st, 0.0f);
    for (size_t r = 0; r < rows(); ++r)
        for (uint64_t k = rowPtr[r]; k < rowPtr[r + 1]; ++k)
            for (size_t c = 0; c < st; ++c)
                dense[(r * cols_ + colIdx[k]) * st + c] = values[k * st + c];
    values = std::move(dense);
    rowPtr.clear();
    rowPtr.shrink_to_fit();
    colIdx.clear();
    colIdx.shrink_to_fit();
    storage = TransportStorage::Dense;
}

void TransportMatrix::toSparse() {
    if (storage == TransportStorage::Sparse) return;
    const size_t cols_ = cols(), st = static_cast<size_t>(stride());
    std::vector<uint64_t> ptr(rows() + 1, 0);
    std::vector<uint16_t> idx;
    std::vector<float> val;
    for (size_t r = 0; r < rows(); ++r) {
        for (size_t c = 0; c < cols_; ++c) {
            const float* v = &values[(r * cols_ + c) * st];
            bool any = false;
            for (size_t k = 0; k < st; ++k) any |= v[k] != 0.0f;
            if (!any) continue;
            idx.push_back(static_cast<uint16_t>(c));
            val.insert(val.end(), v, v + st);
        }
        ptr[r + 1] = idx.size();
    }
    rowPtr = std::move(ptr);
    colIdx = std::move(idx);
    values = std::move(val);
    storage = TransportStorage::Sparse;
}

void chooseStorage(TransportMatrix& t) {
    const double rows = static_cast<double>(t.rows()), cols = static_cast<double>(t.cols());
    const double nz = t.density() * rows * cols;
    const double sparseBytes = nz * (2.0 + 4.0 * t.stride()) + 8.0 * (rows + 1);
    const double denseBytes = rows * cols * t.stride() * 4.0;
    if (sparseBytes <= denseBytes)
        t.toSparse();
    else
        t.toDense();
}

namespace {
/// Sums the 8-byte words of [p, p+bytes) with four independent accumulators: bound by memory
/// bandwidth, not by the latency of a dependent add chain.
uint64_t sumWords(const void* p, size_t bytes) {
    const auto* c = static_cast<const unsigned char*>(p);
    uint64_t a[4] = {0, 0, 0, 0};
    size_t i = 0;
    for (; i + 32 <= bytes; i += 32) {
        for (int k = 0; k < 4; ++k) {
            uint64_t w;
            std::memcpy(&w, c + i + 8 * k, 8);
            a[k] += w;
        }
    }
    for (; i < bytes; ++i) a[0] += c[i];
    return a[0] + a[1] + a[2] + a[3];
}
}  // namespace

double streamingRead(const TransportMatrix& t) {
    // Same chunking and threads as the products; every byte of the arrays is read once.
    const size_t chunkRows = 256;
    const size_t nChunks = (t.rows() + chunkRows - 1) / chunkRows;
    std::vector<uint64_t> partial(nChunks, 0);
    forRowChunks(t, chunkRows, [&](size_t chunk, size_t r0, size_t r1) {
        uint64_t s = 0;
        if (t.storage == TransportStorage::Sparse) {
            const uint64_t b = t.rowPtr[r0], e = t.rowPtr[r1];
            s += sumWords(t.rowPtr.data() + r0, (r1 - r0 + 1) * sizeof(uint64_t));
            s += sumWords(t.colIdx.data() + b, (e - b) * sizeof(uint16_t));
            const size_t st = static_cast<size_t>(t.stride());
            s += sumWords(t.values.data() + b * st, (e - b) * st * sizeof(float));
        } else {
            const size_t w = t.cols() * static_cast<size_t>(t.stride());
            s += sumWords(t.values.data() + r0 * w, (r1 - r0) * w * sizeof(float));
        }
        partial[chunk] = s;
    });
    uint64_t total = 0;
    for (uint64_t p : partial) total += p;
    return static_cast<double>(total);
}

}  // namespace sl
