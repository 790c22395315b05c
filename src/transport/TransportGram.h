// TransportGram: the quadratic forms of T's two halves as dense cols() × cols() matrices, for a
// loss that depends on the half images Y_a = T_a·E, Y_b = T_b·E only through
//
//     G(E) = Σ_pairs (Y_a,q − Y_a,p)·(Y_b,q − Y_b,p) = Eᵀ·P·E,   P = sym(T_aᵀ·Lap·T_b)
//     R(E) = Σ_p Y_a,p·Y_b,p                          = Eᵀ·Q·E,   Q = sym(T_aᵀ·T_b)
//
// (the noise-unbiased objective, objective/UnbiasedObjective.h). The pairs are an image's right
// and down neighbours with both pixels in `pairMask`; Lap is that pixel graph's Laplacian
// (aᵀ·Lap·b = Σ_pairs (a_q − a_p)(b_q − b_p)), and sym(M) = (M + Mᵀ)/2, so ∇G = 2·P·E.
//
// Once built, an evaluation costs one symmetric product with an at most cols()² matrix (the
// seen texels', below: 670² = 3.6 MB on the bundled part at 256²) whatever the image size and
// spp, against two sparse products over all of T's non-zeros and a pass over the image. Building
// costs about Σ_p k_p·|L_p| multiply-adds (k: a row's entries; L_p: row p of Lap·T_b, merged
// once, the texels of p and its neighbours each once; buildWork()), each into one of a
// block of P's rows that stays in the core's cache (adding the neighbours' rows one by one, Σ_p
// k_p·Σ_{q ∈ N[p]} k_q, costs more where neighbouring pixels see the same texels: 1.22–1.26× on the
// tests' small part, tests/test_transport_gram.cpp). It equals the products' loss to rounding
// (another order of the same sums).
//
// For a gray E (luminance of each entry, as TransportColumns). Only the texels some pixel sees
// (T's non-empty columns) have rows and columns in P and Q: the others' are zero (at 256² the
// bundled part sees about half the sky). The rows of Lap·T_b are merged over chunks of pixels
// on every thread; P's rows are summed in blocks, a block by one thread over its own entries of
// T_a, pixels in order (each entry the same sum in the same order whatever the threads),
// and P, Q are formed whole before they are used; a form of at most
// kSerialEntries entries runs on the calling thread (waking other threads for a product of a
// few MB costs more than it saves on a shared machine): results do not depend on the number of
// threads. A dense T is not supported (its caller keeps the sparse products).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "transport/TransportMatrix.h"

namespace sl {

class TransportGram {
  public:
    /// t: a sparse T with two planes; pairMask: t.rows() bytes, non-zero where a pixel takes
    /// part in pairs; products: also build Q (R's matrix). threads: 0 = all.
    TransportGram(const TransportMatrix& t, std::span<const uint8_t> pairMask, bool products,
                  int threads = 0);
    /// The matrices as built before (a stored copy, io/GramFile.h): cols texels, the seen ones
    /// (ascending, each < cols), P and Q (seen.size() squared each, row-major; q empty: no Q).
    /// std::invalid_argument when the parts do not fit together.
    TransportGram(size_t cols, std::vector<uint16_t> seen, std::vector<double> p,
                  std::vector<double> q);

    /// Multiply-adds a build of P (and Q when products) costs on t: what a caller weighs against
    /// the evaluations it saves.
    static double buildWork(const TransportMatrix& t, std::span<const uint8_t> pairMask,
                            bool products);

    static constexpr size_t kSerialEntries = size_t{1} << 22;

    size_t cols() const { return n_; }
    /// The texels with a row and column in P and Q (T's non-empty columns), ascending.
    std::span<const uint16_t> seen() const { return seen_; }
    bool hasProducts() const { return !q_.empty(); }
    /// The symmetric matrices over seen(), row-major seen().size() squared.
    std::span<const double> pairMatrix() const { return p_; }
    std::span<const double> productMatrix() const { return q_; }

    /// G = Eᵀ·P·E; PE (size cols(), when non-empty) receives P·E. Likewise R with Q (needs
    /// hasProducts()). E: cols() values. Each entry of P·E is its row's dot with E over the
    /// seen texels in four sums (the position mod 4) added as (s0 + s2) + (s1 + s3), and G the
    /// same dot of E with P·E: the same bits on any number of threads.
    double pairForm(std::span<const double> E, std::span<double> PE, int threads = 0) const;
    double productForm(std::span<const double> E, std::span<double> QE, int threads = 0) const;
    /// The same for an E that is zero outside `active` (ascending or not, no repeats): only
    /// the active rows and columns are read, and PE is written on the active texels only.
    double pairFormOn(std::span<const double> E, std::span<const uint16_t> active,
                      std::span<double> PE) const;
    double productFormOn(std::span<const double> E, std::span<const uint16_t> active,
                         std::span<double> QE) const;

    size_t bytes() const { return (p_.size() + q_.size()) * sizeof(double); }

  private:
    size_t n_ = 0, m_ = 0;        // texels; seen texels
    std::vector<uint16_t> seen_;  // m_
    std::vector<int32_t> index_;  // n_: a texel's place in seen_, or -1
    std::vector<double> p_, q_;
    double form(const std::vector<double>& m, std::span<const double> E, std::span<double> ME,
                int threads) const;
    double formOn(const std::vector<double>& m, std::span<const double> E,
                  std::span<const uint16_t> active, std::span<double> ME) const;
};

}  // namespace sl
