// The defect map: which samples of a height map are anomalies (scratches, gouges, dents, burrs,
// steps, chatter bands) rather than the regular machining texture, found WITHOUT labels. The
// result lives in height-map space (255 marked, 0 not), as the truth masks of gen-surface do.
//
// Methods (one table, core/Registry.h; `defectMethodTable()`):
//   auto   (default) model the nominal surface as macro shape + periodic tool-path texture and
//          mark what that model cannot explain (below) -- on a machined part as a simulator
//          or a generator makes it. On a measured texture (DefectMapOptions::measured: the
//          height map came from an instrument, or its scene says so) it is the selfsim
//          method: an instrument sees more than the tool path (a bullet land's striae, torn
//          patches, particles, a laser-line pattern), which this model does not explain and
//          marks by the fifth of the map (17-40 % of the five instrument files, defects of
//          known shape inserted: precision 0.01-0.15); selfsim marks 1-5 % at a median
//          precision of 0.5-0.6. No statistic of the map alone told the two apart on the
//          parts of two generators and the five files (the notched bins' share, the texture's
//          share of the relief, the residual's quantiles and seed share each overlapped; docs/
//          RESULTS.md), so the rule is the map's origin, which the user knows;
//   lay    a texture model learned from the part itself, for measured textures:
//          detect/LayMap.h (the median along the texture's lay, thresholds against the
//          residual's robust σ and the texture's RMS, no regions along the border);
//   selfsim what the texture does not repeat: detect/SelfSimMap.h (each sample's copies at
//          the texture's own offsets, their median its background, a-contrario tests on the
//          residual at several scales and against the tail of the map's own regions);
//   paper  the paper's scratch map, detect/ScratchMap.h computeScratchMap with
//          DefectMapOptions::paper (patches whose detrended range is large).
//
// `auto`, step by step (h the heights, W×H, row-major; float storage, double sums). Each
// parameter is a field of DefectMapOptions, documented once, there.
//  1. Macro shape: M = the separable running median of h over `macroWindow` samples, along x
//     (rows) then along z (columns); windows shrink at the borders. A median keeps monotone
//     shapes (a pocket wall, a step) and drops what is narrower than half the window (the tool
//     marks, scratches, dents, burrs). d = h − M.
//  2. Pad: d is extended by `pad` samples on every side to the next size whose only prime
//     factors are 2, 3 and 5, the extension a mirror image of the map cross-faded from the far
//     border's mirror to the near border's, so the FFT's periodic extension has no jump.
//  3. Texture (spectral notch): F = the 2-D FFT of the padded d (real-to-complex, Eigen's
//     kissfft). The background of each bin is B = max(med_x, med_z, med_r) of |F|: running
//     medians of `spectrumWindow` bins along each frequency axis (periodic along k_z, clamped
//     along k_x) and, with `radial`, along the ray from DC through the bin (Hermitian symmetry
//     across k_x = 0), all on |F| pooled 2×2 with half the window, read back at the bin's cell.
//     An isolated peak (a lattice component of the tool path, a ring's arc) stands above all
//     three; a straight feature of the map (scratch, groove, step, wall, burr line) puts its
//     energy on a ray through DC and is its own background along it, as is a long line along
//     an axis (a feature along the other axis over the whole map). A bin with
//     |F| > notchRatio·B outside the radius `keepLowBins` around DC is texture, and so is a bin
//     within `notchSpread` bins (box) of one with |F| > notchGrow·B (the leakage around a
//     peak). Texture bins are shrunk to B, phase kept. T = the inverse FFT of F minus the shrunk
//     spectrum, cropped: the periodic texture. R = d − T. With passes > 1, step 1 is repeated on
//     h − T and steps 2–3 on the new d.
//  4. Level: A = R − the separable running median of R over `levelWindow` samples (x, then z).
//     With `levelWiener`, the score (step 6) and the line valleys (7a) take A + Δ, Δ = the
//     inverse FFT of F·(B²/|F|² − B/|F|) over the notched bins: there the level holds the
//     Wiener estimate F·B²/|F|² of what is not texture instead of B with the texture's phase.
//     That phase is the texture's, so over a lattice's harmonics the shrunk bins add up to a
//     faint copy of the lattice (a phase-only reconstruction: about 12 % of a flat-end
//     step-over ridge, twice that where the lattice meets the map's edges and the padding),
//     which stands out where σ_A is small (feed marks the notch removes whole); the Wiener
//     estimate leaves B/|F| of that. σ_A (step 6) and step 8 keep A: the Wiener estimate is
//     smaller than what it estimates, B is the background's magnitude.
// 4a. Steps (with `stepModel`): a tool-change step is a sharp jump between two plateaus, which
//     the notch and the running medians of steps 1 and 4 smear over a band several samples
//     wide (the level term marks the band; the step itself is its 2-sample ramp). On
//     G = h − T (= M + R), for each of 4 directions u (x, z, both diagonals) the jump
//     J_u = the + side's value minus the − side's, each side's heights at offsets 2 … 2m+1
//     along u (m = stepWindow/2) taken as two means of m samples extrapolated linearly to the
//     sample; Z = max over u of |J_u| / (1.4826 median |J_u|). A centre point is a sample with
//     Z ≥ `stepSigma` where, along the detector direction nearest G's gradient there (Sobel,
//     minus the slope over ±6 samples) and J of the same sign, the 2-sample rise
//     g = G(q+u) − G(q−u) is a local maximum (non-maximum suppression), at least
//     `stepSharpness` × the larger of |J_u| and max |J| and × the rise over ±(stepWindow/2+1)
//     samples (a wall rises over many), and the medians of the two sides' 2m samples differ by
//     at least `stepPlateau` × that jump (a bump comes back: a ridge the notch left). Centre
//     points linked within 3 samples form lines; lines of fewer than `stepMinLength` points are
//     dropped. A point's position is refined along u by a parabola through g (± half a sample),
//     its normal is the minor axis of the line's points within 6 samples, toward the high side.
//     After step 7, within `stepBand` samples of a line the map is the step's ramp alone: the
//     samples whose distance t along the nearest point's normal lies in (−stepRampHalf,
//     stepRampHalf) (with stepRampMoved > 0 the high side stops where a smoothstep ramp
//     2·stepRampHalf wide has moved the surface by that share of the jump). A line whose points
//     lie on a circle (Kåsa's fit, RMS distance ≤ 0.75 samples, radius ≤ 4× the map's larger
//     side: a ring-shaped step, a tool change on a turned part) takes every line's points
//     within 1.5 samples of it, and the arcs between consecutive ones up to `stepGap` samples
//     long get points every half sample (normal along the radius): where a steep wall crosses
//     the ring, the centre tests fail and the level term's smear would stay.
// 4b. Rings (with ringWindow > 0): a rotational texture (turned, faced: grooves on circles or
//     an Archimedean spiral about a centre) is tested for and, where found, modelled by its
//     periodic radial profile. The centre c: each 16×16 block of d's structure tensor gives the
//     line through the block along its dominant gradient (a ring's radius); c = the point
//     nearest all of them, least squares weighted by the blocks' coherence², then 6
//     Cauchy-reweighted rounds (scale 32 samples); it may lie outside the map. `isotropy` =
//     λ_min/λ_max of Σ w·t·tᵀ (t the lines' normals): ≈ 0 for parallel paths. The pitch p: the
//     period of the bin of most gradient power |k|²·|F|² (F the spectrum of step 3, taken from its
//     notch pass) among periods < macroWindow/2. The arc median at a point: the median of d along
//     the spiral of constant r − s·p·φ/2π through it, `ringWindow` samples of arc (bilinear), s =
//     ±1 the hand that leaves the smaller mean |d − arc median| 10–120 samples from c. The
//     decision: ρ = median |d − arc median| / median |d| over a grid on the map; rings are used
//     when isotropy ≥ `ringIsotropy` and ρ ≤ `ringResidual`. The ring texture at a sample, P, is
//     the median of the arc medians through it and through the points 3 pitches further out
//     and in on its radius (the same phase of the spiral on other grooves): a ring-shaped
//     change of level (a step) differs between them and stays out of P, as does a defect
//     along a groove (a scratch tangent to the rings) narrower than 3 pitches. Where |A| ≥
//     growSigma·σ_A and A_ring = d − P has |A_ring| ≤ ringRatio·|A|, A takes the value A_ring
//     (no smaller in magnitude than the median of |A|, so σ_A of step 6 is unchanged): the
//     texture the notch left where the rings curve strongly (around the centre) and where
//     they meet the padding is explained; a dent, a scratch across the rings, a step are not.
//     With `ringRepass`, where the rings are used, steps 1–3 are done once more (before 4a) with
//     the macro shape the running median of h − T (T of the first pass; the fit is kept, A is
//     taken from the new R and d): where the macro window straddles a corner of the macro
//     shape (a pocket wall's foot or top) the wall's samples all lie on one side of the
//     texture beside it, so the median of h is a high (low) quantile of that texture, not its
//     middle, and d keeps a band of that bias along the corner which the level term marks (the
//     turned part's wall foot: 0.8 µm, 3.4–4σ_A). h − T has little texture to take a quantile of.
//  5. Edges: N = (M + R) − its separable quadratic Savitzky–Golay fit over `edgeWindow` samples
//     (x, then z; borders mirrored): a step or a narrow groove, but not a curved wall whose
//     curvature changes little over the window. With `edgeAxes`, two residuals instead:
//     N_x = (M + R) − its fit along x alone, N_z = the same along z alone. What the texture
//     model leaves of a directional texture (the flat-end floor's feed marks, 5 samples apart
//     along the feed) raises the residual along the axis it varies on; a step parallel to the
//     marks varies on the other axis and is scored against that axis's quieter σ. With
//     `edgeRobust` (and edgeAxes) each axis's fit is taken again without the samples of its
//     window whose least-squares residual is ≥ seedSigma × its σ (1.4826 × median): a least-
//     squares fit is pulled toward a narrow groove or lip and leaves its neighbours a residual
//     of the opposite sign, about 0.29 × the depth for a one-sample groove at the default
//     window, which marked a one-sample halo around every scratch and burr; what alone would
//     seed the map is not evidence about the surface around it. A sample keeps its least-
//     squares residual where no sample of its window is left out, or fewer than 4 remain.
//  6. Scale: σ_A, σ_N = 1.4826 × the median of |A|, |N| (over ≤ 4M samples at a fixed stride),
//     each at least 1e-3 × 1.4826 × the median of |h − mean h| (so rounding on a noise-free
//     texture is no anomaly); with `edgeAxes` σ_Nx and σ_Nz the same of |N_x| and |N_z|. The
//     score is S = max(|A|/σ_A, edgeWeight·|N|/σ_N) (with `edgeAxes`, edgeWeight times the
//     larger of |N_x|/σ_Nx and |N_z|/σ_Nz in place of |N|/σ_N), 0 within `border` samples
//     of the map's edges (there the notch's periodic model meets the padding and is unreliable).
//  7. Hysteresis: samples with S ≥ `seedSigma` seed the map; it grows into 8-connected samples
//     with S ≥ `growSigma`. Connected regions of fewer than `minRegion` samples are dropped.
// 7a. Lines (lineLength > 0), before 7: a scratch is a long, straight, narrow groove, lower
//     than the surface on both sides. For K = `lineOrientations` directions θ = πk/K, L_θ = the
//     mean of A over a digital segment of about `lineLength` samples along θ (one running sum
//     per sheared line), and V_θ = min(L_θ(p + o·n) − L_θ(p), L_θ(p − o·n) − L_θ(p)) / σ_θ
//     (n the normal, o = `lineOffset` rounded to samples, σ_θ = 1.4826 × the median of both
//     differences' magnitudes); V = max over θ of V_θ, 0 within `border`. Regions of V ≥
//     `lineGrowSigma` (8-connected) that reach `lineSeedSigma` seed step 7 and are grown
//     through (their S is raised to seedSigma). Averaging along the line lifts a faint groove
//     out of the noise; the two-sided test keeps out what is straight but not a groove: a
//     raised line (the flat-end floor's step-over ridges, which the notch leaves in part) or a
//     step (lower on one side only).
// 7b. The texture's own tail (seedTail > 0; 1.5 by default since 2026-11-28, with the wide
//     changes below): a measured or ground texture is not a stationary Gaussian
//     field: the tool marks, striae and particles the notch cannot model leave a residual whose
//     tail is far heavier than a Gaussian's (on a bullet land, S ≥ 5.5 on a fifth of the map),
//     so thresholds in robust σ mark the texture itself. Let q = the seedTailQuantile quantile
//     of S over the samples outside the border (V for step 7a); the seed threshold becomes
//     max(seedSigma, seedTail·q), the grow threshold is scaled by the same factor, or with
//     growTail > 0 it is max(growSigma, growTail·q) (never above the seed): the tail sets how
//     high a defect must stand to seed; how far it grows is a lower share of the same tail. On a
//     Gaussian residual q_0.99 = 2.6 σ and 1.5·q = 3.9 < 5.5: nothing changes; what the map is
//     for (an inserted defect covers ~1 % of the map) stays above it, being far deeper than
//     the texture's tail. The quantile is taken per tile (seedTailTiles × seedTailTiles) and
//     q is the median of those: a defect is in few tiles, a texture's tail in all. Step 8's
//     threshold on E is raised the same way (to seedTail × E's tail, per tile). A texture
//     change is not in few tiles: a turned part's chatter ring, 27-42 % of the map on some
//     seeds, lies in most tiles and was its own tail (its E and S the tiles' quantiles), so the
//     tail lost it whole. So with seedTailWide > 0 the wide changes, step 8's regions at its own
//     ratios (of any of its tests, on the pooled grid) that hold at least seedTailWide × a
//     tile's samples, are left out of every tail (of S, V and E; a tile with fewer than half of
//     its samples left is left out) and marked by step 8 at its own ratio; a clean ground
//     texture's clusters of deep tracks are far smaller than a tile.
//  8. Texture-change regions (chatter bands): E = the separable running median of |A| over
//     `energyWindow` samples (on |A| pooled 2×2 with half the window, read back at the sample's
//     cell): a robust local amplitude of what the texture model left. Samples with
//     E ≥ energyRatio × median(E), outside the border, are marked too (a scratch or a dent fills
//     less than half a window and does not raise E). With `textureEnergy` the same on |T| with
//     `textureEnergyRatio`: where the tool-path texture itself is locally much stronger (a band
//     of chatter at the texture's own frequencies, which the notch took into T). With
//     textureSectors = K > 1, T is split by the orientation θ = atan2(k_z, k_x) of its bins
//     into K sectors of π/K (sector 0 centred on the k_x axis; their sum is T) and each part is
//     tested against its own median: a chatter band varying along the path stands out in its
//     sector even where the scallops across the paths, in another, are stronger than it.
//     With `energyGrowBorder`, each test's marks then grow outward into the border, layer by
//     layer: a sample at distance j from the map's nearest edge (j < border) joins when an
//     8-neighbour at distance j + 1 is marked by the same test and its own E passes; for |A| the
//     threshold there is raised by the excess of the median of E along the sample's pooled row
//     (top and bottom border; column for left and right, the larger in a corner) over
//     median(E). A band crossing the map's edge is then marked up to it, while the border alone
//     marks nothing: the notch's leftover at the edges lies in A (on the ball-end part, E of
//     |A| is 1.5–2.2× median(E) along the outer rows, its peaks above 3×), as a function of the
//     distance to the edge, nearly constant along it; T does not carry it.
// Every threshold is relative to σ or to median(E), so the map is invariant to h → a·h + b
// (a > 0) up to rounding, and for a < 0 except for step 7a, which looks for grooves (a < 0
// turns them into ridges); a constant map marks nothing. A confined region of different texture
// (gen-surface's chatter half, 40 % of a part) is NOT meant to be marked: it is a state of
// the process over a large region, not a local anomaly, and comparing regions is the defects
// objective's job. It stays unmarked while its amplitude stays under the ratios of step 8 (the
// test parts' 0.5 µm chatter does, mostly: the README gives the share marked); a stronger one
// is marked as a texture change. Parallel over rows and columns with TBB; the result does not
// depend on the thread count. Memory: about 12 float copies of the map; with textureSectors
// K > 1, K more and a copy of the half spectrum while they are made; step 4a about 10 more
// while the steps are found; step 4b one more copy (two while the repass runs); step 7a 2
// more while it runs; with levelWiener one more (Δ) and a copy of the half spectrum while Δ is
// made; step 8 a quarter copy per test (its pooled E; 1 + K with textureSectors K > 1, made
// before step 7 and kept to the end, one more full copy while the first is made) and a byte
// per sample while each test marks.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/RegionLabel.h"
#include "detect/LayMap.h"
#include "detect/ScratchMap.h"
#include "detect/SelfSimMap.h"

