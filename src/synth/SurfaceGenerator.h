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
//     - FlatEndPocket: a flat end mill of radius R (toolRadius) with corner radius r_c
//       (toolCornerRadius) cutting parallel passes along angle a, p_k = pathOffset + k·stepover;
//       the surface is the MIN over passes (material is gone wherever any pass went). Across a
//       pass the tool's profile is flat (0) for |q| ≤ a_f = R − r_c and the corner's arc
//       r_c − √(r_c² − (|q| − a_f)²) beyond, so where passes overlap by less than the flat
//       (s > 2·a_f) a ridge of exactly flatEndRidgeHeight(s, R, r_c) = r_c − √(r_c² − (s/2 − a_f)²)
//       stands between them (0 when s ≤ 2·a_f: a flat floor). Feed marks (feedPerTooth f > 0):
//       as the face mill, only the leading half of the tool cuts (tilted spindle); each tooth's
//       corner sweeps a circle of radius a_f about the tool centre t_m = m·f (+ a phase per
//       pass), leaving the torus h = r_c − √(r_c² − δ²), δ = distance to the nearest leading
//       corner arc: crescents on the floor, r_c − √(r_c² − (f/2)²) ≈ f²/(8·r_c) high on the pass
//       centre line, and feed scallops along the ridges.
//     - Turned: a face-turned section: a turning tool of nose radius r_n (insertNoseRadius) fed
//       f = feedPerTooth mm per revolution toward a centre (turnCentreX, turnCentreZ) leaves
//       an Archimedean spiral groove. At polar position (r, θ) about the centre, revolution n's
//       nose centre was at ρ_n(θ) = f·(n + θ/2π + φ) (φ a random phase); in that radial plane
//       the nose profile is exact, h = min_n r_n − √(r_n² − (r − ρ_n)²), so cusps of exactly
//       scallopHeight(f, r_n) = r_n − √(r_n² − (f/2)²) ≈ f²/(8·r_n) stand between grooves f
//       apart: concentric rings near the centre, nearly straight parallel grooves far from it
//       (put the centre off the map for a section of straight grooves).
//     - Ground: surface grinding along angle a (the lay). Each abrasive grit that cuts leaves a
//       track: a groove of its tip radius r_g (toolRadius), h = r_g − √(r_g² − q²) − δ_k·w(τ)
//       at across-lay distance q from its centre line p_k, over a length L_k along the lay (τ in
//       [0, 1] along it; w = smoothstep(min(τ, 1 − τ)/0.15): a grit enters and leaves the cut).
//       The surface is the MIN of the wheel's envelope y = 0 and every track (material is gone
//       wherever a grit went). Tracks are drawn from the seed: centre lines p_k and mid-points
//       uniform, on average one track across the lay per `stepover` at any point along it
//       (1/(stepover·gritLength) tracks per mm²); lengths uniform in [0.5, 1.5]·gritLength;
//       depths δ_k = gritDepth·e_k, e_k exponential of mean 1 (the grits' protrusion), cut at
//       4: the ground finish's fine streaks along the lay, plateaus at y = 0 where no grit cut.
//     - Chatter: the tool's depth oscillates along the path, A·sin(2π·t/λ + φ_k), random phase
//       φ_k per path (Turned: along the spiral, t = π·ρ_n²/f, the path length to radius ρ_n;
//       Ground: the wheel's, one phase for the whole lay, so the marks are straight lines across
//       it).
//     - Chatter bands (chatterBands > 0): strips |c − c_b| < chatterBandWidth/2 across the
//       paths, c the across-path coordinate (p for milling, the radius r about the turning
//       centre for Turned, so bands are rings there), where the chatter amplitude is
//       chatterBandAmplitude instead of chatterAmplitude (on every sample of the band, also left
//       of chatterStartFraction): a stretch of passes where the tool chattered. Centres uniform
//       over the map's range of c such that the band lies within it (a band wider than that
//       range is centred on it).
//  2. Gouges (defects): the tool digs in by up to `gougeDepth` along a short segment of a path
//     (depth D·sin(π·τ), τ ∈ [0,1] along the segment); the surface becomes the MIN of itself
//     and the swept sphere (radius R for ball-end, r_n for face mill and turned, r_c for the flat
//     end mill; for ground, a rogue grit of tip radius r_g dug in along the lay).
//  3. Roughness: Gaussian noise on a lattice of spacing `roughnessCorrelation` (clamped to at
//     least the pitch), interpolated by a cubic B-spline and renormalised so its RMS is
//     `roughnessRms` at every point. Being defined in mm, it is the same surface at any pitch.
//  4. Scratches (defects): V or rounded grooves of the given width/depth along segments, with
//     a raised burr (lip) on both sides of height burr·depth, depth tapered to 0 over the first
//     and last min(L/4, 5·width) of the segment. Added to the surface. Random scratches: depth
//     uniform in [scratchDepthMin, 1]·scratchDepth, width in [scratchWidthMin, 1]·scratchWidth,
//     direction uniform within ±scratchDirectionSpreadDeg/2 of scratchDirectionDeg (180: any).
//  4b. Dents (defects): a sphere of radius R_d pressed to depth d into the surface (handling
//     damage), lowering it by d − (R_d − √(R_d² − r²)) within r < √(2·R_d·d − d²) of the
//     centre. Added to the surface.
//  4c. Burr (defect): raised material rolled over at the top of the pocket wall (x = the start
//     of the convex arc): height H·g(z)·(1 − u²)², u = (x − x_top)/(pocketBurrWidth/2), g(z) in
//     [0.5, 1] a smooth random profile along the edge (cubic interpolation of values 0.25 mm
//     apart). Added.
//  4d. Tool-change step (defect): from the line c = toolChangeAt on (c as for chatter bands:
//     a line along the tool paths, a circle about the turning centre), the surface is
//     toolChangeStep lower (negative: higher), where a tool with another length offset took
//     over; the step is a smoothstep ramp over max(toolChangeWidth, 2·pitch). Added.
//  4e. Cracks (defects, opt-in: crackCount): a narrow fissure, meandering and branching, with
//     no raised rim (the material parted; nothing was pushed aside): crackPaths() below has the
//     model and its sources. Added to the surface.
//  6. Measurement noise (opt-in, not a defect, not labelled): what an optical profilometer
//     adds to the part's true surface: white Gaussian noise of RMS noiseRms on every sample (its
//     vertical noise floor) and spikeCount single-sample spikes of ±[0.5, 1]·spikeHeight at
//     random samples (outliers at steep slopes or bad pixels; no dropouts, every sample keeps a
//     finite height). Added after everything, the pocket included; positions in `spikes`.
//  5. Pocket edge (macro shape, NOT a defect): the part steps down by `pocketDepth` across a
//     wall parallel to z at x = xmax − pocketWallFraction·(W−1)·pitch (the pocket floor is the
//     last `pocketWallFraction` of the map in +x). The step is an S of two arcs of radius
//     `cornerRadius` (convex at the top, concave at the bottom), with a vertical drop in
//     between when pocketDepth > 2·cornerRadius. Subtracted from the surface.
//
// Truth labels (one value per kind; gen-surface writes them as <stem>-truth.png with a JSON
// legend <stem>-truth.json listing every value present, and "defect" always): kTruthDefect (255)
// where a defect was cut: scratch cells within the groove (distance to the segment < width/2,
// and the tapered depth ≥ 10% of the scratch's depth), gouge cells that the gouge lowered by
// ≥ 10% of its depth; kTruthChatter (128) on the other samples of a confined chatter region
// (chatterStartFraction > 0). Everything else, including the pocket edge, is 0. The kinds added
// for the test parts, each labelled where its own change is ≥ 10% of its size:
//   kTruthCrack (232, "crack"): cells a crack lowered by ≥ 10% of its depth;
//   kTruthDent (224, "dent"): cells a dent lowered by ≥ 10% of its depth;
//   kTruthToolChange (192, "tool-change-step"): the ramp of the step where it has moved the
//     surface by ≥ 10% of the step (the plateau beyond is shifted too, but not labelled: the
//     visible defect is the step line);
//   kTruthBurr (160, "burr"): cells the pocket-edge burr raised by ≥ 10% of its local height,
//     and with labelScratchLips the scratches' lips where they are ≥ 10% of the lip height;
//   kTruthChatterBand (144, "chatter-band"): every sample of a chatter band.
// Where labels overlap the HIGHER value wins: cut defects over cracks over dents over the step
// over burrs over chatter bands over the chatter region. Every value is ≥ 128, so a reader that
// binarises the mask at half scale (optimize --truth's metrics: inside = value/255 > 0.5) counts
// every label as a defect; the judge reads each value as its own region.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/RegionLabel.h"

