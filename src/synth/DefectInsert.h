// Inserting defects of known shape into any height map (a measured texture or a generated part),
// for evaluating the defect map and the defects objective on textures our generator never made
// (`scratchlight insert-defects`, scripts/eval-real). Pure functions on a height array.
//
// CONVENTION: the map has W columns and H rows; distances and sizes are in SAMPLES (the map's
// own pitch: a defect is as many samples wide on every texture, so it is as large in the image
// of a part the camera frames whole), heights in the map's units (mm). Each defect ADDS its
// offset to the heights; where defects would overlap they are placed elsewhere (their bounding
// boxes, grown by 4 samples, never overlap). Each defect labels the samples where its own offset
// is at least 10% of its depth (height for a burr) in magnitude, with its kind's value (below);
// the higher value wins where labels meet (they do not: boxes are disjoint).
//
// Two models, so an evaluation can tune on one and report on the other:
//  Model A (the one tuned on):
//   - scratch (250): a groove along a smooth random curve (a quadratic Bézier of length
//     0.3–0.6 × the shorter side, its control point off the chord by up to 0.15 × the chord),
//     width w (4–8 samples × sizeScale), V (d·(1 − 2|s|/w)) or rounded (d·(1 − (2s/w)²))
//     cross-section, s the distance to the curve, depth tapered to 0 over the first and last
//     min(L/4, 3w) of its length. Material piled up beside it: a rim on each side, centred at
//     |s| = w/2 + r/2, r = w the rim width, profile h_r·(1 − u²)², u ∈ [−1, 1] across it, with
//     h_r chosen so the two rims hold `pileUp` × the groove's cross-section:
//     2·h_r·r·8/15 = pileUp·A, A = d·w/2 (V) or 2·d·w/3 (rounded).
//   - pit (240): a rounded crater, radius ρ_p (4–10 samples × sizeScale), paraboloid
//     d·(1 − (ρ/ρ_p)²), with a rim ring of width r = ρ_p/2 centred at ρ_p + r/2, profile
//     h_r·(1 − u²)², holding `pileUp` × the crater's volume (π·ρ_p²·d/2):
//     h_r = pileUp·π·ρ_p²·d/2 / (2π·(ρ_p + r/2)·r·8/15).
//   - burr (160): a raised lip along an edge segment (straight, 0.1–0.25 × the shorter side):
//     height H·g(t) (g = sin(π·t)^0.5, t ∈ [0, 1] along it), steep on one side (a 1-sample
//     edge) and falling as (1 − s/w_b)² over w_b = 3–6 samples × sizeScale on the other.
//  Model B (never tuned on; another parameterisation):
//   - gouge (248): a straight segment 0.15–0.3 × the shorter side, depth d·sin(π·t), an
//     asymmetric profile: a steep wall of w_1 = 1–2 samples on one side (linear), a concave
//     ramp d·(1 − s/w_2)² of w_2 = 4–8 samples × sizeScale on the other; no rim.
//   - pit-chain (236): 4–8 small pits (radius 2–4 samples × sizeScale, paraboloid, depth
//     d × 0.7–1, no rim) along a straight line, 2.5–4 radii apart.
//   - dent (224): a spherical cap pressed in, lateral radius 10–25 samples × sizeScale, depth d,
//     no rim: d − (R − √(R² − ρ²)), R = (ρ_d² + d²)/(2d).
//   - crack (232, opt-in: `--kinds crack`, not among the model's default three): the
//     generator's crack (SurfaceGenerator.h crackPaths: a zig-zag trunk with branches, a V
//     opening as an ellipse along the trunk, no rim), its trunk 0.15–0.3 × the shorter side
//     long, its widest opening 2–4 samples × sizeScale, depth d, 1–3 branches.
// Depth d of each defect = depthBase × U(0.7, 1.3) (burr height likewise). `faint` defects per
// kind are added at faintDepth (below what any light shows: the eval's choice is a few % of the
// texture's Sq) and are NOT labelled (truth 0); they are listed with `labelled` false so a
// second look at the map's marks can name them.
// Placement: centres (or the curve's chord) uniform in the inner region `margin` samples from
// every edge, up to 200 tries per defect; a defect that finds no room is skipped (and counted).
// Deterministic from `seed`.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "synth/SurfaceGenerator.h"  // the truth label values

