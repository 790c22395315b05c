// The defect map's `lay` method (detect/DefectMap.h's method table): a texture model learned
// from the part itself, for measured textures whose own structure (striae of a bullet land,
// periodic laser lines) the `auto` method marks as defects.
//
// Why (scripts/eval-real's overlays, DEV insertion seeds 101–102, model A): on the five measured
// textures `auto` marks 3–30× more than the inserted truth. Its robust σ comes from the quiet
// majority of the map, so the texture's own heavy tail (striae the notch cannot model because
// they wander, particles, a land's shoulders, a rough patch) stands at 5–15σ, as high as the
// inserted defects; and its texture-change step paints wide blocks along the borders.
//
// Steps (h the heights, W×H, row-major; each parameter a field of LayMapOptions):
//  1. Lay: the texture's dominant direction t, from the structure tensor J = Σ g·gᵀ of the
//     central-difference gradients g of h smoothed by a Gaussian of σ = 1.5 samples (waves a
//     few samples long would tilt it: their differences are damped unequally along x and z),
//     over the samples outside `border`, each g scaled down to
//     at most the `clipQuantile` quantile of |g| (so a few deep defects do not choose the
//     direction). t is normal to the dominant gradient direction: the mode of the clipped
//     gradients' doubled angles (weights |g|², 720 bins smoothed by a Gaussian of 6 bins; the
//     tensor's mean direction is tilted by degrees by one long deep scratch across the lay);
//     J's coherence (λ₁ − λ₂)/(λ₁ + λ₂) is reported.
//  2. Background: B = the median of h along t over `layLength` samples centred on the sample
//     (bilinear, positions mirrored into the map). A stria, a line of a periodic lay, a land's
//     shoulder runs along t and is its own background; a pit, a particle and a scratch that
//     crosses the lay are not. A scratch within a few degrees of the lay is lost with it.
// 1b–2 for curved lays (fieldSigma > 0; off by default): the method runs once as above, then
//     again with a local lay field: the clipped tensor's components (jxx − jzz, 2jxz, jxx + jzz)
//     of every sample, zero on the first pass's marks grown by `fieldExclude` samples (a deep
//     scratch across the lay would turn the field along itself and become its own background),
//     smoothed by a Gaussian of σ = fieldSigma; t at a sample is the smoothed tensor's minor
//     eigenvector, or the global lay where its coherence is below `fieldCoherence`. B is then
//     the median along the streamline of t through the sample (unit steps each way, the
//     direction re-read at the nearest sample and kept pointing forward), which follows a
//     face mill's arcs where a straight line leaves them. With layPasses > 1, steps 1–2 are
//     repeated on h − B (a second lay crossing the first). Measured (DEV insertion seeds 101,
//     both models, with layLength 161 and levelWindow 81): the Wyko arcs' recall 0.49/0.61 →
//     0.69/0.93 (models A/B); a second pass lost scratches (periodic lines, model A, recall
//     0.74 → 0.54) and stays off.
//  3. Residual: r = (h − B) minus its separable running median over `levelWindow` samples
//     (detect/ImageFilters.h separableRunningMedian), σ = 1.4826 × median |r| over the samples
//     outside the border.
//  4. Regions: 8-connected regions of |r| ≥ growSigma·σ (outside the border) are kept when they
//     reach seedSigma·σ, hold at least `minRegion` samples, and
//     (a) their peak |r| is at least `textureRms` × the RMS of d = h − the separable running
//         median of h over `macroWindow` samples (outside the border): the texture's own
//         roughness. σ measures the quiet majority; a measured texture's tail (particles,
//         wandering striae) lies above many σ but not above its own RMS by much;
//     (b) with `dropBorderRegions`, they do not reach the border's inner line: a region there
//         continues outside what the map can judge (a land's shoulder, a rough patch, the
//         edge of a logo) and is never marked as a block along the border. Such a region is
//         first split once more: its samples with |r| ≥ max(growSigma·σ, borderRegrow ×
//         the threshold of (a)) form sub-regions, judged by the same rules, and those that do
//         not reach the border are kept. On a smooth land σ is tiny, and growth at growSigma·σ
//         links a deep defect to the land's shoulders through the land's own fine texture.
// Every threshold is relative to σ or to the RMS of d, so the map is invariant to h → a·h + b
// (a ≠ 0) up to rounding; a constant map marks nothing.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace sl {

struct LayMapOptions {
    int layLength = 81;             // samples of the median along the lay (odd, >= 3)
    double clipQuantile = 0.95;     // gradients clipped at this quantile of |g| (in (0, 1])
    double fieldSigma = 0;          // σ (samples) of the local lay field's tensor (>= 0; 0: one
                                    // lay for the map)
    double fieldCoherence = 0.1;    // below this local coherence, the global lay (in [0, 1])
    int layPasses = 1;              // the lay taken out this many times (>= 1; the second
                                    // pass, on the residual, takes out a crossing lay)
    int fieldExclude = 4;           // the field leaves out the first pass's marks grown by this
                                    // many samples (>= 0)
    int levelWindow = 31;           // samples of the residual's running median (odd, >= 3)
    int macroWindow = 61;           // samples of the running median d is taken about (odd, >= 3)
    double seedSigma = 6.0;         // a region reaches |r| >= seedSigma·σ (> 0)
    double growSigma = 3.0;         // and holds |r| >= growSigma·σ (0 < grow <= seed)
    double textureRms = 1.5;        // its peak |r| >= textureRms × RMS of d (>= 0; 0: off)
    int border = 40;                // samples at the map's edges never marked (>= 0)
    int minRegion = 12;             // smallest region kept, samples (>= 1)
    bool dropBorderRegions = true;  // regions reaching the border's inner line are dropped
    double borderRegrow = 0.5;      // ... after a second split at this × the texture-RMS threshold
                                    // (in [0, 1])
};

struct LayMap {
    std::vector<uint8_t> map;   // width*height: 255 marked, 0 not
    double layX = 1, layZ = 0;  // the lay direction t (x = column, z = row), unit length
    double coherence = 0;       // of the clipped structure tensor
    double sigma = 0;           // σ of the residual r (height units)
    double textureRms = 0;      // RMS of d (height units)
    size_t regions = 0;         // regions kept
    size_t droppedShallow = 0;  // regions dropped by (a)
    size_t droppedBorder = 0;   // regions dropped by (b)
};

/// Throws InputError naming the option for a bad value.
void checkLayMapOptions(const LayMapOptions& o);

/// The lay method's map of a width×height height map (finite heights; the caller checks).
LayMap detectLayDefects(std::span<const float> heights, int width, int height,
                        const LayMapOptions& o = {});

}  // namespace sl
