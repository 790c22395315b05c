// TransportSlices: an in-memory layout of a transport matrix (TransportMatrix.h) for the two
// products of an iteration, T·E and Tᵀ·g, built from T once (TransportLoss builds it when it
// pays, TransportLayout below). The .tm file and TransportMatrix keep CSR; this is a copy.
//
// SELL-C-σ with C = kLanes = 8 and σ = one image row: the pixels of each image row are sorted
// by their number of entries (longest first, stably) and cut into slices of 8; a slice stores
// its rows side by side, padded to its longest row, entry by entry ("slot" j holds the j-th
// entry of each of the 8 rows):
//
//     col[(slot·8 + lane)]                                       16-bit column
//     values[((slot·planes + plane)·channels + channel)·8 + lane]   float
//
// Padding repeats the lane's last column with the value 0. T·E keeps 8 independent sums and
// runs lane-parallel; Tᵀ·g forms a slot's 8 products lane-parallel and adds each into its
// lane's own sums (out8[i·8 + lane], reduced at the end), so the scatter never collides.
// Sorting makes the padding small (about 3 % on the bundled part) and the loops' lengths the
// same for 8 rows at a time. Each row's T·E adds the same products in the same order as
// TransportMatrix's product (its entries in order, then zeros), so Y equals it exactly; Tᵀ·g
// adds the rows in another order, so it equals TransportMatrix's to rounding (about 1e-16
// relative to the largest entry). The whole products run over fixed chunks of image rows and
// reduce the transposed partial sums in chunk order: results do not depend on the number of
// threads.
//
// Planes, channels and an RGB E as in TransportMatrix.h (plane 0, 1 or kMeanPlane; the mean of
// the halves is 0.5f·(a + b) in float, as TransportMatrix reads it). A dense T is stored by its
// non-zero entries. Bytes: (2 + 4·stride) per slot, 2 per pixel (the order), 8 per slice.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "transport/TransportMatrix.h"

namespace sl {

/// Which layout TransportLoss's products read: T's CSR arrays, the slices, or (Auto) CSR for
/// a loss's first kAutoSlicesAfter evaluations and the slices from then on (building them costs
/// about as much as 15–80 evaluations save, so a loss evaluated a few times never builds them).
/// Auto keeps CSR for a T of more than kAutoSlicesMaxBytes: the copy adds about 0.9× T's
/// memory, and a big image's T must fit beside it (4096² at 64 spp with halves: T 2.5 GB, peak
/// 7.0 GB on CSR; the copy would take it past 8 GB). Gram: a loss quadratic in T's halves
/// (objective/HalfImageObjective.h) is evaluated through T's Gram matrices
/// (transport/TransportGram.h), any other as Auto; Auto does the same from its
/// kAutoSlicesAfter-th evaluation on when the build pays (TransportLoss::gramPays), and from
/// the first when the loss has its Gram already (built, or read from the cache:
/// TransportLoss::adoptGram).
enum class TransportLayout { Csr, Slices, Auto, Gram };
inline constexpr int kAutoSlicesAfter = 16;
inline constexpr size_t kAutoSlicesMaxBytes = size_t{1} << 30;

class TransportSlices {
  public:
    static constexpr int kLanes = 8;

    explicit TransportSlices(const TransportMatrix& t);

    size_t rows() const { return static_cast<size_t>(width_) * height_; }
    size_t cols() const { return cols_; }
    int channels() const { return channels_; }
    int planes() const { return planes_; }
    /// T's non-zero entries (as counted when the layout was built).
    size_t nnz() const { return nnz_; }
    /// Stored entries, padding included (each 2 + 4·stride bytes).
    size_t slots() const { return col_.size(); }
    /// slots() / nnz(): the padding's overhead (1 = none).
    double padding() const;
    size_t bytes() const;  // bytes of the arrays a product streams through

    /// The products of TransportMatrix with the same arguments and results (see above);
    /// threads: worker threads (0 = all).
    void applyLuminance(std::span<const double> E, std::span<double> Y,
                        int plane = TransportMatrix::kMeanPlane, int threads = 0) const;
    void applyTransposeLuminance(std::span<const double> g, std::span<double> out,
                                 int plane = TransportMatrix::kMeanPlane, int threads = 0) const;
    void applyLuminanceHalves(std::span<const double> E, std::span<double> Ya, std::span<double> Yb,
                              int threads = 0) const;
    void applyTransposeLuminanceHalves(std::span<const double> ga, std::span<const double> gb,
                                       std::span<double> out, int threads = 0) const;

    /// Sequential kernels over rows [r0, r1) (any range; whole image rows are fastest, a part
    /// of a row costs the whole row's T·E), as TransportMatrix's: Y[r − r0], g[r − r0];
    /// accumulateTransposeRows ADDS into out. The fused loss uses these on bands of image rows.
    void applyLuminanceRows(const double* E, bool rgbE, double* Y, size_t r0, size_t r1,
                            int plane = TransportMatrix::kMeanPlane) const;
    void accumulateTransposeRows(const double* g, bool rgbE, double* out, size_t r0, size_t r1,
                                 int plane = TransportMatrix::kMeanPlane) const;
    /// The transposed product into per-lane sums out8[i·kLanes + lane] (size kLanes times
    /// out's): lanes never collide, so this is the fast form for many calls in a row (the fused
    /// loss adds a chunk's bands here); addLanes then adds them into out (out[i] += Σ lanes).
    void accumulateTransposeLanes(const double* g, bool rgbE, double* out8, size_t r0, size_t r1,
                                  int plane = TransportMatrix::kMeanPlane) const;
    static void addLanes(const double* out8, double* out, size_t n);
    /// Halves (planes() == 2) in one pass: Ya, Yb for a gray E; out += T_aᵀ·ga + T_bᵀ·gb.
    void applyHalvesRows(const double* E, bool rgbE, double* Ya, double* Yb, size_t r0,
                         size_t r1) const;
    void accumulateTransposeHalvesRows(const double* ga, const double* gb, bool rgbE, double* out,
                                       size_t r0, size_t r1) const;

  private:
    int width_ = 0, height_ = 0, channels_ = 1, planes_ = 1;
    size_t cols_ = 0, nnz_ = 0;
    int slicesPerRow_ = 0;
    std::vector<uint64_t> slicePtr_;  // slices + 1: first slot (of 8 entries) of each slice
    std::vector<uint16_t> order_;     // rows(): x of the pixel in each lane of an image row
    std::vector<uint16_t> col_;       // slots() entries, 8 per slot
    std::vector<float> values_;       // slots() · stride

    size_t stride() const { return static_cast<size_t>(channels_) * planes_; }
    struct SliceLanes {
        size_t row[kLanes];  // the row (pixel) in each lane
        bool in[kLanes];     // the lane holds a row of the requested range
    };
    bool checkE(size_t size, const char* who) const;  // true for an RGB E
    template <typename F>
    void forSlices(size_t r0, size_t r1, F&& f) const;
};

}  // namespace sl
