// TransportMatrix T: for a fixed scene, camera and set of samples, the image is linear in the
// env map, I = T·E (docs/DESIGN.md "The one idea"). One row per pixel, one column per env-map
// texel.
//
//   channels == 1 ("gray T"): each entry is the luminance Y of the paths' RGB throughput times
//                 the texel's bilinear weight, so Y(I) = T·E for a gray E.
//   channels == 3 ("RGB T"): three blocks T_r, T_g, T_b that share one sparsity pattern (the
//                 same paths fill them), stored as interleaved r,g,b values per entry:
//                 I_c = T_c·E_c. Luminance Y = Σ_c lum_c·T_c·E_c; a gray E drives all three.
//
//   planes == 2 ("halves"): the samples of each pixel form two independent sets (see
//                 RenderOptions::sampleSets) and each entry holds both half-matrices, T_a and
//                 T_b (each an unbiased estimate on its own, so T = (T_a + T_b)/2), values laid
//                 out [a: channels..., b: channels...]. One shared sparsity pattern: the halves
//                 cost (2 + 8·ch) bytes per entry instead of (2 + 4·ch) for T alone, less than
//                 two separate matrices (whose patterns overlap). Products take a `plane`:
//                 0 = T_a, 1 = T_b, kMeanPlane = T.
//
// Storage: CSR with 16-bit column indices (at most kMaxTransportTexels texels) and float32 values
// (rows were accumulated in double), or dense row-major float32 — whichever takes fewer bytes for
// the measured density (see chooseStorage). Products accumulate in double.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace sl {

enum class TransportStorage { Sparse, Dense };

/// The most env-map texels a transport matrix has columns for: CSR column indices are 16-bit.
/// The scene file's envmap.width × envmap.height is held to it (io/SceneFile.h).
inline constexpr int kMaxTransportTexels = 65536;

struct TransportMatrix {
    int width = 0, height = 0;        // image
    int envWidth = 0, envHeight = 0;  // env-map texel grid
    int channels = 1;                 // 1: gray (luminance) T; 3: RGB T
    int planes = 1;                   // 1: T; 2: the halves T_a, T_b
    TransportStorage storage = TransportStorage::Sparse;
    std::vector<uint64_t> rowPtr;     // sparse: rows()+1
    std::vector<uint16_t> colIdx;     // sparse: nnz
    std::vector<float> values;        // sparse: nnz*stride(); dense: rows*cols*stride()
    std::vector<uint8_t> objectMask;  // rows(): 1 where every camera sample hit the part
    int threads = 0;                  // products: worker threads (0 = all)

    static constexpr int kMeanPlane = -1;
    int stride() const { return channels * planes; }  // floats per entry
    size_t rows() const { return static_cast<size_t>(width) * height; }
    size_t cols() const { return static_cast<size_t>(envWidth) * envHeight; }
    size_t nnz() const;  // stored non-zero entries (dense: rows*cols)
    double density() const;
    size_t bytes() const;  // bytes of the arrays a product streams through

    /// Y = luminance of T·E, size rows(). E: cols() values (gray) or 3·cols() (RGB,
    /// interleaved per texel; requires channels == 3).
    void applyLuminance(std::span<const double> E, std::span<double> Y,
                        int plane = kMeanPlane) const;
    /// RGB image I = T·E (interleaved, 3·rows()); requires channels == 3.
    void applyRgb(std::span<const double> E, std::span<double> rgb) const;
    /// out = dLoss/dE given g = dLoss/dY (size rows()): out = Tᵀ·g for a gray E
    /// (out.size() == cols()), or lum_c·T_cᵀ·g per channel for an RGB E (3·cols()).
    void applyTransposeLuminance(std::span<const double> g, std::span<double> out,
                                 int plane = kMeanPlane) const;

    /// For halves (planes == 2): Ya = lum(T_a·E), Yb = lum(T_b·E) in ONE pass over T, and
    /// out = T_aᵀ·ga + T_bᵀ·gb (luminance-weighted per channel for an RGB E) in one pass: the
    /// noise-unbiased objective's products at the cost of one streaming read each.
    void applyLuminanceHalves(std::span<const double> E, std::span<double> Ya,
                              std::span<double> Yb) const;
    void applyTransposeLuminanceHalves(std::span<const double> ga, std::span<const double> gb,
                                       std::span<double> out) const;

    /// Sequential kernels over rows [r0, r1), the building blocks of the products (and of fused
    /// kernels). Arrays are indexed relative to r0: Y[r − r0], g[r − r0]. rgbE: E holds 3
    /// values per texel (needs channels == 3). accumulateTransposeRows ADDS into out.
    void applyLuminanceRows(const double* E, bool rgbE, double* Y, size_t r0, size_t r1,
                            int plane = kMeanPlane) const;
    void accumulateTransposeRows(const double* g, bool rgbE, double* out, size_t r0, size_t r1,
                                 int plane = kMeanPlane) const;

    /// Convert between storages (used by chooseStorage and tests).
    void toDense();
    void toSparse();
};

/// The same image, env-map grid, channels and planes (rows and columns mean the same things).
bool sameShape(const TransportMatrix& a, const TransportMatrix& b);
/// A sparse T of `shape`'s image, grid, channels and planes with no entries yet: rowPtr all 0
/// (rows() + 1), objectMask all 0; the rows are appended in order by the caller.
TransportMatrix emptySparseOfShape(const TransportMatrix& shape);

/// Picks the storage that takes fewer bytes for T's measured density and converts T to it.
void chooseStorage(TransportMatrix& t);

/// One sequential read over T's arrays (a checksum-like reduction), the reference a product's
/// time is compared with in benchmarks. Returns a value so the read is not optimised away.
double streamingRead(const TransportMatrix& t);

}  // namespace sl
