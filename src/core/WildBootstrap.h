// The standard error of scores formed from two independent half estimates of an image, by a
// wild bootstrap on the halves: the judge's errors (app/pipeline/Judge.h scoreWithErrors) and the
// noise rule's gap (app/pipeline/TrainingNoise.h trainingGapError) are this one estimate.
//
// A pixel's samples are independent of every other pixel's, and its two halves Y_a, Y_b are two
// independent estimates of the same value, so d_p = Y_a,p − Y_b,p has mean 0 and variance
// 2·var(Y_a,p). Each replicate perturbs the halves by ±d_p/√2, with independent signs per pixel
// and half (Rademacher weights; a fixed seed, so the same images give the same errors), and forms
// the scores again; the standard error is the replicates' spread, robustly (robustSpread). Several
// images made by the same samples (a light's and the white furnace's) take the same signs. To
// first order this is the delta method's standard error without the scores' derivatives; it
// falls as 1/sqrt(spp).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

namespace sl {

/// One image as two independent half estimates (width*height each).
struct HalfImages {
    std::vector<double> a, b;
};

/// The spread of replicates as a standard deviation, robustly: 1.4826 × their median absolute
/// deviation (a normal spread's standard deviation; a replicate whose denominator nearly
/// vanished does not decide it). Non-finite replicates are dropped; NaN when fewer than half of
/// `replicates` (or fewer than 2) remain.
double robustSpread(std::vector<double> values, int replicates);

/// The scores of one replicate: the perturbed images, in the order given.
using ReplicateScores = std::function<std::vector<double>(std::span<const HalfImages> images)>;

/// The standard error of each score `scores` returns (always the same count), over `replicates`
/// replicates of `images` (all of the same size) drawn with `seed`. The replicates run on
/// `threads` threads at once (0: one per core; `scores` is then called concurrently, each call
/// with its own images); replicate r's signs depend on (seed, r) only and the spread on the
/// set of replicates, so the errors are the same, bit for bit, on any number of threads.
std::vector<double> wildBootstrapErrors(std::span<const HalfImages> images, uint64_t seed,
                                        int replicates, const ReplicateScores& scores,
                                        int threads = 0);

}  // namespace sl
