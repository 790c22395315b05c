// Synthetic NC-machined surfaces with a ground-truth defect mask: the default demo scene and
// the test fixture of the scratch-map / visibility code.
//
// CONVENTION (frame, as docs/DESIGN.md "Conventions"): units are millimetres. The map has W columns
// and H rows at `pitch` mm; sample (row j, column i) sits at
//     x = (i − (W−1)/2)·pitch,   z = (j − (H−1)/2)·pitch,   y = heights[j·W + i]
// so the surface faces +Y, row 0 is at −z and column 0 at −x. Directions in the x–z plane are
// given by an angle a measured from +x toward +z: along-path t = x·cos a + z·sin a, across-path
// p = −x·sin a + z·cos a.
//
// What is generated (in this order, every stage deterministic from `seed`, independent of the
// number of threads):
//  1. Tool marks, relative to the nominal cut plane y = 0 (the bottom of the tool paths).
//     - BallEndRaster: parallel paths along angle a at p_k = pathOffset + k·stepover. A ball of
//       radius R leaves h_k = R − √(R² − d²) at distance d from path k; the surface is the MIN
//       over paths (material is gone wherever any pass went), so cusps of exactly
//       scallopHeight(stepover, R) = R − √(R² − (s/2)²) ≈ s²/(8R) stand between paths. With
//       `ballFeedMarks` the ball is taken at its tooth positions t = m·feedPerTooth (+ a phase
//       per path), h = R − √(R² − dt² − d²), which adds the feed scallops ≈ f²/(8R) along the
//       path.
//     - FaceMillFeed: passes of a face mill of radius R (toolRadius) fed along angle a, pass
//       centre lines p_k = pathOffset + k·stepover, the later pass wins where passes overlap.
//       Each tooth's leading edge leaves a circular arc of radius R around the cutter centre
//       t_c = m·feedPerTooth; the insert's nose radius r_n turns the arcs into grooves
//       h = r_n − √(r_n² − δ²), δ = distance to the nearest arc: the crescent feed-mark pattern,
//       r_n − √(r_n² − (f/2)²) high on the pass centre line (≈1 µm for f = 0.08, r_n = 0.8).
//     - Chatter: the tool's depth oscillates along the path, A·sin(2π·t/λ + φ_k), random phase
//       φ_k per path.
//  2. Gouges (defects): the tool digs in by up to `gougeDepth` along a short segment of a path
//     (depth D·sin(π·τ), τ ∈ [0,1] along the segment); the surface becomes the MIN of itself
//     and the swept sphere (radius R for ball-end, r_n for face mill).
//  3. Roughness: Gaussian noise on a lattice of spacing `roughnessCorrelation` (clamped to at
//     least the pitch), interpolated by a cubic B-spline and renormalised so its RMS is
//     `roughnessRms` at every point. Being defined in mm, it is the same surface at any pitch.
//  4. Scratches (defects): V or rounded grooves of the given width/depth along segments, with
//     a raised burr (lip) on both sides of height burr·depth, depth tapered to 0 over the first
//     and last min(L/4, 5·width) of the segment. Added to the surface.
//  5. Pocket edge (macro shape, NOT a defect): the part steps down by `pocketDepth` across a
//     wall parallel to z at x = xmax − pocketWallFraction·(W−1)·pitch (the pocket floor is the
//     last `pocketWallFraction` of the map in +x). The step is an S of two arcs of radius
//     `cornerRadius` (convex at the top, concave at the bottom), with a vertical drop in
//     between when pocketDepth > 2·cornerRadius. Subtracted from the surface.
//
// Truth labels (one value per kind; gen-surface writes them as <stem>-truth.png with a JSON
// legend <stem>-truth.json): kTruthDefect (255) where a defect was cut: scratch cells within the
// groove (distance to the segment < width/2, and the tapered depth ≥ 10% of the scratch's depth),
// gouge cells that the gouge lowered by ≥ 10% of its depth; kTruthChatter (128) on the other
// samples of a confined chatter region (chatterStartFraction > 0). Everything else, including the
// pocket edge, is 0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace sl {

inline constexpr uint8_t kTruthDefect = 255;   // scratch or gouge
inline constexpr uint8_t kTruthChatter = 128;  // confined chatter region (not a cut defect)

/// One scratch: a groove along the segment (x0,z0)–(x1,z1), mm, in the map's centred frame.
struct ScratchSpec {
    double x0 = 0, z0 = 0, x1 = 0, z1 = 0;  // mm
    double width = 0.03;                    // mm, groove width at the surface
    double depth = 0.004;                   // mm, groove depth at the centre line
    enum class Shape { V, Round } shape = Shape::V;
    double burr = 0.3;  // height of the raised lip on each side, as a fraction of depth
};