namespace sl {

enum class DefectMethod { Auto, Lay, SelfSim, Paper };

struct DefectMethodRow {
    DefectMethod value;
    const char* name;
    const char* help;
};

std::span<const DefectMethodRow> defectMethodTable();
/// The method named `name`; InputError naming `where` and listing the table otherwise.
DefectMethod parseDefectMethod(std::string_view name, const std::string& where = "method");
const char* defectMethodName(DefectMethod method);

struct DefectMapOptions {
    DefectMethod method = DefectMethod::Auto;
    // auto (see the steps above)
    int macroWindow = 61;       // samples of the macro shape's running median (odd, >= 3)
    int passes = 1;             // macro + notch passes (>= 1)
    int pad = 100;              // samples of mirror extension on each side (>= 0)
    int spectrumWindow = 121;   // bins of the spectral background's running medians (odd, >= 3)
    bool radial = true;         // the background includes the radial median (see step 3)
    double notchRatio = 4.0;    // |F| > notchRatio·B is texture (> 1)
    int notchSpread = 4;        // bins around a notched bin that may join it (>= 0)
    double notchGrow = 1.5;     // ... when |F| > notchGrow·B (0 < grow <= notchRatio)
    int keepLowBins = 2;        // bins around DC never notched (>= 0)
    bool levelWiener = true;    // step 4: the score's level takes the notched bins' Wiener
                                // estimate F·B²/|F|², not B with the texture's phase
    int levelWindow = 31;       // samples of the level's running median (odd, >= 3)
    int edgeWindow = 7;         // samples of the edge residual's quadratic fit (odd, >= 5)
    double edgeWeight = 1.0;    // the edge residual's weight in the score (>= 0; 0: off)
    bool edgeAxes = true;       // one edge residual per axis, each with its own σ (step 5)
    bool edgeRobust = true;     // with edgeAxes: the fits leave out what alone seeds (step 5)
    double seedSigma = 5.5;     // hysteresis: seeds at S >= seedSigma (> 0)
    double growSigma = 2.5;     // hysteresis: grown into S >= growSigma (0 < grow <= seed)
    int border = 40;            // samples at the map's edges never marked (>= 0)
    int minRegion = 12;         // connected regions smaller than this are dropped (>= 1)
    int energyWindow = 41;      // samples of the local amplitude's running median (odd, >= 3;
                                // 0 switches step 7 off)
    bool textureEnergy = true;  // step 8 also on |T| (a band of stronger tool-path texture)
    double textureEnergyRatio = 4.0;  // ... with this ratio (> 1)
    int textureSectors = 2;           // ... on T split into this many orientation sectors of
                                      // its spectrum, each against its own median (1: T whole)
    double energyRatio = 2.0;         // E >= energyRatio·median(E) is a texture change (> 1)
    bool energyGrowBorder = true;     // step 8's marks grow outward into the border
    bool stepModel = true;            // step 4a: find sharp steps, mark their ramps alone
    int stepWindow = 11;              // ... 2m+1: each side's 2m samples (odd, >= 3)
    double stepSigma = 2.5;           // ... a centre point's Z (> 0)
    double stepSharpness = 0.5;       // ... its 2-sample rise over the jump (in (0, 1])
    double stepPlateau = 0.35;        // ... its sides' medians' difference over the jump (> 0)
    int stepMinLength = 60;           // ... samples of a connected centre line (>= 1)
    double stepRampHalf = 1.0;        // ... samples marked within this of the centre (> 0)
    double stepBand = 8.0;            // ... and nothing else within this (>= stepRampHalf)
    double stepRampMoved = 0.02;      // ... on the high side, only where the ramp has moved
                                      // the surface by this share of the jump ([0, 0.5))
    double stepGap = 200.0;           // ... arcs of a circular step up to this long between
                                      // its points are filled (samples; >= 0, 0: off)
    int ringWindow = 61;              // step 4b: samples of arc of the ring median (0: off;
                                      // else odd, >= 3)
    double ringIsotropy = 0.25;       // step 4b: rings need isotropy >= this (in [0, 1])
    double ringResidual = 0.5;        // ... and ρ <= this (> 0)
    double ringRatio = 0.5;           // step 4b: A_ring replaces A when |A_ring| <= this·|A|
                                      // (in (0, 1])
    bool ringRepass = true;           // step 4b: where the rings are used, steps 1–3 once
                                      // more with the macro shape of h − T
    // auto, step 7a (the line-valley score)
    int lineLength = 15;         // samples of the segment (odd, >= 3; 0 switches step 7a off)
    int lineOrientations = 16;   // its directions over 180° (1..64)
    double lineOffset = 3.0;     // samples from the line to each side it is compared with
    double lineSeedSigma = 8.0;  // a line region reaches V >= lineSeedSigma (> 0) ...
    double lineGrowSigma = 4.0;  // ... and holds V >= lineGrowSigma (0 < grow <= seed)
    // step 7b (the texture's own tail): the seed thresholds of steps 7 and 7a are raised to
    // seedTail × the seedTailQuantile-quantile of S (of V for 7a) over the samples outside the
    // border, when that is higher, and their grow thresholds by the same factor (0: off)
    double seedTail = 1.5;           // (>= 0; 0: off)
    double seedTailQuantile = 0.99;  // (in (0, 1))
    int seedTailTiles = 8;  // ... that quantile per tile of an n × n grid, q their median (>= 1;
                            // 1: the whole map's)
    double growTail = 0.0;  // with seedTail: the grow thresholds are max(their σ value,
                            // growTail × the same quantile), not scaled with the seed (>= 0)
    double seedTailWide = 1.0;  // with seedTail: a texture change (step 8 at its own ratio) of at
                                // least this many tail tiles' samples is no texture's tail: it is
                                // left out of every tail and marked (>= 0; 0: off)
    // the height map is a measurement (an instrument's file, or its scene says
    // heightmap.measured): auto is then the selfsim method (see the method table above)
    bool measured = false;

