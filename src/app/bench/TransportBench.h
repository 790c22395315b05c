// `scratchlight bench transport`: what precomputing T costs against rendering (the same tracer
// with the transport sink instead of the radiance sink) and against bare Embree closest hits on
// the same camera rays (all three interleaved), T's size, and what an
// iteration on T costs against one streaming read of T's bytes (products, one loss-and-gradient
// evaluation in two passes and fused, a whole Adam run), each on T's CSR arrays and on the
// slices layout (transport/TransportSlices.h) side by side; and the noise-unbiased objective's
// evaluation on T's halves through the slices and through T's Gram matrices
// (transport/TransportGram.h).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "render/Benchmark.h"

namespace sl {

struct TransportBenchOptions {
    std::filesystem::path scene;              // empty: the bundled default scene (app/host/Plot.h)
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    int resolution = 512, spp = 64;           // image N×N, samples per pixel
    int iterations = 100;                     // Adam iterations of the whole-run measurement
    int repeats = 3;  // interleaved tracing runs (median); products: 4·repeats+1
    int threads = 0;  // 0: all cores
};

struct TransportBenchResult {
    TransportBenchOptions options;
    int width = 0, height = 0, maxDepth = 0;
    ThroughputRow renderer, precompute;  // medians over the repeats
    /// Bare Embree closest hits on the same camera rays (render/Benchmark.h), interleaved.
    ThroughputRow bare;
    bool sparse = true;  // T's storage: CSR or dense
    size_t nnz = 0, bytes = 0;
    int stride = 1;  // floats per entry (channels · planes)
    double density = 0;
    // The slices layout of T (transport/TransportSlices.h) the loss reads by default.
    size_t slicesBytes = 0;
    double slicesPadding = 0;  // its stored entries over T's non-zeros (1 = no padding)
    double slicesBuild = 0;    // seconds to build it from T
    int productRepeats = 0;
    double streamingRead = 0;  // seconds (medians from here on) of one read of T's CSR bytes
    // Each product on T's CSR arrays (the old path) and on the slices layout, measured
    // interleaved (CSR, slices, CSR, ...) so that both see the same load.
    double apply = 0, applySlices = 0;  // T·E (luminance)
    double iterationTwoPass = 0, iterationTwoPassSlices = 0;
    double iterationFused = 0, iterationFusedSlices = 0;
    double adam = 0, adamSlices = 0;  // `iterations` Adam steps (fused evaluations)
    /// Tᵀ·g alone on the slices and on the columns layout (transport/TransportColumns.h,
    /// transposeAll), interleaved; and the columns' bytes.
    double transposeSlices = 0, transposeColumns = 0;
    size_t columnsBytes = 0;
    /// The noise-unbiased objective on T's halves (optimize's default; T traced once more
    /// with two sample sets): one loss-and-gradient evaluation through the slices' products
    /// and through T's Gram matrices (transport/TransportGram.h), interleaved; the Gram's
    /// build (seconds, multiply-adds) and bytes; the halves' non-zeros and one streaming read
    /// of their bytes.
    size_t halvesNnz = 0, halvesBytes = 0, gramBytes = 0;
    double halvesRead = 0, gramBuild = 0, gramBuildWork = 0;
    double unbiasedSlices = 0, unbiasedGram = 0;
    /// The same in process CPU seconds (medians of batches of 10, interleaved): on a machine
    /// shared with other work a sub-millisecond step's wall time is mostly the scheduler's.
    double unbiasedSlicesCpu = 0, unbiasedGramCpu = 0, gramBuildCpu = 0;
    /// L-BFGS (optimize's default method, its default budget) from the same start through
    /// each: seconds, evaluations, final loss on T, and the loss of its E* on an independent
    /// estimate of T's halves (another seed: a held-out check that the answers are as good);
    /// the largest difference between the two E*.
    struct LbfgsRun {
        double seconds = 0, cpuSeconds = 0, finalLoss = 0, heldOutLoss = 0;
        int evaluations = 0;
    };
    LbfgsRun lbfgsSlices, lbfgsGram;
    double lbfgsMaxDifference = 0;

    /// The time one streaming read of T's non-zeros alone takes, nnz·(2 + 4·stride) bytes at
    /// the measured streaming read's bandwidth (the row pointers left out).
    double nonZerosRead() const;

    double precomputeRatio() const;   // precompute rays/s over renderer rays/s
    double precomputeVsBare() const;  // precompute rays/s over bare Embree rays/s
    std::string csv() const;          // header + one line
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
TransportBenchResult runTransportBench(const TransportBenchOptions& options);

}  // namespace sl