/// One gouge: the tool digs in along the segment (x0,z0)–(x1,z1) by up to `depth` below the
/// nominal cut plane y = 0 (depth·sin(π·τ) along the segment).
struct GougeSpec {
    double x0 = 0, z0 = 0, x1 = 0, z1 = 0;  // mm
    double depth = 0.012;                   // mm
};

struct SurfaceSpec {
    int width = 1024, height = 1024;  // samples (columns, rows)
    double pitch = 0.01;              // mm per sample
    enum class Process { BallEndRaster, FaceMillFeed } process = Process::BallEndRaster;
    double toolRadius = 3.0;     // mm: ball radius R (ball-end) or cutter radius (face mill)
    double stepover = 0.4;       // mm: path (ball-end) or pass (face mill) spacing, < 2·toolRadius
    double pathOffset = 0.0;     // mm: across-path position p of path k = 0
    double feedPerTooth = 0.08;  // mm: feed per tooth (face-mill crescents, ball feed marks)
    bool ballFeedMarks = true;   // ball-end: model the tooth positions (feed scallops)
    double insertNoseRadius = 0.8;  // mm: face-mill insert nose radius r_n
    double rasterAngleDeg = 0.0;    // direction of the tool paths in the x-z plane, from +x to +z
    double chatterAmplitude = 0.0005;  // mm, periodic waviness along the path (chatter)
    double chatterWavelength = 0.4;    // mm
    // Chatter only where x ≥ this fraction of the map's width from its −x edge (0: everywhere,
    // 0.5: the right half). When > 0 the chatter region is labelled in the truth (kTruthChatter).
    double chatterStartFraction = 0.0;
    double roughnessRms = 0.0002;        // mm, small random roughness (fixed seed)
    double roughnessCorrelation = 0.02;  // mm, lattice spacing of the roughness (≥ pitch used)
    // Random scratches, used when `scratches` is empty: depth uniform in [0.5, 1]·scratchDepth,
    // width uniform in [0.75, 1]·scratchWidth, centres stratified (Latin hypercube) over the
    // inner 80% of the map, lengths 15–50% of the shorter side, random orientation and shape.
    int scratchCount = 4;
    double scratchDepth = 0.004;
    double scratchWidth = 0.03;
    std::vector<ScratchSpec> scratches;  // explicit scratches (override the random ones)
    // Random gouges, used when `gouges` is empty: along a tool path (ball-end), in the inner 60%
    // of the map, kept clear of the pocket edge.
    int gougeCount = 1;
    double gougeDepth = 0.012;      // mm
    double gougeLength = 0.6;       // mm
    std::vector<GougeSpec> gouges;  // explicit gouges (override the random ones)
    bool pocketEdge = true;
    double pocketDepth = 0.3;          // mm
    double pocketWallFraction = 0.25;  // fraction of the map (in +x) that is pocket floor
    double cornerRadius = 0.5;         // mm, fillet radius of the pocket edge (0 = sharp step)
    uint64_t seed = 1;
};

struct GeneratedSurface {
    int width = 0, height = 0;
    double pitch = 0;
    std::vector<float> heights;  // row-major, row 0 first, mm
    std::vector<uint8_t> truth;  // same size: kTruthDefect, kTruthChatter or 0 (see above)
    std::string description;     // one line: what was generated, incl. the predicted scallop
    double scallop = 0;          // predicted cusp height of the tool marks, mm (see description)
    std::vector<ScratchSpec> scratches;  // the scratches actually cut (explicit or random)
    std::vector<GougeSpec> gouges;       // the gouges actually cut
    // Pocket edge (macro shape, not a defect): the step spans x in
    // [pocketEdgeX − pocketEdgeHalfWidth, pocketEdgeX + pocketEdgeHalfWidth]; NaN when absent.
    double pocketEdgeX = 0, pocketEdgeHalfWidth = 0;

    float at(int i, int j) const { return heights[static_cast<size_t>(j) * width + i]; }
    bool isDefect(int i, int j) const { return truth[static_cast<size_t>(j) * width + i] != 0; }
};

/// Generates the surface. Validates `spec` first and throws sl::InputError naming the field.
GeneratedSurface generateSurface(const SurfaceSpec& spec);

/// Cusp height between two ball-end paths, exact: R − √(R² − (s/2)²) (≈ s²/(8R)).
/// Throws InputError unless R > 0 and 0 ≤ s ≤ 2R.
double scallopHeight(double stepover, double ballRadius);

}  // namespace sl