    LayMapOptions lay;          // the `lay` method's options
    SelfSimMapOptions selfsim;  // the `selfsim` method's options
    ScratchMapOptions paper;    // the `paper` method's options
};

// The values of DefectMap::unjudged: where the map could not judge the part (a person looks
// there), and where it judged it (marked or not).
inline constexpr uint8_t kUnjudgedRegion = 255;  // a region at the border the map left unmarked
inline constexpr uint8_t kUnjudgedBorder = 128;  // the border the method never marks
inline constexpr uint8_t kJudged = 0;

/// The method that maps a part with these options: SelfSim for auto on a measured texture.
DefectMethod methodInForce(const DefectMapOptions& options);

struct DefectMap {
    int width = 0, height = 0;  // of the height map
    std::vector<uint8_t> map;   // width*height, row-major: 255 marked, 0 not
    // selfsim only (and auto on a measured texture; empty for the other methods): width*height,
    // kUnjudgedRegion on the samples of the regions that stand out of the texture (steps 6-7's
    // gates) but reach the border's inner line, left unmarked (SelfSimMap::unjudged: such a
    // region continues beyond what the map shows, so it is neither a mark nor cleared),
    // kUnjudgedBorder on the border the method never marks, kJudged elsewhere
    std::vector<uint8_t> unjudged;
    size_t unjudgedRegions = 0;  // regions with samples of kUnjudgedRegion
    DefectMethod method = DefectMethod::Auto;
    // auto only: σ_A and σ_N (with edgeAxes σ_Nx; height units), the bins notched, samples
    // marked by the level/edge score and by the texture-change step, padded FFT size
    double sigmaLevel = 0, sigmaEdge = 0;
    size_t notchedBins = 0, spectrumBins = 0;
    size_t markedScore = 0, markedEnergy = 0, markedStep = 0;
    size_t stepPoints = 0;  // step 4a: centre points of the steps found
    int fftWidth = 0, fftHeight = 0;
    // step 4b: the ring model's fit (centre in samples: x = column, z = row; may lie outside
    // the map), pitch (samples), hand (±1), the decision statistics, whether it was used and
    // the samples whose level it lowered
    double ringCentreX = 0, ringCentreZ = 0, ringPitch = 0, ringIsotropy = 0, ringResidual = 0;
    int ringHand = 0;
    bool ringUsed = false;
    size_t ringLowered = 0;
    // step 7b: the thresholds used (the options' when the tail did not raise them)
    double seedUsed = 0, growUsed = 0, lineSeedUsed = 0;
    // auto on a measured texture (options.measured): `method` is SelfSim and the selfsim
    // fields below are its map's
    bool measuredTexture = false;
    // lay only: the lay direction (x = column, z = row), its coherence, σ of the residual and
    // the texture's RMS (height units), regions kept and dropped (detect/LayMap.h)
    double layX = 0, layZ = 0, layCoherence = 0, layTextureRms = 0;
    size_t layRegions = 0, layDroppedShallow = 0, layDroppedBorder = 0;
    // selfsim only: the offsets kept, the detection threshold (robust sigmas), samples
    // detected, regions kept and dropped at the border (detect/SelfSimMap.h; σ_0 of the
    // residual in sigmaLevel)
    size_t selfsimOffsets = 0, selfsimDetections = 0, selfsimRegions = 0, selfsimDropped = 0;
    double selfsimThreshold = 0;
    // selfsim only: the texture's own tail (step 7: the threshold on a region's peak score, 0
    // off), the regions grown and those dropped below it
    double selfsimTextureThreshold = 0;
    size_t selfsimCandidates = 0, selfsimDroppedTexture = 0;
    // selfsim only: step 7b's threshold on a piece's line score at the growth's level (0 off),
    // and the pieces of the dropped regions kept as lines
    double selfsimLineThreshold = 0;
    size_t selfsimTextureLines = 0;
    // selfsim only: regions whose deepest |r| is below the texture's RMS (step 6), and that RMS
    size_t selfsimDroppedShallow = 0;
    double selfsimTextureRms = 0;
    size_t selfsimBorderPieces = 0;  // selfsim only: pieces of border regions kept (step 8d)
    size_t selfsimBorderLines = 0;   // selfsim only: ... of which kept as lines across the lay (8i)
    size_t selfsimLayLines = 0;      // selfsim only: marks step 8l judged as lines along the lay
    size_t selfsimLayLineSamples = 0;     // ... and the samples it added to them
    size_t selfsimLineCopyLines = 0;      // lines along the lay step 8r judged on their own copies
    size_t selfsimLineCopySamples = 0;    // ... and the samples it added to them
    size_t selfsimValleyLines = 0;        // valleys of the heights step 8t took beside marks ...
    size_t selfsimValleyLineSamples = 0;  // ... and their samples
    size_t selfsimRimBands = 0;           // segments of grooves' bands step 8s took (rims) ...
    size_t selfsimRimBandSamples = 0;     // ... and the samples they added
    size_t selfsimEdgeRingCells = 0;      // cells of the marks' ring step 8u took ...
    size_t selfsimEdgeRingSamples = 0;    // ... and their samples
    size_t selfsimValleyRims = 0;         // segments beside valley lines step 8v took (rims) ...
    size_t selfsimValleyRimSamples = 0;   // ... and their samples
    size_t selfsimReliefLevels = 0;  // selfsim only: a relief's levels taken out (step 1b; 0: none)
    size_t selfsimRaisedLines = 0;  // selfsim only: raised pieces kept as burrs across the lay (8j)
    size_t selfsimBurrBasin = 0;    // ... and the samples of their basins step 8n took back
    size_t selfsimHollowRows = 0;   // selfsim only: rows of hollows (step 8k) ...
    size_t selfsimRowHollows = 0;   // ... and their hollows that steps 6-7 had dropped
    size_t selfsimHollowChains = 0;    // step 8p: chains of hollows on a rough stretch kept ...
    size_t selfsimChainHollows = 0;    // ... and their hollows
    size_t selfsimFarBanks = 0;        // step 8q: grooves' banks kept ...
    size_t selfsimFarBankSamples = 0;  // ... and their samples
    double seconds = 0;

