// A relief's plateaus (the selfsim method's step 1b, detect/SelfSimMap.h): a map whose heights
// sit on a few flat levels joined by steps -- a logo or lettering in relief, a stepped part --
// rather than a texture. Its letters do not repeat, so the selfsim estimate cannot explain them:
// a letter stroke narrower than the patch finds only flat copies, and the whole stroke is left
// in the residual as deep as a defect. Here the relief is taken out before the copies are
// compared: each sample's plateau level is subtracted, and what a defect adds (a groove or a pit
// is below its plateau, not on any level) is left.
//
// (h the levelled heights of step 1, W×H, row-major; rms their RMS inside the border)
//  1. Levels: a histogram of h inside the border with bins of binShare × rms; the highest bin
//     not taken is a level, its band the bins around it (at most as many as the first level's)
//     that hold more than bandTail of its count; repeated while a band holds at least
//     minLevelShare of the samples. A band within two bins of a level taken before is that
//     level's shoulder and is not another level.
//  2. The first level's plane: the least-squares quadratic surface through the samples in the
//     first level's band, subtracted, then step 1 again (`refits` times): a relief's letters
//     pull a fit through all samples off its background, which then spans many bins.
//  3. The gate: a relief when there are at least two levels, the first level's band is at most
//     maxHalfWidth × rms wide each side, and at least minCover of the samples lie on plateaus
//     (step 4's pieces of a band). A texture's heights spread over ~rms (its first band is
//     0.35–2 rms wide each side on the measured textures of scripts/eval-real, 0.67–2.2 on
//     gen-surface's parts); the x3ptools logo's are 0.005 rms, on 18 levels holding 0.99 of its
//     samples; maxHalfWidth sits between them, and admits plateaus with some noise
//     (tests/test_relief_levels.cpp). A texture stored with a
//     coarse height quantum (an 8-bit height map) has its heights on a few exact levels too,
//     but in specks, not plateaus: noise quantized to 16 levels has under 1 % on a plateau.
//     minCover is half: the logo alone has 0.99 of its samples on plateaus, but with
//     eval-real's defects on it 0.898-0.936 (model A) and 0.943-0.958 (model B; 34 runs,
//     2026-11-29), and at the gate's first value, 0.9, one of them (A 7103: 0.898) was read as
//     a texture and its letters marked (precision 0.31, recall 0.34); a relief damaged over up
//     to half of it is still one.
//  4. Each sample's plateau: its own level when its height is in a level's band (widened by half
//     a bin each side) and it lies in a 4-connected piece of that band of at least minPlateau
//     samples (a pit or a groove on a letter passing through another level's height leaves a
//     thin ring or line there, not a plateau); else the level of the nearest sample on a
//     plateau (8-connected steps). A sample out of every band with
//     in-band samples of a level above it and of a level below it within rampReach samples is
//     the ramp of a step (explained by the relief, flattened to 0); any other is the plateau's
//     deviation (a defect on it), kept as height − its plateau's level.
// Invariant to h → a·h + b (a > 0) up to rounding; a constant map is no relief.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace sl {

struct ReliefLevelsOptions {
    double binShare = 0.01;  // histogram bin, share of the RMS (> 0)
    double bandTail = 0.05;  // a level's band: neighbouring bins above this share of its peak
    double minLevelShare = 0.0005;  // a level holds at least this share of the samples
    int refits = 3;                 // the first level's quadratic fitted again this many times
    double maxHalfWidth = 0.15;     // a relief's first band at most this × RMS each side
    double minCover = 0.5;          // ... and at least this share of the samples is on plateaus
    int minPlateau = 12;            // a plateau: a 4-connected piece of a band this large (samples)
    int rampReach = 1;              // a step's ramp: levels above and below within this (samples)
};

struct ReliefLevels {
    bool relief = false;           // the gate (step 3) passed
    std::vector<double> levels;    // the levels' heights (first: the most samples)
    size_t plateauLevels = 0;      // relief only: levels with a plateau (the others' samples are
                                   // a defect's passing through their height)
    double halfWidth = 0;          // the first band's half-width (height units)
    double cover = 0;              // share of the samples inside the border on a plateau
                                   // (measured once the bands pass the gate's first tests)
    std::vector<float> flattened;  // relief only: height − its plateau's level, ramps 0
    std::vector<uint8_t> ramp;     // relief only: 1 on a step's ramp
};

/// Steps 1–4 on the levelled heights g (W×H, finite) with `border` samples left out of the
/// statistics; flattened and ramp are filled only when the map is a relief.
ReliefLevels findReliefLevels(std::span<const float> g, int W, int H, int border,
                              const ReliefLevelsOptions& o = {});

}  // namespace sl
