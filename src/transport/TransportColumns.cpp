#include "transport/TransportColumns.h"

#include <algorithm>
#include <stdexcept>

#include "core/Color.h"
#include "transport/BlockParallel.h"

namespace sl {

namespace {

// The luminance weights of core/Color.h (its one rule), each exact: w·1 + 0 + 0.
constexpr double kLum[3] = {luminance(1.0, 0.0, 0.0), luminance(0.0, 1.0, 0.0),
                            luminance(0.0, 0.0, 1.0)};

/// Σ term(k) over [k0, k1) in four interleaved partial sums (entry k into sum k mod 4, then
/// (s0 + s2) + (s1 + s3)): the adds of one sum no longer wait on each other, and the order is
/// fixed.
template <typename F>
inline double columnSum(uint64_t k0, uint64_t k1, F&& term) {
    double s[4] = {0, 0, 0, 0};
    uint64_t k = k0;
    for (; k + 4 <= k1; k += 4) {
        s[0] += term(k);
        s[1] += term(k + 1);
        s[2] += term(k + 2);
        s[3] += term(k + 3);
    }
    for (int l = 0; k < k1; ++k, ++l) s[l] += term(k);
    return (s[0] + s[2]) + (s[1] + s[3]);
}

}  // namespace

TransportColumns::TransportColumns(const TransportMatrix& t)
    : rows_(t.rows()), cols_(t.cols()), planes_(t.planes) {
    if (t.rows() > UINT32_MAX) throw std::invalid_argument("TransportColumns: too many rows");
    const size_t st = static_cast<size_t>(t.stride());
    const int ch = t.channels;
    // The luminance of channel block `plane` of an entry (gray E).
    auto lum = [&](const float* v, int plane) {
        const float* p = v + plane * ch;
        if (ch == 1) return double(p[0]);
        return kLum[0] * p[0] + kLum[1] * p[1] + kLum[2] * p[2];
    };
    auto nonZero = [&](const float* v) {
        for (size_t k = 0; k < st; ++k)
            if (v[k] != 0.0f) return true;
        return false;
    };
    // Count per column, then fill (rows ascending within each column).
    colPtr_.assign(cols_ + 1, 0);
    auto forEntry = [&](auto&& f) {
        for (size_t r = 0; r < rows_; ++r) {
            if (t.storage == TransportStorage::Sparse) {
                for (uint64_t k = t.rowPtr[r]; k < t.rowPtr[r + 1]; ++k)
                    f(r, static_cast<size_t>(t.colIdx[k]), t.values.data() + k * st);
            } else {
                const float* v = t.values.data() + r * cols_ * st;
                for (size_t c = 0; c < cols_; ++c)
                    if (nonZero(v + c * st)) f(r, c, v + c * st);
            }
        }
    };
    forEntry([&](size_t, size_t c, const float*) { ++colPtr_[c + 1]; });
    for (size_t c = 0; c < cols_; ++c) colPtr_[c + 1] += colPtr_[c];
    const size_t n = colPtr_[cols_];
    row_.resize(n);
    value_.resize(n * static_cast<size_t>(planes_));
    std::vector<uint64_t> next(colPtr_.begin(), colPtr_.end() - 1);
    forEntry([&](size_t r, size_t c, const float* v) {
        const uint64_t k = next[c]++;
        row_[k] = static_cast<uint32_t>(r);
        for (int p = 0; p < planes_; ++p)
            value_[k * static_cast<size_t>(planes_) + static_cast<size_t>(p)] =
                static_cast<float>(lum(v, p));
    });
}

void TransportColumns::checkActive(std::span<const uint16_t> active) const {
    for (uint16_t c : active)
        if (c >= cols_) throw std::invalid_argument("TransportColumns: active column out of range");
}

void TransportColumns::apply(std::span<const double> E, std::span<const uint16_t> active,
                             std::span<double> Y, int plane) const {
    if (E.size() != cols_ || Y.size() != rows_)
        throw std::invalid_argument("TransportColumns::apply: wrong sizes");
    if (plane != TransportMatrix::kMeanPlane && (plane < 0 || plane >= planes_))
        throw std::invalid_argument("TransportColumns: no such plane");
    checkActive(active);
    std::fill(Y.begin(), Y.end(), 0.0);
    const size_t P = static_cast<size_t>(planes_);
    const bool mean = plane == TransportMatrix::kMeanPlane && planes_ == 2;
    const size_t off = plane > 0 ? static_cast<size_t>(plane) : 0;
    for (uint16_t c : active) {
        const double e = E[c];
        if (e == 0.0) continue;
        for (uint64_t k = colPtr_[c]; k < colPtr_[c + 1]; ++k) {
            const float* v = value_.data() + k * P;
            Y[row_[k]] += (mean ? 0.5 * (double(v[0]) + v[1]) : double(v[off])) * e;
        }
    }
}

void TransportColumns::applyHalves(std::span<const double> E, std::span<const uint16_t> active,
                                   std::span<double> Ya, std::span<double> Yb) const {
    if (planes_ != 2) throw std::invalid_argument("TransportColumns::applyHalves: no halves");
    if (E.size() != cols_ || Ya.size() != rows_ || Yb.size() != rows_)
        throw std::invalid_argument("TransportColumns::applyHalves: wrong sizes");
    checkActive(active);
    std::fill(Ya.begin(), Ya.end(), 0.0);
    std::fill(Yb.begin(), Yb.end(), 0.0);
    for (uint16_t c : active) {
        const double e = E[c];
        if (e == 0.0) continue;
        for (uint64_t k = colPtr_[c]; k < colPtr_[c + 1]; ++k) {
            Ya[row_[k]] += double(value_[2 * k]) * e;
            Yb[row_[k]] += double(value_[2 * k + 1]) * e;
        }
    }
}

void TransportColumns::transpose(std::span<const double> g, std::span<const uint16_t> active,
                                 std::span<double> out, int plane) const {
    if (g.size() != rows_ || out.size() != cols_)
        throw std::invalid_argument("TransportColumns::transpose: wrong sizes");
    if (plane != TransportMatrix::kMeanPlane && (plane < 0 || plane >= planes_))
        throw std::invalid_argument("TransportColumns: no such plane");
    checkActive(active);
    const size_t P = static_cast<size_t>(planes_);
    const bool mean = plane == TransportMatrix::kMeanPlane && planes_ == 2;
    const size_t off = plane > 0 ? static_cast<size_t>(plane) : 0;
    for (uint16_t c : active) {
        double acc = 0;
        for (uint64_t k = colPtr_[c]; k < colPtr_[c + 1]; ++k) {
            const float* v = value_.data() + k * P;
            acc += (mean ? 0.5 * (double(v[0]) + v[1]) : double(v[off])) * g[row_[k]];
        }
        out[c] = acc;
    }
}

void TransportColumns::transposeHalves(std::span<const double> ga, std::span<const double> gb,
                                       std::span<const uint16_t> active,
                                       std::span<double> out) const {
    if (planes_ != 2) throw std::invalid_argument("TransportColumns::transposeHalves: no halves");
    if (ga.size() != rows_ || gb.size() != rows_ || out.size() != cols_)
        throw std::invalid_argument("TransportColumns::transposeHalves: wrong sizes");
    checkActive(active);
    for (uint16_t c : active) {
        double acc = 0;
        for (uint64_t k = colPtr_[c]; k < colPtr_[c + 1]; ++k) {
            const uint32_t r = row_[k];
            acc += double(value_[2 * k]) * ga[r] + double(value_[2 * k + 1]) * gb[r];
        }
        out[c] = acc;
    }
}

size_t TransportColumns::bytes() const {
    return colPtr_.size() * sizeof(uint64_t) + row_.size() * sizeof(uint32_t) +
           value_.size() * sizeof(float);
}

void TransportColumns::transposeAll(std::span<const double> g, std::span<double> out, int plane,
                                    int threads) const {
    if (g.size() != rows_ || out.size() != cols_)
        throw std::invalid_argument("TransportColumns::transposeAll: wrong sizes");
    if (plane != TransportMatrix::kMeanPlane && (plane < 0 || plane >= planes_))
        throw std::invalid_argument("TransportColumns: no such plane");
    const size_t P = static_cast<size_t>(planes_);
    const bool mean = plane == TransportMatrix::kMeanPlane && planes_ == 2;
    const size_t off = plane > 0 ? static_cast<size_t>(plane) : 0;
    const float* val = value_.data();
    const uint32_t* row = row_.data();
    const double* gd = g.data();
    forBlocks(cols_, 16, threads, [&](size_t c0, size_t c1) {
        for (size_t c = c0; c < c1; ++c) {
            const uint64_t k1 = colPtr_[c + 1];
            auto term = [&](uint64_t k) {
                return mean ? 0.5 * (double(val[2 * k]) + val[2 * k + 1]) * gd[row[k]]
                            : double(val[k * P + off]) * gd[row[k]];
            };
            out[c] = columnSum(colPtr_[c], k1, term);
        }
    });
}

void TransportColumns::transposeHalvesAll(std::span<const double> ga, std::span<const double> gb,
                                          std::span<double> out, int threads) const {
    if (planes_ != 2)
        throw std::invalid_argument("TransportColumns::transposeHalvesAll: no halves");
    if (ga.size() != rows_ || gb.size() != rows_ || out.size() != cols_)
        throw std::invalid_argument("TransportColumns::transposeHalvesAll: wrong sizes");
    const float* val = value_.data();
    const uint32_t* row = row_.data();
    const double* a = ga.data();
    const double* b = gb.data();
    forBlocks(cols_, 16, threads, [&](size_t c0, size_t c1) {
        for (size_t c = c0; c < c1; ++c) {
            out[c] = columnSum(colPtr_[c], colPtr_[c + 1], [&](uint64_t k) {
                const uint32_t r = row[k];
                return double(val[2 * k]) * a[r] + double(val[2 * k + 1]) * b[r];
            });
        }
    });
}

}  // namespace sl