namespace sl {

inline constexpr uint8_t kTruthDefect = 255;       // scratch or gouge
inline constexpr uint8_t kTruthScratch = 250;      // inserted scratch (synth/DefectInsert.h, A)
inline constexpr uint8_t kTruthGouge = 248;        // inserted asymmetric gouge (model B)
inline constexpr uint8_t kTruthPit = 240;          // inserted pit with a rim (model A)
inline constexpr uint8_t kTruthPitChain = 236;     // inserted chain of small pits (model B)
inline constexpr uint8_t kTruthCrack = 232;        // crack (generated or inserted, model B)
inline constexpr uint8_t kTruthDent = 224;         // spherical dent
inline constexpr uint8_t kTruthToolChange = 192;   // tool-change step (its ramp)
inline constexpr uint8_t kTruthBurr = 160;         // pocket-edge burr, labelled scratch lips
inline constexpr uint8_t kTruthChatterBand = 144;  // chatter band
inline constexpr uint8_t kTruthChatter = 128;      // confined chatter region (not a cut defect)

/// One kind of truth label: its value and its legend name.
struct TruthKind {
    uint8_t value;
    const char* name;
    const char* help;
};

/// Every truth label kind, highest value (and priority) first.
std::span<const TruthKind> truthKinds();

/// The legend of a truth mask: "defect" (always, as gen-surface has always written it), then
/// every other kind whose value is present, in truthKinds() order. A value present that is no
/// kind's would be named "label-<v>" (the generator writes none).
std::vector<RegionLabel> truthLegend(const std::vector<uint8_t>& truth);

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

/// One dent: a sphere of radius `radius` pressed `depth` into the surface at (x, z), mm.
struct DentSpec {
    double x = 0, z = 0;   // mm, centre
    double depth = 0.005;  // mm
    double radius = 0.5;   // mm, indenter radius
};

/// One crack: its trunk's centre, direction and length along its path, its widest opening and
/// deepest point, its branches, and the seed of its meander (crackPaths draws the shape from
/// it). Lengths in the map's units: mm in the generator, samples in insert-defects.
struct CrackSpec {
    double x = 0, z = 0;   // centre of the trunk's chord
    double angleDeg = 0;   // the trunk's mean direction, from +x toward +z
    double length = 1.5;   // the trunk's length along its path
    double width = 0.025;  // the opening at the surface where widest (the trunk's middle)
    double depth = 0.006;  // the depth where deepest (the trunk's middle)
    int branches = 2;      // branches off the trunk
    uint64_t seed = 1;     // the meander's and the branches' draws
};

/// One piece of a crack: a polyline (the trunk, or a branch starting on the trunk) with the
/// opening and depth of its own profile (crackPaths).
struct CrackPath {
    std::vector<double> x, z;  // vertices
    double width = 0, depth = 0;
    bool branch = false;
};

/// A crack's pieces, trunk first. The model and its sources:
///  - a recession with no raised portion: ISO 8785:1998 (surface imperfections) tells the
///    hollows without a raised edge (4.1.10, the dent) from those with one (4.3.1, the crater)
///    and names crazing (4.4.5) "a network of cracks on a surface"; a crack is a parting of the
///    material, nothing is pushed aside, so it has no rim;
///  - its path: "a clean (crystalline) fracture passing through or across the grain
///    boundaries" (the crack of ISO 6157 and ASTM A788), so it is deflected at every grain: a
///    zig-zag that keeps its mean direction, and it branches;
///  - its opening: linear-elastic fracture mechanics (Westergaard 1939, Irwin 1957): a crack
///    of half-length a under uniform tension opens as √(a² − x²), and near a tip as the square
///    root of the distance to it.
///  - the trunk: 16 straight pieces of length/16; piece k heads angle + φ_k, φ_0 = U(−30°, 30°),
///    φ_k = φ_(k−1)/2 + U(−30°, 30°) (a grain's deflection, pulled back toward the mean so the
///    crack keeps its direction); the polyline is centred on (x, z) by its chord's midpoint;
///  - its opening along its arc t ∈ [0, L]: e(t) = √(1 − (2t/L − 1)²) (the ellipse: 1 in the
///    middle, 0 at both tips); width·e(t) wide and depth·e(t) deep;
///  - `branches` branches, each from a trunk vertex k ∈ [3, 13] (uniform), heading the trunk's
///    piece k direction ± U(25°, 50°), length U(0.25, 0.5)·L in 8 pieces of the same meander; its
///    opening √(1 − t/L_b) (a tip's root) times 0.6 × the trunk's opening e at its vertex
///    (width and depth alike);
///  - the cross-section, s the distance to the piece's polyline and t the arc position of the
///    nearest point: a V, −D(t)·(1 − 2s/W(t)) for s < W(t)/2, and 0 beyond (no rim); where
///    pieces meet, the deeper one (the MIN).
/// Deterministic from the spec (its seed).
std::vector<CrackPath> crackPaths(const CrackSpec& spec);

/// One piece's offset (≤ 0) at (x, z), and the crack's: the MIN over its pieces.
double crackPathOffset(const CrackPath& path, double x, double z);
double crackOffset(const std::vector<CrackPath>& paths, double x, double z);

/// One measurement spike: sample (i, j) offset by `height` mm.
struct Spike {
    int i = 0, j = 0;
    double height = 0;
};

struct SurfaceSpec {
    int width = 1024, height = 1024;  // samples (columns, rows)
    double pitch = 0.01;              // mm per sample
    enum class Process {
        BallEndRaster,
        FaceMillFeed,
        FlatEndPocket,
        Turned,
        Ground
    } process = Process::BallEndRaster;
    // mm: ball radius R (ball-end), cutter radius (face mill, flat end), grit tip radius (ground)
    double toolRadius = 3.0;
    // mm: path (ball-end) or pass (face mill) spacing, < 2·toolRadius; ground: the mean spacing
    // of the grit tracks across the lay
    double stepover = 0.4;
    double pathOffset = 0.0;  // mm: across-path position p of path k = 0
    // mm: feed per tooth (face-mill crescents, ball and flat-end feed marks; flat end: 0 = no
    // feed marks), or per revolution (Turned)
    double feedPerTooth = 0.08;
    bool ballFeedMarks = true;      // ball-end: model the tooth positions (feed scallops)
    double insertNoseRadius = 0.8;  // mm: face-mill or turning insert nose radius r_n
    double toolCornerRadius = 0.2;  // mm: flat end mill corner radius r_c (< toolRadius)
    double turnCentreX = 0.0, turnCentreZ = 0.0;  // mm: Turned, the spiral's centre
    double gritDepth = 0.0008;                    // mm: Ground, the grits' mean depth of cut
    double gritLength = 1.0;      // mm: Ground, the grit tracks' mean length along the lay
    double rasterAngleDeg = 0.0;  // direction of the tool paths in the x-z plane, from +x to +z
    double chatterAmplitude = 0.0005;  // mm, periodic waviness along the path (chatter)
    double chatterWavelength = 0.4;    // mm
    // Chatter only where x ≥ this fraction of the map's width from its −x edge (0: everywhere,
    // 0.5: the right half). When > 0 the chatter region is labelled in the truth (kTruthChatter).
    double chatterStartFraction = 0.0;
    // Chatter bands (see above; labelled kTruthChatterBand): how many, their width across the
    // paths (radial for Turned) and the chatter amplitude inside them.
    int chatterBands = 0;
    double chatterBandWidth = 0.8;        // mm
    double chatterBandAmplitude = 0.001;  // mm
    double roughnessRms = 0.0002;         // mm, small random roughness (fixed seed)
    double roughnessCorrelation = 0.02;   // mm, lattice spacing of the roughness (≥ pitch used)
    // Random scratches, used when `scratches` is empty: depth uniform in
    // [scratchDepthMin, 1]·scratchDepth, width uniform in [scratchWidthMin, 1]·scratchWidth,
    // centres stratified (Latin hypercube) over the inner 80% of the map, lengths 15–50% of the
    // shorter side, direction uniform within scratchDirectionDeg ± scratchDirectionSpreadDeg/2
    // (180: any direction), random shape.
    int scratchCount = 4;
    double scratchDepth = 0.004;
    double scratchWidth = 0.03;
    double scratchDepthMin = 0.5;            // fraction of scratchDepth, in [0, 1]
    double scratchWidthMin = 0.75;           // fraction of scratchWidth, in (0, 1]
    double scratchDirectionDeg = 0.0;        // from +x toward +z
    double scratchDirectionSpreadDeg = 180;  // in [0, 180]
    bool labelScratchLips = false;           // label the scratches' lips kTruthBurr
    std::vector<ScratchSpec> scratches;      // explicit scratches (override the random ones)
    // Random gouges, used when `gouges` is empty: along a tool path (ball-end), in the inner 60%
    // of the map, kept clear of the pocket edge.
    int gougeCount = 1;
    double gougeDepth = 0.012;      // mm
    double gougeLength = 0.6;       // mm
    std::vector<GougeSpec> gouges;  // explicit gouges (override the random ones)
    // Random dents, used when `dents` is empty: centres uniform over the inner 80% of the map,
    // kept clear of the pocket edge, depth uniform in [0.5, 1]·dentDepth.
    int dentCount = 0;
    double dentDepth = 0.005;     // mm
    double dentRadius = 0.5;      // mm, indenter radius
    std::vector<DentSpec> dents;  // explicit dents (override the random ones)
    // Random cracks (0: none): centres uniform over the inner 60% of the map, kept clear of the
    // pocket edge, any direction, depth and width uniform in [0.5, 1]·crackDepth/crackWidth,
    // length in [0.75, 1]·crackLength, crackBranches branches each (crackPaths).
    int crackCount = 0;
    double crackLength = 1.5;   // mm, along the trunk's path
    double crackWidth = 0.025;  // mm, the widest opening
    double crackDepth = 0.006;  // mm, the deepest point
    int crackBranches = 2;
    bool pocketEdge = true;
    double pocketDepth = 0.3;          // mm
    double pocketWallFraction = 0.25;  // fraction of the map (in +x) that is pocket floor
    double cornerRadius = 0.5;         // mm, fillet radius of the pocket edge (0 = sharp step)
    double pocketBurrHeight = 0.0;     // mm, burr on the pocket's top edge (0: none)
    double pocketBurrWidth = 0.04;     // mm
    double toolChangeStep = 0.0;       // mm, tool-change step (0: none; > 0: lower beyond)
    double toolChangeAt = 0.0;         // mm, across-path position (Turned: radius) of the step
    double toolChangeWidth = 0.02;     // mm, width of the step's ramp (at least 2·pitch used)
    double noiseRms = 0.0;             // mm, white measurement noise (0: none)
    int spikeCount = 0;                // measurement spikes
    double spikeHeight = 0.005;        // mm
    uint64_t seed = 1;
};

/// The processes a user names (gen-surface --process), one row each.
struct ProcessRow {
    SurfaceSpec::Process value;
    const char* name;
    const char* help;
};
std::span<const ProcessRow> processTable();

/// The default spec of a process: SurfaceSpec{} with `process` set, and for FlatEndPocket and
/// Turned a typical finishing tool (flat end: R 1 mm, r_c 0.2 mm, stepover 1.7 mm, 0.05 mm per
/// tooth; turned: nose 0.8 mm, 0.1 mm per revolution). BallEndRaster and FaceMillFeed get
/// exactly SurfaceSpec{}'s tool, so their surfaces are those gen-surface has always made.
SurfaceSpec processDefaults(SurfaceSpec::Process process);

/// The labelled test parts (gen-surface --part): one per process, every defect kind present.
enum class TestPart { BallEnd, FaceMill, FlatEnd, Turned, Ground };
struct TestPartRow {
    TestPart value;
    const char* name;
    const char* help;
};
std::span<const TestPartRow> testPartTable();

/// The spec of a test part: 1024×1024 at 0.01 mm, seed 1, processDefaults of its process (the
/// face mill with R 4 mm, passes 3 mm apart), 5 scratches of spread direction, depth and width
/// with labelled lips, 1 gouge, 3 dents, a 4 µm burr on the pocket edge, a 3 µm tool-change step,
/// chatter on the right 40% of the map and 2 chatter bands.
SurfaceSpec testPartSpec(TestPart part);

struct GeneratedSurface {
    int width = 0, height = 0;
    double pitch = 0;
    std::vector<float> heights;  // row-major, row 0 first, mm
    std::vector<uint8_t> truth;  // same size: kTruthDefect, kTruthChatter or 0 (see above)
    std::string description;     // one line: what was generated, incl. the predicted scallop
    // Predicted cusp height of the tool marks, mm (see description): ball-end, between paths;
    // face mill, the feed crescents; flat end, the ridge between passes; turned, the groove cusp.
    double scallop = 0;
    std::vector<ScratchSpec> scratches;  // the scratches actually cut (explicit or random)
    std::vector<GougeSpec> gouges;       // the gouges actually cut
    std::vector<DentSpec> dents;         // the dents actually pressed
    std::vector<CrackSpec> cracks;       // the cracks actually opened
    std::vector<double> chatterBands;    // band centres, across-path coordinate c (mm)
    std::vector<Spike> spikes;           // measurement spikes added
    // Predicted feed-mark height (the face mill's `scallop`; ball-end f²-scallop with feed marks;
    // flat end: floor crescents on the pass centre line; turned: the groove cusp), mm.
    double feedMark = 0;
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

/// Ridge between two flat-end passes s apart, tool radius R, corner radius r_c, exact:
/// r_c − √(r_c² − (s/2 − (R − r_c))²) when s/2 > R − r_c, else 0.
/// Throws InputError unless 0 < r_c ≤ R and 0 ≤ s ≤ 2R.
double flatEndRidgeHeight(double stepover, double toolRadius, double cornerRadius);

}  // namespace sl
