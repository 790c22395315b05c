// `scratchlight bench transport`: what precomputing T costs against rendering (the same tracer
// with the transport sink instead of the radiance sink, interleaved), T's size, and what an
// iteration on T costs against one streaming read of T's bytes (products, one loss-and-gradient
// evaluation in two passes and fused, a whole Adam run).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "render/Benchmark.h"

namespace sl {

struct TransportBenchOptions {
    std::filesystem::path scene;              // empty: the bundled default scene (app/Plot.h)
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
    bool sparse = true;                  // T's storage: CSR or dense
    size_t nnz = 0, bytes = 0;
    double density = 0;
    int productRepeats = 0;
    double streamingRead = 0;  // seconds (medians from here on)
    double apply = 0;          // T·E (luminance)
    double iterationTwoPass = 0;
    double iterationFused = 0;
    double adam = 0;  // `iterations` Adam steps

    double precomputeRatio() const;  // precompute rays/s over renderer rays/s
    std::string csv() const;         // header + one line
};

/// Runs the benchmark. Throws InputError for a bad scene or option.
TransportBenchResult runTransportBench(const TransportBenchOptions& options);

}  // namespace sl
