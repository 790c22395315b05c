#include "transport/TransportGram.h"

#include <stdexcept>
#include <string>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/Color.h"
#include "transport/BlockParallel.h"

namespace sl {

namespace {

// The luminance weights of core/Color.h (its one rule), each exact: w·1 + 0 + 0.
constexpr double kLum[3] = {luminance(1.0, 0.0, 0.0), luminance(0.0, 1.0, 0.0),
                            luminance(0.0, 0.0, 1.0)};

/// Σ_k a[k]·b[k] over n values in four interleaved sums (fixed order).
inline double dot(const double* a, const double* b, size_t n) {
    double s[4] = {0, 0, 0, 0};
    size_t k = 0;
    for (; k + 4 <= n; k += 4)
        for (int l = 0; l < 4; ++l) s[l] += a[k + l] * b[k + l];
    for (int l = 0; k < n; ++k, ++l) s[l] += a[k] * b[k];
    return (s[0] + s[2]) + (s[1] + s[3]);
}

/// out[r] = dot(a + r·stride, b, n) for r = 0..3, each the same bits as dot's: its four sums
/// in the same order, only with four rows in flight at once, so that each b[k] is loaded once
/// for the four and the sums' chains overlap (the form's product is bound by those chains).
inline void dot4(const double* a, size_t stride, const double* b, size_t n, double* out) {
#if defined(__SSE2__) && !defined(__FMA__)
    // Lanes: s[r][0] holds sums 0 and 1 of row r, s[r][1] sums 2 and 3. Each step rounds the
    // product and then the sum, as dot's does where the target has no fused multiply-add (with
    // one, the compiler may fuse dot's: then dot4 is dot itself, below).
    __m128d s[4][2];
    for (auto& row : s) row[0] = row[1] = _mm_setzero_pd();
    size_t k = 0;
    for (; k + 4 <= n; k += 4) {
        const __m128d x0 = _mm_loadu_pd(b + k), x1 = _mm_loadu_pd(b + k + 2);
        for (size_t r = 0; r < 4; ++r) {
            const double* ar = a + r * stride + k;
            s[r][0] = _mm_add_pd(s[r][0], _mm_mul_pd(_mm_loadu_pd(ar), x0));
            s[r][1] = _mm_add_pd(s[r][1], _mm_mul_pd(_mm_loadu_pd(ar + 2), x1));
        }
    }
    for (size_t r = 0; r < 4; ++r) {
        double t[4];
        _mm_storeu_pd(t, s[r][0]);
        _mm_storeu_pd(t + 2, s[r][1]);
        const double* ar = a + r * stride;
        for (size_t j = k, l = 0; j < n; ++j, ++l) t[l] += ar[j] * b[j];
        out[r] = (t[0] + t[2]) + (t[1] + t[3]);
    }
#else
    for (size_t r = 0; r < 4; ++r) out[r] = dot(a + r * stride, b, n);
#endif
}

/// The masked right/down/left/up neighbours of pixel p (itself masked): f(q) for each.
template <typename F>
inline void forNeighbours(const uint8_t* mask, size_t w, size_t h, size_t p, F&& f) {
    const size_t x = p % w, y = p / w;
    if (x + 1 < w && mask[p + 1]) f(p + 1);
    if (y + 1 < h && mask[p + w]) f(p + w);
    if (x > 0 && mask[p - 1]) f(p - 1);
    if (y > 0 && mask[p - w]) f(p - w);
}

void check(const TransportMatrix& t, std::span<const uint8_t> pairMask) {
    if (t.storage != TransportStorage::Sparse)
        throw std::invalid_argument("TransportGram: needs a sparse T");
    if (t.planes != 2) throw std::invalid_argument("TransportGram: needs the two halves of T");
    if (t.channels != 1 && t.channels != 3)
        throw std::invalid_argument("TransportGram: T has " + std::to_string(t.channels) +
                                    " channels");
    if (pairMask.size() != t.rows())
        throw std::invalid_argument("TransportGram: the pair mask has " +
                                    std::to_string(pairMask.size()) + " pixels, T " +
                                    std::to_string(t.rows()) + " rows");
}

}  // namespace

double TransportGram::buildWork(const TransportMatrix& t, std::span<const uint8_t> pairMask,
                                bool products) {
    check(t, pairMask);
    const size_t w = static_cast<size_t>(t.width), h = static_cast<size_t>(t.height);
    auto k = [&](size_t p) { return static_cast<double>(t.rowPtr[p + 1] - t.rowPtr[p]); };
    // The texels of row p of Lap·T_b: those of p and of its masked neighbours, each once.
    std::vector<size_t> stamp(t.cols(), 0);
    size_t now = 0;
    double work = 0;
    for (size_t p = 0; p < t.rows(); ++p) {
        const double kp = k(p);
        if (kp == 0) continue;
        if (products) work += kp * kp;
        if (!pairMask[p]) continue;
        ++now;
        size_t merged = 0;
        int deg = 0;
        auto visit = [&](size_t q) {
            for (uint64_t e = t.rowPtr[q]; e < t.rowPtr[q + 1]; ++e)
                if (stamp[t.colIdx[e]] != now) stamp[t.colIdx[e]] = now, ++merged;
        };
        forNeighbours(pairMask.data(), w, h, p, [&](size_t q) {
            visit(q);
            ++deg;
        });
        if (deg > 0) {
            visit(p);
            work += kp * static_cast<double>(merged);
        }
    }
    return work;
}

TransportGram::TransportGram(const TransportMatrix& t, std::span<const uint8_t> pairMask,
                             bool products, int threads)
    : n_(t.cols()) {
    check(t, pairMask);
    const size_t w = static_cast<size_t>(t.width), h = static_cast<size_t>(t.height);
    const size_t rows = t.rows(), st = static_cast<size_t>(t.stride());
    const int ch = t.channels;
    // The luminance of an entry's plane (gray E), in double from T's floats.
    auto lum = [&](uint64_t k, int plane) {
        const float* v = t.values.data() + k * st + static_cast<size_t>(plane * ch);
        if (ch == 1) return double(v[0]);
        return kLum[0] * v[0] + kLum[1] * v[1] + kLum[2] * v[2];
    };
    // The texels some pixel sees (T's non-empty columns), ascending.
    std::vector<uint8_t> seen(n_, 0);
    for (uint64_t k = 0; k < t.rowPtr[rows]; ++k) seen[t.colIdx[k]] = 1;
    index_.assign(n_, -1);
    for (size_t c = 0; c < n_; ++c)
        if (seen[c]) {
            index_[c] = static_cast<int32_t>(seen_.size());
            seen_.push_back(static_cast<uint16_t>(c));
        }
    m_ = seen_.size();
    // acc += s · lum(T_b row q).
    auto addRow = [&](double* acc, size_t q, double s) {
        for (uint64_t k = t.rowPtr[q]; k < t.rowPtr[q + 1]; ++k)
            acc[index_[t.colIdx[k]]] += s * lum(k, 1);
    };
    // Row p of Lap·T_b, deg(p)·T_b[p] − Σ_{q ~ p} T_b[q], merged once per pixel (its texels
    // each once, at their places in seen_): a row of P then takes one multiply-add per texel of
    // it, where adding the neighbours' rows one by one took one per entry of each.
    std::vector<uint64_t> lapPtr(rows + 1, 0);
    std::vector<uint32_t> lapCol;
    std::vector<double> lapVal;
    {
        std::vector<double> acc(m_, 0.0);
        std::vector<uint32_t> touched;
        std::vector<uint8_t> on(m_, 0);
        auto gather = [&](size_t q, double s) {
            for (uint64_t k = t.rowPtr[q]; k < t.rowPtr[q + 1]; ++k) {
                const auto j = static_cast<uint32_t>(index_[t.colIdx[k]]);
                if (!on[j]) on[j] = 1, touched.push_back(j);
                acc[j] += s * lum(k, 1);
            }
        };
        const uint8_t* mask = pairMask.data();
        for (size_t p = 0; p < rows; ++p) {
            lapPtr[p + 1] = lapPtr[p];
            if (!mask[p] || t.rowPtr[p + 1] == t.rowPtr[p]) continue;
            int deg = 0;
            forNeighbours(mask, w, h, p, [&](size_t q) {
                gather(q, -1.0);
                ++deg;
            });
            if (deg > 0) gather(p, deg);
            for (uint32_t j : touched) {
                lapCol.push_back(j);
                lapVal.push_back(acc[j]);
                acc[j] = 0;
                on[j] = 0;
            }
            touched.clear();
            lapPtr[p + 1] = lapCol.size();
        }
    }
    p_.assign(m_ * m_, 0.0);
    if (products) q_.assign(m_ * m_, 0.0);
    // P's rows in blocks of kRowsPerBlock, each block by one thread in pixel order: pixel p adds
    // T_a[p, i]·(row p of Lap·T_b) to the block's rows i, so each pixel's rows are read once
    // per block while they are in cache (a block's rows of P and Q stay in L2), where summing
    // row i over column i of T_a read every pixel's Lap row once per texel it sees, from
    // memory (~12 bytes per multiply-add: the periodic lines' 1.5·10⁹ took 4.9 s of CPU).
    // Every P[i][j] is the same sum in the same order (pixels ascending), so the matrices are
    // the column order's bit for bit.
    constexpr size_t kRowsPerBlock = 32;
    const size_t blocks = (m_ + kRowsPerBlock - 1) / kRowsPerBlock;
    forBlocks(blocks, 1, threads, [&](size_t b0, size_t b1) {
        for (size_t b = b0; b < b1; ++b) {
            const auto i0 = static_cast<int32_t>(b * kRowsPerBlock);
            const auto i1 = static_cast<int32_t>(std::min(m_, (b + 1) * kRowsPerBlock));
            for (size_t p = 0; p < rows; ++p)
                for (uint64_t k = t.rowPtr[p]; k < t.rowPtr[p + 1]; ++k) {
                    const int32_t i = index_[t.colIdx[k]];
                    if (i < i0 || i >= i1) continue;
                    const double ai = lum(k, 0);
                    const auto iu = static_cast<size_t>(i);
                    if (products) addRow(q_.data() + iu * m_, p, ai);
                    double* pr = p_.data() + iu * m_;
                    for (uint64_t l = lapPtr[p]; l < lapPtr[p + 1]; ++l)
                        pr[lapCol[l]] += ai * lapVal[l];
                }
        }
    });
    // sym(M) in place: the pairs (i, j), (j, i) get their mean, so P is exactly symmetric.
    auto symmetrise = [&](std::vector<double>& m) {
        forBlocks(m_, 16, threads, [&](size_t i0, size_t i1) {
            for (size_t i = i0; i < i1; ++i)
                for (size_t j = i + 1; j < m_; ++j) {
                    const double s = 0.5 * (m[i * m_ + j] + m[j * m_ + i]);
                    m[i * m_ + j] = s;
                    m[j * m_ + i] = s;
                }
        });
    };
    symmetrise(p_);
    if (products) symmetrise(q_);
}

TransportGram::TransportGram(size_t cols, std::vector<uint16_t> seen, std::vector<double> p,
                             std::vector<double> q)
    : n_(cols), m_(seen.size()), seen_(std::move(seen)), p_(std::move(p)), q_(std::move(q)) {
    if (p_.size() != m_ * m_ || (!q_.empty() && q_.size() != m_ * m_))
        throw std::invalid_argument("TransportGram: the matrices do not match the seen texels");
    index_.assign(n_, -1);
    for (size_t k = 0; k < m_; ++k) {
        if (seen_[k] >= n_ || (k > 0 && seen_[k] <= seen_[k - 1]))
            throw std::invalid_argument("TransportGram: seen texels not ascending within cols");
        index_[seen_[k]] = static_cast<int32_t>(k);
    }
}

double TransportGram::form(const std::vector<double>& m, std::span<const double> E,
                           std::span<double> ME, int threads) const {
    if (E.size() != n_) throw std::invalid_argument("TransportGram: E has the wrong size");
    if (!ME.empty() && ME.size() != n_)
        throw std::invalid_argument("TransportGram: the product has the wrong size");
    thread_local std::vector<double> e, v;
    e.resize(m_);
    v.resize(m_);
    for (size_t k = 0; k < m_; ++k) e[k] = E[seen_[k]];
    const double* x = e.data();
    double* out = v.data();  // the calling thread's vectors: workers use them through pointers
    auto rows = [&](size_t i0, size_t i1) {
        size_t i = i0;
        for (; i + 4 <= i1; i += 4) dot4(m.data() + i * m_, m_, x, m_, out + i);
        for (; i < i1; ++i) out[i] = dot(m.data() + i * m_, x, m_);
    };
    if (m_ * m_ <= kSerialEntries)
        rows(0, m_);
    else
        forBlocks(m_, 64, threads, rows);
    if (!ME.empty()) {
        std::fill(ME.begin(), ME.end(), 0.0);
        for (size_t k = 0; k < m_; ++k) ME[seen_[k]] = out[k];
    }
    return dot(x, out, m_);
}

double TransportGram::formOn(const std::vector<double>& m, std::span<const double> E,
                             std::span<const uint16_t> active, std::span<double> ME) const {
    if (E.size() != n_) throw std::invalid_argument("TransportGram: E has the wrong size");
    if (!ME.empty() && ME.size() != n_)
        throw std::invalid_argument("TransportGram: the product has the wrong size");
    thread_local std::vector<uint32_t> at;  // the active seen texels' places in seen_
    thread_local std::vector<uint16_t> texel;
    at.clear();
    texel.clear();
    for (uint16_t i : active) {
        if (i >= n_) throw std::invalid_argument("TransportGram: active texel out of range");
        if (index_[i] < 0) {
            if (!ME.empty()) ME[i] = 0.0;  // a texel no pixel sees
            continue;
        }
        at.push_back(static_cast<uint32_t>(index_[i]));
        texel.push_back(i);
    }
    double g = 0;
    for (size_t a = 0; a < at.size(); ++a) {
        const double* row = m.data() + size_t(at[a]) * m_;
        double s = 0;
        for (size_t b = 0; b < at.size(); ++b) s += row[at[b]] * E[texel[b]];
        if (!ME.empty()) ME[texel[a]] = s;
        g += E[texel[a]] * s;
    }
    return g;
}

double TransportGram::pairForm(std::span<const double> E, std::span<double> PE, int threads) const {
    return form(p_, E, PE, threads);
}

double TransportGram::productForm(std::span<const double> E, std::span<double> QE,
                                  int threads) const {
    if (q_.empty()) throw std::logic_error("TransportGram: built without the product form");
    return form(q_, E, QE, threads);
}

double TransportGram::pairFormOn(std::span<const double> E, std::span<const uint16_t> active,
                                 std::span<double> PE) const {
    return formOn(p_, E, active, PE);
}

double TransportGram::productFormOn(std::span<const double> E, std::span<const uint16_t> active,
                                    std::span<double> QE) const {
    if (q_.empty()) throw std::logic_error("TransportGram: built without the product form");
    return formOn(q_, E, active, QE);
}

}  // namespace sl