    size_t markedCount() const;
    double markedFraction() const;  // marked samples / all samples
    size_t unjudgedCount() const;   // samples of kUnjudgedRegion (0 when unjudged is empty)
    /// Why the self-similarity map marked nothing although regions stood out of its residual's
    /// noise (step 7's texture tail or step 6's RMS dropped them all): a sentence for the user,
    /// "" when something is marked or nothing stood out. Names no option.
    std::string whyNothingMarked() const;
};

/// The defect map of a width×height height map (row-major, row 0 first). Throws InputError
/// for bad options (naming the option), a size mismatch, a map smaller than 2×2 or a
/// non-finite height (naming its row and column).
DefectMap detectDefects(std::span<const float> heights, int width, int height,
                        const DefectMapOptions& options = {});

// In image space (e.g. a defect mask for the optimizer): with a Scene `scene`,
//   const DefectMap m = detectDefects(scene.heights, scene.mapWidth, scene.mapHeight);
//   const std::vector<uint8_t> mask = projectToImage(tracePrimaryHits(scene), m.map);
// (objective/ImageSpace.h; 255 where the pixel's centre ray sees a marked sample), then
// intersect with the object mask as for any loss mask. m.map is empty of marks (all 0) on a
// surface without anomalies: check markedCount() before using it as a region.

/// Steps 1–3 alone: R = h − macro shape − periodic texture (width*height), for figures and
/// tests; with levelWiener the notched bins hold their Wiener estimate (R + Δ of step 4).
std::vector<float> removeTexture(std::span<const float> heights, int width, int height,
                                 const DefectMapOptions& options = {});

// ---- Scoring a map against a truth label mask (io/MaskIO.h readLabelMask) ----------------
//
// DEFINITIONS (pixels = height-map samples; "marked" = map != 0):
//   overall:  truth = samples whose label is nonzero and not in `negatives`;
//             precision = |marked ∩ truth| / |marked|, recall = |marked ∩ truth| / |truth|.
//   kind v:   recall_v = |marked ∩ {label = v}| / |{label = v}|;
//             precision_v = |marked ∩ {label = v}| / |marked ∩ ({label = v} ∪ {label = 0} ∪
//             {label ∈ negatives})|: the marks on other kinds are neither right nor wrong for v.
//             On a part that holds only kind v this is the plain precision.
//   F1 = 2PR/(P+R) (0 when P + R = 0); a ratio with a zero denominator is NaN.
// Labels in `negatives` (e.g. 128, a chatter region the map is not meant to mark) are counted
// as defect-free: a mark there is a false positive.
struct DefectScoreRow {
    uint8_t value = 0;  // 0 for the overall row
    std::string name;   // "all" for the overall row
    size_t truth = 0;   // samples of the kind (overall: of every kind but the negatives)
    size_t hits = 0;    // marked among them
    size_t marked = 0;  // the precision's denominator
    double precision = 0, recall = 0, f1 = 0;
};

struct DefectScore {
    DefectScoreRow overall;
    std::vector<DefectScoreRow> kinds;  // legend order, negatives included (their recall is
                                        // the share of them marked)
    size_t marked = 0, samples = 0;
};

/// Scores `map` against `labels` (same size). Throws InputError on a size mismatch.
DefectScore scoreDefectMap(std::span<const uint8_t> map, std::span<const uint8_t> labels,
                           std::span<const RegionLabel> legend,
                           std::span<const uint8_t> negatives = {});

}  // namespace sl
