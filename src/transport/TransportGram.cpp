#include "transport/TransportGram.h"

#include <algorithm>
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

// P's rows a thread sums at once (32 rows of the periodic lines' 1060 seen texels: 271 KB, in
// a core's L2), and the pixels a thread takes at once for the rows of Lap·T_b.
constexpr size_t kRowsPerBlock = 32;
constexpr size_t kPixelsPerChunk = 1024;

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
    // Each entry's place in seen_ (T's columns are texels, < 65536: colIdx is 16-bit).
    const uint64_t nnz = t.rowPtr[rows];
    std::vector<uint16_t> at(nnz);
    forBlocks(rows, kPixelsPerChunk, threads, [&](size_t p0, size_t p1) {
        for (uint64_t k = t.rowPtr[p0]; k < t.rowPtr[p1]; ++k)
            at[k] = static_cast<uint16_t>(index_[t.colIdx[k]]);
    });
    // Row p of Lap·T_b, deg(p)·T_b[p] − Σ_{q ~ p} T_b[q], merged once per pixel (its texels
    // each once, at their places in seen_): a row of P then takes one multiply-add per texel of
    // it, where adding the neighbours' rows one by one took one per entry of each. Built over
    // chunks of pixels on every thread, each row on its own (the same values whatever the
    // threads): its texels counted first, so the rows are written once where they stay.
    const uint8_t* mask = pairMask.data();
    // f(q, s) for the rows that make row p of Lap·T_b (none where p has no pair or no entry).
    auto lapParts = [&](size_t p, auto&& f) {
        if (!mask[p] || t.rowPtr[p + 1] == t.rowPtr[p]) return;
        int deg = 0;
        forNeighbours(mask, w, h, p, [&](size_t q) {
            f(q, -1.0);
            ++deg;
        });
        if (deg > 0) f(p, static_cast<double>(deg));
    };
    const size_t chunks = (rows + kPixelsPerChunk - 1) / kPixelsPerChunk;
    std::vector<uint64_t> lapPtr(rows + 1, 0);
    forBlocks(chunks, 1, threads, [&](size_t c0, size_t c1) {
        std::vector<uint32_t> stamp(m_, 0);
        uint32_t now = 0;
        for (size_t p = c0 * kPixelsPerChunk; p < std::min(rows, c1 * kPixelsPerChunk); ++p) {
            ++now;
            uint64_t merged = 0;
            lapParts(p, [&](size_t q, double) {
                for (uint64_t k = t.rowPtr[q]; k < t.rowPtr[q + 1]; ++k)
                    if (stamp[at[k]] != now) stamp[at[k]] = now, ++merged;
            });
            lapPtr[p + 1] = merged;
        }
    });
    for (size_t p = 0; p < rows; ++p) lapPtr[p + 1] += lapPtr[p];
    std::vector<uint16_t> lapCol(lapPtr[rows]);
    std::vector<double> lapVal(lapPtr[rows]);
    forBlocks(chunks, 1, threads, [&](size_t c0, size_t c1) {
        std::vector<double> acc(m_, 0.0);
        std::vector<uint8_t> on(m_, 0);
        for (size_t p = c0 * kPixelsPerChunk; p < std::min(rows, c1 * kPixelsPerChunk); ++p) {
            uint64_t end = lapPtr[p];
            lapParts(p, [&](size_t q, double s) {
                for (uint64_t k = t.rowPtr[q]; k < t.rowPtr[q + 1]; ++k) {
                    const uint16_t j = at[k];
                    if (!on[j]) on[j] = 1, lapCol[end++] = j;
                    acc[j] += s * lum(k, 1);
                }
            });
            for (uint64_t l = lapPtr[p]; l < end; ++l) {
                lapVal[l] = acc[lapCol[l]];
                acc[lapCol[l]] = 0;
                on[lapCol[l]] = 0;
            }
        }
    });
    p_.assign(m_ * m_, 0.0);
    if (products) q_.assign(m_ * m_, 0.0);
    // P's rows in blocks of kRowsPerBlock, each block by one thread in pixel order: pixel p adds
    // T_a[p, i]·(row p of Lap·T_b) to the block's rows i, so each pixel's rows are read once
    // per block while they are in cache (a block's rows of P and Q stay in L2), where summing
    // row i over column i of T_a read every pixel's Lap row once per texel it sees, from
    // memory (~12 bytes per multiply-add: the periodic lines' 1.5·10⁹ took 4.9 s of CPU).
    // A block reads only its own entries of T_a (bucketed by block, pixels ascending), and a
    // pixel's entries in the block share each read of its rows (up to four rows of P at once).
    // Every P[i][j] is the same sum in the same order (pixels ascending), so the matrices are
    // the column order's bit for bit.
    const size_t blocks = (m_ + kRowsPerBlock - 1) / kRowsPerBlock;
    std::vector<uint64_t> blockPtr(blocks + 1, 0);
    for (uint64_t k = 0; k < nnz; ++k) ++blockPtr[at[k] / kRowsPerBlock + 1];
    for (size_t b = 0; b < blocks; ++b) blockPtr[b + 1] += blockPtr[b];
    std::vector<uint32_t> entryPixel(nnz);
    std::vector<uint16_t> entryInRow(nnz);  // its place in the pixel's row (< cols() <= 65536)
    {
        std::vector<uint64_t> next(blockPtr.begin(), blockPtr.end() - 1);
        for (size_t p = 0; p < rows; ++p)
            for (uint64_t k = t.rowPtr[p]; k < t.rowPtr[p + 1]; ++k) {
                const uint64_t e = next[at[k] / kRowsPerBlock]++;
                entryPixel[e] = static_cast<uint32_t>(p);
                entryInRow[e] = static_cast<uint16_t>(k - t.rowPtr[p]);
            }
    }
    // row[r][cols[l]] += a[r]·vals[l] for R rows at once, l over one row of Lap·T_b or T_b.
    auto addRows = [](double* const* row, const double* a, int R, const uint16_t* cols,
                      const double* vals, size_t len) {
        if (R == 4) {
            for (size_t l = 0; l < len; ++l) {
                const double v = vals[l];
                const size_t c = cols[l];
                row[0][c] += a[0] * v;
                row[1][c] += a[1] * v;
                row[2][c] += a[2] * v;
                row[3][c] += a[3] * v;
            }
        } else if (R == 2) {
            for (size_t l = 0; l < len; ++l) {
                const double v = vals[l];
                const size_t c = cols[l];
                row[0][c] += a[0] * v;
                row[1][c] += a[1] * v;
            }
        } else {
            for (size_t l = 0; l < len; ++l) row[0][cols[l]] += a[0] * vals[l];
        }
    };
    forBlocks(blocks, 1, threads, [&](size_t b0, size_t b1) {
        std::vector<double> rowB;  // T_b's row of a pixel, for Q
        for (size_t b = b0; b < b1; ++b) {
            const uint64_t e1 = blockPtr[b + 1];
            for (uint64_t e = blockPtr[b]; e < e1;) {
                const uint32_t p = entryPixel[e];
                uint64_t g = e + 1;
                while (g < e1 && entryPixel[g] == p) ++g;
                const uint16_t* lc = lapCol.data() + lapPtr[p];
                const double* lv = lapVal.data() + lapPtr[p];
                const size_t nl = lapPtr[p + 1] - lapPtr[p];
                const uint64_t k0 = t.rowPtr[p], kb = t.rowPtr[p + 1] - k0;
                if (products) {
                    rowB.resize(kb);
                    for (uint64_t k = 0; k < kb; ++k) rowB[k] = lum(k0 + k, 1);
                }
                while (e < g) {
                    const int R = g - e >= 4 ? 4 : g - e >= 2 ? 2 : 1;
                    double* pr[4];
                    double* qr[4];
                    double a[4];
                    for (int r = 0; r < R; ++r) {
                        const uint64_t k = k0 + entryInRow[e + static_cast<uint64_t>(r)];
                        a[r] = lum(k, 0);
                        pr[r] = p_.data() + size_t{at[k]} * m_;
                        qr[r] = products ? q_.data() + size_t{at[k]} * m_ : nullptr;
                    }
                    if (products) addRows(qr, a, R, at.data() + k0, rowB.data(), kb);
                    addRows(pr, a, R, lc, lv, nl);
                    e += static_cast<uint64_t>(R);
                }
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