namespace sl {

enum class DefectModel { A, B };
enum class InsertKind { Scratch, Pit, Burr, Gouge, PitChain, Dent, Crack };

struct InsertKindRow {
    InsertKind value;
    const char* name;
    DefectModel model;
    uint8_t label;
    const char* help;
    bool byDefault = true;  // among the model's kinds when none are named (modelKinds)
};
std::span<const InsertKindRow> insertKindTable();
const InsertKindRow& insertKindRow(InsertKind kind);
/// The kind named `name` (a row of insertKindTable); InputError naming `where` otherwise.
InsertKind parseInsertKind(std::string_view name, const std::string& where);
/// The model's three default kinds (byDefault), in table order: what --kinds left out means.
std::vector<InsertKind> modelKinds(DefectModel model);

struct InsertSpec {
    DefectModel model = DefectModel::A;
    std::vector<InsertKind> kinds;  // empty: the model's three (modelKinds); each the model's
    int count = 3;                  // labelled defects per kind (>= 0)
    int faint = 1;                  // unlabelled faint defects per kind (>= 0)
    double depth = 0.002;           // depthBase, height units (> 0)
    double faintDepth = 0.00005;    // height units (> 0)
    double sizeScale = 1.0;         // multiplies every lateral size in samples (> 0)
    double pileUp = 0.6;            // model A rims: share of the removed volume (>= 0)
    int margin = 48;                // samples from the edges kept clear (>= 0)
    uint64_t seed = 1;
};

struct InsertedDefect {
    InsertKind kind;
    bool labelled = true;
    double depth = 0;                    // height units (burr: its height)
    double x = 0, z = 0;                 // centre (column, row), samples
    int x0 = 0, z0 = 0, x1 = 0, z1 = 0;  // bounding box (inclusive), samples
    double size = 0;     // width (scratch, gouge, burr; crack: widest), radius (pit, dent, chain)
    size_t samples = 0;  // samples labelled (0 when not labelled)
};

struct InsertResult {
    std::vector<float> heights;  // the input plus every offset
    std::vector<uint8_t> truth;  // labels (kTruthScratch, ...), 0 elsewhere
    std::vector<InsertedDefect> defects;
    int skipped = 0;  // defects that found no room
};

/// Inserts the defects. Throws InputError (naming the field) for bad spec values, a kind not of
/// the model, a size mismatch or a map smaller than 2 × margin + 16 samples on a side.
InsertResult insertDefects(std::span<const float> heights, int width, int height,
                           const InsertSpec& spec);

// The single defects, as offsets (added to a map; `label` receives the kind's value where the
// offset is ≥ 10% of depth in magnitude). Exposed for tests; insertDefects calls them.
struct Groove {
    std::vector<double> px, pz;  // the curve as a polyline, samples
    double width = 6, depth = 0.002;
    bool rounded = false;
    double pileUp = 0.6;
};
/// The offset of a model-A scratch at distance s from its curve, at arc position t of length L
/// (taper included).
double grooveProfile(const Groove& g, double s, double t, double length);
/// The rim height h_r of a model-A scratch or pit (see above).
double grooveRimHeight(double width, double depth, bool rounded, double pileUp);
double pitRimHeight(double radius, double depth, double pileUp);
/// The offset of a model-A pit at distance rho from its centre.
double pitProfile(double radius, double depth, double pileUp, double rho);

/// The texture's Sq without its tilt, form and waviness (a curved bullet land, a bent part):
/// the RMS of the S-L surface: the heights minus their least-squares quadratic surface
/// (a + bx + cz + dx² + exz + fz²), minus that residual's low-pass (the L-filter: twice a
/// separable box mean of 2·⌊min(W, H)/10⌋ + 1 samples, edges clamped).
double textureSq(std::span<const float> heights, int width, int height);

/// Resamples a map to at most maxSide samples on its longer side (box average over each new
/// sample's footprint, then bilinear): returns the new heights and sets width/height; the
/// pitch grows by the returned factor (old size / new size). A map already small enough is
/// returned unchanged (factor 1).
double resampleToMaxSide(std::vector<float>& heights, int& width, int& height, int maxSide);

}  // namespace sl
