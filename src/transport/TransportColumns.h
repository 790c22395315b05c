// TransportColumns: a column-major (CSC) copy of a transport matrix's luminance, for products
// where the env map is non-zero on a few texels only (physical lamps, optimize/LampFit.h). With E zero
// outside a set A of texels,
//     Y = T·E = Σ_{t∈A} E_t · T[:, t]          (a scatter of |A| columns)
//     (Tᵀ·g)_t = T[:, t] · g   for t ∈ A        (|A| gathers)
// cost the non-zeros of A's columns instead of all of T's: when lamps light a fifth of the sky
// the products read a fraction of T (the measured saving is `bench lamps`'s).
//
// Values are the luminance of each entry for a GRAY E (TransportMatrix.h: lum_c·T_c summed over
// channels for an RGB T), rounded to float like T's values (sums in double); each plane of a T with
// halves is kept, and the mean plane is (T_a + T_b)/2 as TransportMatrix's products read it. Sums
// run in a fixed order (columns in the order given, rows ascending), one thread: a product's result
// does not depend on threads. Callers run several products side by side (the lamp fit's candidates)
// instead.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "transport/TransportMatrix.h"

namespace sl {

class TransportColumns {
  public:
    explicit TransportColumns(const TransportMatrix& t);

    size_t rows() const { return rows_; }
    size_t cols() const { return cols_; }
    int planes() const { return planes_; }
    /// Stored entries (one per non-zero of T).
    size_t nnz() const { return row_.size(); }
    /// Entries of column c.
    size_t columnEntries(size_t c) const { return colPtr_[c + 1] - colPtr_[c]; }

    /// Y = lum(T_plane · E) where E is zero outside `active` (E.size() == cols()); Y is
    /// overwritten (size rows()). plane: 0, 1 or TransportMatrix::kMeanPlane.
    void apply(std::span<const double> E, std::span<const uint16_t> active, std::span<double> Y,
               int plane = TransportMatrix::kMeanPlane) const;
    /// Both halves in one pass over the active columns (planes() == 2).
    void applyHalves(std::span<const double> E, std::span<const uint16_t> active,
                     std::span<double> Ya, std::span<double> Yb) const;
    /// out[t] = T_plane[:, t]·g for t in `active`; other entries of out are not touched.
    void transpose(std::span<const double> g, std::span<const uint16_t> active,
                   std::span<double> out, int plane = TransportMatrix::kMeanPlane) const;
    /// out[t] = T_a[:, t]·ga + T_b[:, t]·gb for t in `active` (planes() == 2).
    void transposeHalves(std::span<const double> ga, std::span<const double> gb,
                         std::span<const uint16_t> active, std::span<double> out) const;

    /// out = T_planeᵀ·g over every column (out.size() == cols()), the columns split over
    /// `threads` worker threads (0: all); each column's sum runs over its rows in order, so the
    /// result does not depend on the threads. The full transposed product with no scatter: the
    /// fast form when T is read many times (TransportLoss's gradient, transport/TransportSlices.h
    /// for T·E).
    void transposeAll(std::span<const double> g, std::span<double> out,
                      int plane = TransportMatrix::kMeanPlane, int threads = 0) const;
    /// out = T_aᵀ·ga + T_bᵀ·gb over every column (planes() == 2), as transposeAll.
    void transposeHalvesAll(std::span<const double> ga, std::span<const double> gb,
                            std::span<double> out, int threads = 0) const;
    size_t bytes() const;  // of the arrays a product reads

  private:
    size_t rows_ = 0, cols_ = 0;
    int planes_ = 1;
    std::vector<uint64_t> colPtr_;  // cols()+1
    std::vector<uint32_t> row_;     // nnz
    std::vector<float> value_;      // nnz·planes, [a, b] per entry for halves

    void checkActive(std::span<const uint16_t> active) const;
};

}  // namespace sl
