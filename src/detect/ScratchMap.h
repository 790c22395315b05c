// The cutting-scratch map of the paper's §5.1 (Motegi et al.): a binary map, in height-map
// space, of the patches where the detrended surface varies a lot (a scratch, a gouge, or an
// edge of the macro shape).
//
// Definition, step by step (every number in double unless said otherwise):
//  1. Detrend: D(j, i) = h(j, i) − A(j, i), where A is the moving average of h over the
//     kernel×kernel box of samples rows j − (K−1)/2 … j + K/2, columns i − (K−1)/2 … i + K/2
//     (K = kernel; centred for odd K, one more sample after the centre for even K).
//     Borders: the window SHRINKS to the samples inside the map (A is the mean of the samples
//     of the box that exist), no padding. Computed as a separable running box sum of
//     (h − mean(h)) (the global mean is subtracted first so the running sums do not cancel),
//     O(W·H) whatever K, parallel over bands of patch rows.
//  2. Scale: S = (D − min D) / (max D − min D), min and max over the whole map (a flat map,
//     max D = min D, gives S = 0 everywhere and marks nothing).
//  3. Patches: non-overlapping patch×patch tiles starting at sample (0, 0); tiles at the right
//     and bottom borders are partial (narrower/shorter) and included. A tile is marked when
//     max S − min S over its samples ≥ threshold, and then every sample of the tile is marked.
// The result is invariant to an affine change of the heights (h → a·h + b, a > 0), so integer
// height maps need no height range.
//
// The paper's parameters (its 5000×5000 data): kernel 21, patch 40, threshold 0.03. NOTE: the
// scaling to [0, 1] uses the map's global extremes, so a deep defect or a macro-shape edge
// (a pocket wall) compresses every other patch's range: the threshold is relative.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace sl {

struct ScratchMapOptions {
    int kernel = 21;          // moving-average window, samples (>= 1)
    int patch = 40;           // patch side, samples (>= 1)
    double threshold = 0.03;  // on the [0, 1]-scaled detrended map, in [0, 1]
};

struct ScratchMap {
    int width = 0, height = 0;       // of the height map
    std::vector<uint8_t> map;        // width*height, row-major: 255 marked, 0 not
    int patchesX = 0, patchesY = 0;  // tiles per row / column (partial ones included)
    int patchesMarked = 0;
    double detrendedMin = 0, detrendedMax = 0;  // min/max of D (height units)
    double seconds = 0;

    double markedFraction() const;  // marked samples / all samples
};

/// Computes the scratch map of a width×height height map (row-major, row 0 first).
/// Throws InputError for bad options (naming option 'kernel', 'patch' or 'threshold'), a size
/// mismatch, a map smaller than 1×1 or a non-finite height (naming its row and column).
ScratchMap computeScratchMap(std::span<const float> heights, int width, int height,
                             const ScratchMapOptions& options = {});

/// Step 1 alone: the detrended map D (width*height, double), for figures and tests.
std::vector<double> detrendHeights(std::span<const float> heights, int width, int height,
                                   int kernel = 21);

}  // namespace sl
