// Defect visibility on two independent half-sample images (the judge's per-region scores).
//
// Given Y_a, Y_b (two unbiased estimates of the same image from disjoint samples) and a label
// image (one value per defect kind, 0 = no defect), for every label v:
//
//   R_v      = part pixels labelled v;   F = part pixels farther than kCleanMargin pixels
//              (Chebyshev) from every labelled pixel: the defect-free surface (with a
//              reference region given: only its pixels, the defects objective's reference)
//   g²(X)    = Σ_{pairs p,q ⊂ X} (Y_a,q − Y_a,p)·(Y_b,q − Y_b,p) / #pairs(X)   (x and y neighbours)
//              an unbiased estimate of the mean squared noise-free gradient in X
//   rms(X)   = sqrt(max(g²(X), 0))
//   visibility_v = rms(R_v) / rms(F)       1.0: the defect is no more salient than the texture
//   contrast_v   = rms(R_v) / mean Ȳ over the part: the region's gradient relative to the
//              image's brightness (a ratio of two tiny gradients can make visibility_v large
//              under a light that shows nothing: under uniform light contrast_v is ~1e-3)
//   weber_v  = (mean Ȳ over R_v − mean Ȳ over B_v) / mean Ȳ over B_v,  Ȳ = (Y_a + Y_b)/2,
//              B_v = the unlabelled part pixels within kWeberRing pixels of R_v (its local
//              background)
//   jnd_v    with a viewing model: the region's visibility in just-noticeable differences over
//            F's texture (perception/JndVisibility.h), with the band it is seen in and the
//            texture's masking contrast
//
// Values that cannot be formed (no pairs, zero denominators) are NaN (JSON null).
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "core/RegionLabel.h"
#include "perception/ViewingModel.h"

namespace sl {

inline constexpr int kCleanMargin = 2;  // px between a defect and the "defect-free" surface
inline constexpr int kWeberRing = 4;    // px of local background around a region

struct RegionVisibility {
    RegionLabel label;
    size_t pixels = 0;            // part pixels with this label
    double rmsGradient = 0;       // rms(R_v), luminance per pixel
    double cleanRmsGradient = 0;  // rms(F)
    double visibility = 0;        // rms(R_v) / rms(F)
    double contrast = 0;          // rms(R_v) / mean brightness of the part
    double weber = 0;             // Weber contrast against the local background
    double jnd = std::numeric_limits<double>::quiet_NaN();           // NaN: no viewing model given
    double jndFrequency = std::numeric_limits<double>::quiet_NaN();  // c/deg it is seen at
    double maskContrast =
        std::numeric_limits<double>::quiet_NaN();                 // the texture's RMS band contrast
    double luminance = std::numeric_limits<double>::quiet_NaN();  // cd/m², the part's mean
};

class BandFilterBank;

/// How the JND is seen: the viewing model and the image value shown at the display's white
/// (the white furnace's mean over the part); `bank`: the band filters built once for this part
/// (perception/BandFilters.h; the judge's bootstrap replicates share one), or null (built here).
struct JndViewing {
    ViewingModel view;
    double white = 0;
    const BandFilterBank* bank = nullptr;
};

/// Per-label visibility. labels: width*height label image (image space); partMask: nonzero
/// on the part. Labels present in `labels` but missing from `legend` are scored as
/// "label-<v>"; legend entries with no pixel are reported with pixels = 0 and NaN scores.
/// reference: nonzero where F may lie (empty: the whole part). viewing: also the JND.
std::vector<RegionVisibility> defectVisibility(int width, int height, std::span<const double> Ya,
                                               std::span<const double> Yb,
                                               std::span<const uint8_t> partMask,
                                               std::span<const uint8_t> labels,
                                               const std::vector<RegionLabel>& legend,
                                               std::span<const uint8_t> reference = {},
                                               const JndViewing* viewing = nullptr);

/// All regions as one: the RMS gradient over every region's pixels over the clean surface's,
/// sqrt(Σ pixels·visibility² / Σ pixels) over the regions with pixels and a finite visibility
/// (the clean RMS gradient is shared). NaN when there is none.
double combinedVisibility(std::span<const RegionVisibility> regions);
/// The regions' contrast pooled the same way (the defects' RMS gradient over the mean
/// brightness). NaN when there is none.
double combinedContrast(std::span<const RegionVisibility> regions);
/// The regions' JND as one: their Minkowski sum (exponent kJndPooling, probability summation:
/// several regions each at threshold are seen more surely than one). NaN when there is none.
double combinedJnd(std::span<const RegionVisibility> regions);
/// The defects' JND as the answer reports it: the least visible kind's (the least JND of the
/// regions with pixels and a finite JND). Every kind of defect must be seen, so a light is as
/// good as the kind it shows least; the defects objective maximizes a soft-min of the same
/// (objective/JndObjective.h). `which`, when given, receives that region's index. NaN when
/// there is none.
double leastVisibleJnd(std::span<const RegionVisibility> regions, size_t* which = nullptr);

}  // namespace sl
