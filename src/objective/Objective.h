// The paper's objective (Motegi et al., eq. 1–3) on a luminance image Y (one value per pixel):
//
//   Loss(E) = L_grad(Y) + λ · L_reg
//   L_grad  = S / G,   S = Σ_p M_p,   G = Σ_{pairs} M·(|Y_{x+1,y} − Y_{x,y}| + |Y_{x,y+1} −
//   Y_{x,y}|) L_reg   = mean(E²) over all texels (× channels)              (RegTarget::EnvMap, the
//   paper's)
//           = Σ_p Y_p² / (W·H)                                   (RegTarget::Image, the ablation)
//
// The exact definitions (pair mask, borders, G → 0, |0|, smooth |x|) are documented in
// Objective.cpp's header comment and tested in tests/test_objective.cpp.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "objective/ObjectiveKind.h"
#include "perception/ViewingModel.h"

namespace sl {

enum class RegTarget { EnvMap, Image };

struct ObjectiveOptions {
    double lambda = 30.0;               // the paper's λ (10 for its RGB run)
    RegTarget reg = RegTarget::EnvMap;  // where the L2 regulariser acts
    bool smoothAbs = false;             // |x| ≈ sqrt(x² + ε²) − ε, for quasi-Newton methods
    double smoothEps = 1e-4;            // ε of the smooth |x|, in luminance units
    /// What the defects objective makes large (objective/ObjectiveKind.h DefectMeasure): by
    /// default the worse of the JND's and the visibility ratio's gains over the user's lamp
    /// (raced against JND alone on held-out parts: docs/RESULTS.md "The defects light above the
    /// lamp by both measures").
    DefectMeasure defectMeasure = DefectMeasure::Both;
    /// How the image is seen, for the jnd measure (pixelsPerDegree 0: the caller's default,
    /// e.g. the scene's viewing block).
    ViewingModel viewing{};
    /// The light the `both` measure's gains are over (objective/BothMeasuresObjective.h): the
    /// user's lamp, as E (one value per texel and channel); empty: the studio preset
    /// (app/pipeline/Search.h objectiveOnT). Unused by the other measures.
    std::vector<double> anchorLight;
};

/// The value of the loss and its parts.
struct LossParts {
    double total = 0;      // lGrad + λ·lReg
    double lGrad = 0;      // S / G
    double lReg = 0;       // mean(E²) or mean(Y²), without λ
    double G = 0;          // masked sum of absolute differences
    double S = 0;          // mask size
    bool clamped = false;  // G was below the floor: eq. 2 (Objective.cpp) then has a zero L_grad
                           // gradient; the unbiased loss follows its tangent (UnbiasedObjective.h)
};

class ImageObjective {
  public:
    /// mask: width*height, nonzero = inside M. Throws InputError if the mask is empty or
    /// its size does not match.
    ImageObjective(int width, int height, std::vector<uint8_t> mask, ObjectiveOptions options);

    /// Loss at luminance image Y (width*height) and env map E (any length N).
    /// If dLdY is non-empty (size width*height) it receives dLoss/dY (the L_grad part and, for
    /// RegTarget::Image, the regulariser's part). If dLdE is non-empty (size N) it receives
    /// the regulariser's dLoss/dE (zero for RegTarget::Image). The total gradient with respect
    /// to E is Tᵀ·dLdY + dLdE.
    LossParts evaluate(std::span<const double> Y, std::span<const double> E,
                       std::span<double> dLdY = {}, std::span<double> dLdE = {}) const;

    /// The same loss, templated on the scalar type (double, ceres::Jet, ...), no gradients:
    /// used by autodiff validation. Non-smooth |x| uses the sub-gradient sign(0) = 0.
    template <typename T>
    T value(std::span<const T> Y, std::span<const T> E) const;

    /// dG/dY_p contribution helpers for fused kernels: the signed "difference direction"
    /// s_p = dG/dY_p at Y (size width*height), G returned.
    double gradientSigns(std::span<const double> Y, std::span<double> s) const;

    /// For fused kernels that work on bands of rows: adds dG/dY of the counted pairs whose first
    /// pixel lies in rows [y0, y1) into s and returns their G. Y and s hold rows firstRow..
    /// (Y[0] is pixel (0, firstRow)); rows y0..y1 (inclusive, if inside the image) are read
    /// and written, so they must be held. No checks: the caller guarantees sizes, finite Y.
    double accumulateSignsRows(const double* Y, double* s, int y0, int y1, int firstRow) const;

    /// The loss from the sums a fused kernel accumulates over bands of rows: G and Σ_p Y_p²
    /// (all pixels; used by RegTarget::Image). Fills dLdE as evaluate() does (when non-empty,
    /// size N = E.size()). evaluate() assembles its result here too.
    LossParts fromSums(double G, double sumY2, std::span<const double> E,
                       std::span<double> dLdE) const;

    /// The floor of G (1e-12·S, > 0): below it L_grad is clamped to S/gFloor() and its
    /// gradient is 0 (LossParts::clamped).
    double gFloor() const { return 1e-12 * S_; }
    /// L_grad for a given G (S/G, or S/gFloor() when G < gFloor()).
    double lGrad(double G) const { return G < gFloor() ? S_ / gFloor() : S_ / G; }
    /// The scalar a fused kernel multiplies gradientSigns' s by: dL_grad/dY = lGradScale(G)·s,
    /// i.e. −S/G², or 0 when G < gFloor() (clamped).
    double lGradScale(double G) const { return G < gFloor() ? 0.0 : -S_ / (G * G); }

    /// The env-map regulariser mean(E²) (RegTarget::EnvMap); fills dLdE = 2λ·E/N when it is
    /// non-empty (size N). Shared by every objective that regularises E.
    double envMapRegulariser(std::span<const double> E, std::span<double> dLdE) const;

    /// dLoss/dY of the image regulariser is imageRegScale()·Y: 2λ/(W·H) for RegTarget::Image,
    /// 0 for RegTarget::EnvMap.
    double imageRegScale() const {
        return opt_.reg == RegTarget::Image
                   ? 2.0 * opt_.lambda / (static_cast<double>(width_) * height_)
                   : 0.0;
    }

    int width() const { return width_; }
    int height() const { return height_; }
    const std::vector<uint8_t>& mask() const { return mask_; }
    const ObjectiveOptions& options() const { return opt_; }
    double maskSize() const { return S_; }

  private:
    int width_, height_;
    std::vector<uint8_t> mask_;
    ObjectiveOptions opt_;
    double S_ = 0;

    // Throws std::invalid_argument unless Y has width*height entries and E suits the
    // regulariser (non-empty for RegTarget::EnvMap). `who` names the calling function.
    void checkSizes(size_t nY, size_t nE, const char* who) const;
};

/// Intersection of two masks (both width*height).
std::vector<uint8_t> intersectMasks(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b);

}  // namespace sl

#include "objective/Objective_impl.h"  // value<T> and the pair traversal shared with Objective.cpp
