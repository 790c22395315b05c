// scratchlight bench X: every benchmark is a row of benchCommands() below, the one table of
// `bench`'s subcommands. For render | transport | scratchmap | read | load | lamps | targets | jnd
// | defectmap | noise | sampling | depth | regions this file parses the options, runs the benchmark
// in the library (app/bench/XBench.h), prints its table and writes its CSV; race and settings
// (RaceCmd.cpp), gradients (GradCheckCmd.cpp) and view (ViewCmd.cpp) sit beside the command whose
// options they share.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <memory>
#include <sstream>

#include "app/bench/DefectMapBench.h"
#include "app/bench/DepthBench.h"
#include "app/bench/JndBench.h"
#include "app/bench/LampsBench.h"
#include "app/bench/LoadBench.h"
#include "app/bench/NoiseBench.h"
#include "app/bench/ReadBench.h"
#include "app/bench/RegionBench.h"
#include "app/bench/RenderBench.h"
#include "app/bench/SamplingBench.h"
#include "app/bench/ScratchMapBench.h"
#include "app/bench/TargetsBench.h"
#include "app/bench/TransportBench.h"
#include "app/host/Plot.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Interrupt.h"
#include "core/Text.h"
#include "io/AtomicFile.h"

namespace sl::cli {

namespace {

double mb(size_t b) {
    return static_cast<double>(b) / 1e6;
}

void logInfo(const std::string& m) {
    spdlog::info("{}", m);
}

/// A benchmark's CSV, after its last safe point (core/Interrupt.h): a Ctrl-C before it writes
/// nothing, one after it lets the file appear whole; then the table's last line names it.
void writeBenchCsv(const std::string& path, const std::string& text) {
    enterCommit();
    writeTextAtomically(path, text);
    std::printf("wrote %s\n", path.c_str());
}

struct RenderBenchArgs {
    RenderBenchOptions o;
    std::string scene, csv = "bench-render.csv";
};

int runRenderBenchCmd(RenderBenchArgs a) {
    a.o.scene = a.scene;
    a.o.log = logInfo;
    const RenderBenchResult r = runRenderBench(a.o);
    std::printf("%-14s %8s %9s %10s %10s %10s | %14s %14s %7s | %14s %14s %7s\n", "height map",
                "gen s", "build s", "vertex MB", "embree MB", "peak MB", "renderer Mr/s",
                "bare Mr/s", "ratio", "part: ren Mr/s", "bare Mr/s", "ratio");
    for (const RenderBenchRow& row : r.rows)
        std::printf(
            "%-14s %8.2f %9.3f %10.1f %10.1f %10.1f | %14.2f %14.2f %6.1f%% | %14.2f %14.2f "
            "%6.1f%%\n",
            row.map.c_str(), row.genSeconds, row.heightfield.buildSeconds,
            mb(row.heightfield.vertexBytes), mb(row.heightfield.embreeBytes),
            mb(row.heightfield.embreePeakBytes), row.renderer.raysPerSecond() / 1e6,
            row.bare.raysPerSecond() / 1e6, 100.0 * row.ratio(),
            row.rendererFootprint.raysPerSecond() / 1e6, row.bareFootprint.raysPerSecond() / 1e6,
            100.0 * row.footprintRatio());
    std::printf(
        "(%dx%d image, %d spp, median of %d interleaved runs; ratio = renderer/bare, on every "
        "pixel, then on the part's footprint only: the pixels a precompute traces)\n",
        a.o.resolution, a.o.resolution, a.o.spp, a.o.repeats);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct TransportBenchArgs {
    TransportBenchOptions o;
    std::string scene, csv = "bench-transport.csv";
};

int runTransportBenchCmd(TransportBenchArgs a) {
    a.o.scene = a.scene;
    const TransportBenchResult r = runTransportBench(a.o);
    std::printf("scene %s at %dx%d, %d spp, max_depth %d\n",
                a.scene.empty() ? "scenes/default (bundled)" : a.scene.c_str(), r.width, r.height,
                a.o.spp, r.maxDepth);
    std::printf("  %-44s %12.2f Mrays/s\n", r.renderer.workload.c_str(),
                r.renderer.raysPerSecond() / 1e6);
    std::printf("  %-44s %12.2f Mrays/s   (%.1f%% of the renderer)\n",
                r.precompute.workload.c_str(), r.precompute.raysPerSecond() / 1e6,
                100.0 * r.precomputeRatio());
    std::printf("  %-44s %12.2f Mrays/s   (precompute: %.1f%% of it)\n", r.bare.workload.c_str(),
                r.bare.raysPerSecond() / 1e6, 100.0 * r.precomputeVsBare());
    std::printf("  T: %s, nnz %zu, density %.4f, %.1f MB\n", r.sparse ? "CSR" : "dense", r.nnz,
                r.density, static_cast<double>(r.bytes) / 1e6);
    std::printf(
        "  T: %.2f bytes per non-zero; slices layout: %.1f MB, %.2f bytes per non-zero, "
        "padding x %.3f, built in %.3f s\n",
        static_cast<double>(r.bytes) / static_cast<double>(r.nnz),
        static_cast<double>(r.slicesBytes) / 1e6,
        static_cast<double>(r.slicesBytes) / static_cast<double>(r.nnz), r.slicesPadding,
        r.slicesBuild);
    std::printf("  %-44s %12.3f ms\n", "streaming read of T's bytes (CSR)", r.streamingRead * 1e3);
    std::printf("  %-44s %12.3f ms\n", "streaming read of the non-zeros alone",
                r.nonZerosRead() * 1e3);
    std::printf("  %-44s %21s %21s\n", "(x: over the streaming read of T)", "CSR", "slices");
    auto row = [&](const char* what, double csr, double slices) {
        std::printf("  %-44s %9.3f ms (%5.2f x) %9.3f ms (%5.2f x)\n", what, csr * 1e3,
                    csr / r.streamingRead, slices * 1e3, slices / r.streamingRead);
    };
    row("T.E (luminance product)", r.apply, r.applySlices);
    std::printf("  %-44s %9.3f ms (%5.2f x) %9.3f ms (%5.2f x)  columns: %.1f MB\n",
                "T'.g: slices | columns (CSC, no scatter)", r.transposeSlices * 1e3,
                r.transposeSlices / r.streamingRead, r.transposeColumns * 1e3,
                r.transposeColumns / r.streamingRead, static_cast<double>(r.columnsBytes) / 1e6);
    row("one iteration, two passes (T.E then T'.g)", r.iterationTwoPass, r.iterationTwoPassSlices);
    row("one iteration, fused single pass", r.iterationFused, r.iterationFusedSlices);
    std::printf("  %-44s %12.3f s %17.3f s\n",
                ("Adam, " + std::to_string(a.o.iterations) + " iterations").c_str(), r.adam,
                r.adamSlices);
    std::printf("  %-44s %12.2f x\n", "fused evaluation on slices / non-zeros' read",
                r.iterationFusedSlices / r.nonZerosRead());
    if (r.unbiasedGram > 0) {
        // The halves' non-zeros alone at the halves' measured read bandwidth (2 + 8 bytes each).
        const double nzRead = r.halvesRead * static_cast<double>(r.halvesNnz) * 10.0 /
                              static_cast<double>(r.halvesBytes);
        std::printf(
            "  unbiased objective on T's halves (optimize's default): nnz %zu, %.1f MB, read "
            "%.3f ms (non-zeros %.3f ms)\n",
            r.halvesNnz, static_cast<double>(r.halvesBytes) / 1e6, r.halvesRead * 1e3,
            nzRead * 1e3);
        std::printf("  %-44s %12s %12s\n", "", "wall", "CPU");
        std::printf("  %-44s %9.3f ms %9.3f ms (%5.2f x its non-zeros' read)\n",
                    "one evaluation through the slices' products", r.unbiasedSlices * 1e3,
                    r.unbiasedSlicesCpu * 1e3, r.unbiasedSlices / nzRead);
        std::printf("  %-44s %9.3f ms %9.3f ms (%5.2f x; %.1f x faster, CPU %.1f x)\n",
                    "one evaluation through T's Gram matrices", r.unbiasedGram * 1e3,
                    r.unbiasedGramCpu * 1e3, r.unbiasedGram / nzRead,
                    r.unbiasedSlices / r.unbiasedGram, r.unbiasedSlicesCpu / r.unbiasedGramCpu);
        std::printf(
            "  %-44s %9.3f ms %9.3f ms (CPU: %.1f evaluations' worth; %.3g multiply-adds, "
            "%.1f MB)\n",
            "the Gram's build", r.gramBuild * 1e3, r.gramBuildCpu * 1e3,
            r.gramBuildCpu / r.unbiasedSlicesCpu, r.gramBuildWork,
            static_cast<double>(r.gramBytes) / 1e6);
        for (const auto& [what, run] :
             {std::pair{"L-BFGS through the slices", r.lbfgsSlices},
              std::pair{"L-BFGS through the Gram (built above)", r.lbfgsGram}})
            std::printf(
                "  %-44s %9.3f s (CPU %.3f s), %4d evaluations, loss %.6g, on an independent "
                "estimate %.6g\n",
                what, run.seconds, run.cpuSeconds, run.evaluations, run.finalLoss, run.heldOutLoss);
        std::printf("  %-44s %9.2g\n", "largest |E*_slices - E*_Gram|", r.lbfgsMaxDifference);
    }
    std::printf("(medians: tracing of %d interleaved runs, products of %d runs)\n", a.o.repeats,
                r.productRepeats);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct TargetsBenchArgs {
    TargetsBenchOptions o;
    std::string csv = "bench-targets.csv";
};

int runTargetsBenchCmd(TargetsBenchArgs a) {
    a.o.log = logInfo;
    const TargetsBenchResult r = runTargetsBench(a.o);
    std::printf("%s", r.table().c_str());
    std::printf(
        "(%s at %dx%d, %d spp with halves, T traced in %.1f s and cached with everything the "
        "first runs keep; each job in this process as the command runs it (no process start-up), "
        "median and range of %d interleaved runs; ratio = median / bound; trace: T and its "
        "validation estimate traced (the scene row); optimizer: its seconds (lamps: the fits "
        "K = 1..K), evals: loss-and-gradient evaluations in them; rest: loading, E* (lamps), "
        "comparison lights, self-check, renders, figures, report); the rows are `optimize "
        "part.tm --lambda %s --heldout none`, the same with the default --heldout, `optimize "
        "SCENE --size %d --spp %d --lambda %s --heldout none` with an empty cache each run, and "
        "`lamps part.tm --count %d`\n",
        a.o.scene.empty() ? "the bundled part" : a.o.scene.c_str(), a.o.size, a.o.size, a.o.spp,
        r.precomputeSeconds, a.o.repeats, formatNumber(a.o.lambda).c_str(), a.o.size, a.o.spp,
        formatNumber(a.o.lambda).c_str(), a.o.lampCount);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct JndBenchArgs {
    JndBenchOptions o;
    std::string csv = "bench-jnd.csv";
};

int runJndBenchCmd(const JndBenchArgs& a) {
    const JndBenchResult r = runJndBench(a.o);
    std::printf("%s", r.table().c_str());
    std::printf(
        "(the bundled part; evaluation rows: T at %d spp with halves, E = 0.5, the JND objective "
        "with its band filters direct and through the Fourier domain (the same operator: loss "
        "diff and grad diff are their relative differences) and the ratio measure, interleaved; "
        "optimize rows: `optimize scene.json --truth part-truth.png --size %d "
        "--defects-measure M` from an empty cache, in this process, interleaved; trace: T and "
        "V of every round; search: every round's; gap SE: the noise rule's standard errors; "
        "answer: the self-check; judge: its estimate and scoring rounds; JND: the judge's, worst "
        "label, of the answer and of the studio lamp)\n",
        a.o.evaluationSpp, a.o.optimizeSize);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct LampsBenchArgs {
    LampsBenchOptions o;
    std::vector<std::string> objectives;
    std::string csv = "bench-lamps.csv";
};

int runLampsBenchCmd(LampsBenchArgs a) {
    if (!a.objectives.empty()) {
        a.o.objectives.clear();
        for (const std::string& n : a.objectives)
            a.o.objectives.push_back(parseObjectiveKind(n, "--objectives"));
    }
    const LampsBenchResult r = runLampsBench(a.o);
    std::printf("%s", r.table().c_str());
    std::printf(
        "(K = %d lamps at %dx%d; judge measure on the held-out 1024-spp estimate: eq. 2 or U "
        "(lower is better) or the defect region's visibility (higher is better); gap: how much "
        "worse the lamps are than E*, relative; fit all/cols: wall seconds of the fit with "
        "products over all of T / over the lamps' texels, one after the other on the same T "
        "and E*; cpu: CPU seconds of all threads)\n",
        a.o.count, a.o.size, a.o.size);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct DefectMapBenchArgs {
    DefectMapBenchOptions o;
    std::string csv = "bench-defectmap.csv";
};

int runDefectMapBenchCmd(const DefectMapBenchArgs& a) {
    const DefectMapBenchResult r = runDefectMapBench(a.o);
    std::printf("%-12s %-20s %10s %8s %9s %9s %7s\n", "height map", "method", "seconds", "ratio",
                "marked", "precision", "recall");
    for (const DefectMapBenchRow& row : r.rows) {
        const std::string size = std::to_string(row.size) + "x" + std::to_string(row.size);
        const auto line = [&](const char* method, double seconds, double ratio, double marked,
                              double precision, double recall) {
            // nothing marked: no precision to show
            char p[32] = "-";
            if (marked > 0) std::snprintf(p, sizeof p, "%.3f", precision);
            std::printf("%-12s %-20s %10.3f %8.1f %8.2f%% %9s %7.3f\n", size.c_str(), method,
                        seconds, ratio, 100.0 * marked, p, recall);
        };
        line("auto (simulator)", row.secondsAuto, row.ratio, row.markedAuto, row.precision,
             row.recall);
        if (a.o.measured)
            line("auto (measured)", row.secondsMeasured, row.ratioMeasured, row.markedMeasured,
                 row.precisionMeasured, row.recallMeasured);
        std::printf("%-12s %-20s %10.3f %8.1f %8.2f%%\n", size.c_str(), "paper scratch map",
                    row.secondsPaper, 1.0, 100.0 * row.markedPaper);
    }
    std::printf(
        "(ball-end test part at NxN, seed 1; median of %d runs; ratio = seconds / the paper's "
        "scratch map's in the same run; auto (measured) = the same heights read as an "
        "instrument's, the selfsim method)\n",
        a.o.repeats);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct ScratchMapBenchArgs {
    ScratchMapBenchOptions o;
    std::string csv = "bench-scratchmap.csv";
};

int runScratchMapBenchCmd(const ScratchMapBenchArgs& a) {
    const ScratchMapBenchResult r = runScratchMapBench(a.o);
    std::printf("%-12s %10s %9s %9s %8s\n", "height map", "seconds", "patches", "marked",
                "marked %");
    for (const ScratchMapBenchRow& row : r.rows)
        std::printf("%-12s %10.3f %9d %9d %7.1f%%\n",
                    (std::to_string(row.size) + "x" + std::to_string(row.size)).c_str(),
                    row.seconds, row.patches, row.patchesMarked, 100.0 * row.markedFraction);
    std::printf("(kernel %d, patch %d, threshold %g; median of %d runs)\n", a.o.map.kernel,
                a.o.map.patch, a.o.map.threshold, a.o.repeats);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct LoadBenchArgs {
    LoadBenchOptions o;
    std::vector<std::string> files;
    std::string csv = "bench-load.csv";
};

int runLoadBenchCmd(LoadBenchArgs a) {
    for (const std::string& f : a.files) a.o.files.emplace_back(f);
    const LoadBenchResult r = runLoadBench(a.o);
    std::printf("%-36s %-22s %7s %8s | %8s %8s | %8s %8s %7s %8s | %8s %-8s | %8s\n", "file",
                "reader", "MB", "Msamples", "raw ms", "MB/s", "read s", "MB/s", "x raw", "CPU s",
                "level s", "", "first s");
    for (const LoadBenchRow& row : r.rows) {
        // the reader's name; its count of invalid points filled stays in the CSV
        const std::string reader = row.reader.substr(0, row.reader.find(','));
        std::printf(
            "%-36s %-22s %7.2f %8.3f | %8.2f %8.0f | %8.3f %8.1f %6.0fx %8.3f | %8.3f %-8s | "
            "%8.3f\n",
            row.file.filename().string().c_str(), reader.c_str(), row.megabytes(),
            row.samples() / 1e6, row.rawSeconds * 1e3, row.rawMBps(), row.readSeconds,
            row.readMBps(), row.readRatio(), row.readCpuSeconds, row.levelSeconds,
            levellingName(row.levelling.applied).c_str(), row.firstSeconds);
    }
    std::printf(
        "(median of %d interleaved runs; raw = the file's bytes into memory, read = "
        "loadHeightmap: decode, fill, resample; x raw = read / raw; level = the default "
        "levelling; first = the first read, a reader module's loading included)\n",
        a.o.repeats);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct ReadBenchArgs {
    ReadBenchOptions o;
    std::string csv = "bench-read.csv";
};

int runReadBenchCmd(const ReadBenchArgs& a) {
    const ReadBenchResult r = runReadBench(a.o);
    std::printf("%-12s %-20s %9s %10s %9s\n", "format", "reader", "MB", "seconds", "vs EXR");
    for (const ReadBenchRow& row : r.rows)
        std::printf("%-12s %-20s %9.1f %10.3f %8.2fx\n", row.format.c_str(), row.reader.c_str(),
                    row.megabytes, row.seconds, row.ratioToExr);
    std::printf("(%dx%d heights, loadHeightmap median of %d reads", a.o.size, a.o.size,
                a.o.repeats);
    if (r.gwyddionInitSeconds > 0)
        std::printf("; Gwyddion's one-time initialisation %.3f s, not included",
                    r.gwyddionInitSeconds);
    std::printf(")\n");
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct NoiseArgs {
    NoiseBenchOptions o;
    std::string optimizers = "adam:100,lbfgs:2000";
    std::string csv = "out/bench-noise/bench-noise.csv";
    bool plot = false;
    std::string groupsCsv() const {
        const auto dot = csv.rfind(".csv");
        return (dot == std::string::npos ? csv : csv.substr(0, dot)) + "-median.csv";
    }
};

int runNoiseBenchCmd(NoiseArgs a) {
    a.o.optimizers = parseNoiseBenchOptimizers(a.optimizers);
    a.o.log = [](const std::string& m) { spdlog::info("{}", m); };
    NoiseBenchResult r = runNoiseBench(a.o);
    std::printf("medians over %d training seed(s); held-out = E* scored on the shared estimate\n",
                a.o.seeds);
    std::printf("%6s %-9s %-12s %5s %10s %11s %11s %14s %10s %26s\n", "spp", "objective",
                "optimizer", "conv", "seconds", "train loss", "held-out", "held-out eq.2",
                "gap tr-ho", "vs top spp (min..max)");
    for (const NoiseBenchGroup& g : r.groups)
        std::printf(
            "%6d %-9s %-12s %2d/%-2d %10.3f %11.5g %11.5g %14.5g %+9.2f%% %+8.2f%% "
            "(%+.2f..%+.2f)\n",
            g.spp, g.objective.c_str(), g.optimizer.c_str(), g.converged, g.runs, g.seconds,
            g.trainLoss, g.heldOutLoss, g.heldOutPaper, 100.0 * g.trainGap, 100.0 * g.relToTop,
            100.0 * g.relToTopMin, 100.0 * g.relToTopMax);
    std::printf(
        "(shared held-out estimate: %d spp, traced in %.1f s; image %dx%d; seconds = "
        "precompute + optimize)\n",
        r.heldOutSpp, r.heldOutSeconds, a.o.resolution, a.o.resolution);
    std::ostringstream os;
    os << "spp,seed,objective,optimizer,iterations,converged,precompute_s,optimize_s,total_s,"
          "train_loss,heldout_loss,heldout_paper_loss,heldout_spp\n";
    for (const NoiseBenchRow& row : r.rows)
        os << row.spp << ',' << row.seed << ',' << row.objective << ',' << row.optimizer << ','
           << row.iterations << ',' << (row.converged ? 1 : 0) << ',' << row.precomputeSeconds
           << ',' << row.optimizeSeconds << ',' << row.seconds() << ',' << row.trainLoss << ','
           << row.heldOutLoss << ',' << row.heldOutPaper << ',' << r.heldOutSpp << '\n';
    std::ostringstream og;
    og << "spp,objective,optimizer,runs,converged,total_s,train_loss,heldout_loss,"
          "heldout_paper_loss,train_gap,rel_to_top,rel_to_top_min,rel_to_top_max,heldout_spp\n";
    for (const NoiseBenchGroup& g : r.groups)
        og << g.spp << ',' << g.objective << ',' << g.optimizer << ',' << g.runs << ','
           << g.converged << ',' << g.seconds << ',' << g.trainLoss << ',' << g.heldOutLoss << ','
           << g.heldOutPaper << ',' << g.trainGap << ',' << g.relToTop << ',' << g.relToTopMin
           << ',' << g.relToTopMax << ',' << r.heldOutSpp << '\n';
    enterCommit();  // both CSVs or neither (core/Interrupt.h)
    writeTextAtomically(a.csv, os.str());
    writeTextAtomically(a.groupsCsv(), og.str());
    std::printf("wrote %s and %s\n", a.csv.c_str(), a.groupsCsv().c_str());
    std::fflush(stdout);
    return runPlot("plot_noise.py", {a.csv}, a.plot);
}

struct SamplingArgs {
    SamplingBenchOptions o;
    std::string scene, csv = "bench-sampling.csv";
};

int runSamplingBenchCmd(SamplingArgs a) {
    a.o.scene = a.scene;
    a.o.log = logInfo;
    const SamplingBenchResult r = runSamplingBench(a.o);
    std::printf("%-12s %6s %10s | %9s %9s %9s %10s | %9s %10s %8s %8s\n", "part", "spp", "sampler",
                "rel RMSE", "net", "mean diff", "Mrays/s", "seconds", "RMSE /bsdf", "time /b",
                "eff. /b");
    for (const SamplingBenchPart& p : r.parts) {
        for (int spp : a.o.spps) {
            const SamplingBenchRow* b = r.find(p.part, Sampling::Bsdf, spp);
            for (const SamplingRow& sr : samplingTable()) {
                const SamplingBenchRow* row = r.find(p.part, sr.value, spp);
                if (!row) continue;
                std::printf("%-12s %6d %10s | %8.3f%% %8.3f%% %+8.3f%% %10.2f | %9.3f",
                            p.part.c_str(), spp, sr.name, 100.0 * row->relRmse,
                            100.0 * row->relRmseNet, 100.0 * row->relMeanDiff,
                            row->raysPerSecond() / 1e6, row->seconds);
                if (row != b && b && b->relRmseNet > 0 && b->seconds > 0) {
                    // Efficiency: 1 / (error² · seconds), against bsdf.
                    const double rr = row->relRmseNet / b->relRmseNet,
                                 tr = row->seconds / b->seconds;
                    std::printf(" %10.3f %8.2f %8.2f", rr, tr, 1.0 / (rr * rr * tr));
                }
                std::printf("\n");
            }
        }
        std::printf(
            "%-12s alpha %g: reference %d spp (%s, two halves) in %.1f s, its own "
            "noise %.3f%%, %zu px on the part\n",
            p.part.c_str(), p.alpha, a.o.referenceSpp,
            registryRow(samplingTable(), kReferenceSampling).name, p.referenceSeconds,
            100.0 * p.referenceNoise, p.pixels);
    }
    std::printf(
        "(%dx%d image under %s; rel RMSE of luminance over the part against the "
        "reference; net = without the reference's own noise; /bsdf: ratios of net "
        "RMSE, seconds and 1/(RMSE^2 s) to bsdf in the same run)\n",
        a.o.resolution, a.o.resolution, a.o.envmap.c_str());
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct DepthArgs {
    DepthBenchOptions o;
    std::string scene, csv = "bench-depth.csv";
};

int runDepthBenchCmd(DepthArgs a) {
    a.o.scene = a.scene;
    const DepthBenchResult r = runDepthBench(a.o);
    std::printf("%9s %14s %12s %9s %12s\n", "max_depth", "energy (E=1)", "this bounce", "seconds",
                "rays");
    for (const DepthBenchRow& row : r.rows)
        std::printf("%9d %14.6g %11.4f%% %9.3f %12llu\n", row.maxDepth, row.energy,
                    100.0 * row.added, row.seconds, static_cast<unsigned long long>(row.rays));
    std::printf("max_depth %d (the scene has %d): %s\n", r.choice.maxDepth, r.sceneMaxDepth,
                r.choice.reason.c_str());
    std::printf(
        "(%dx%d image, %d spp, white light; this bounce = its share of the image at that "
        "max_depth)\n",
        a.o.resolution, a.o.resolution, a.o.spp);
    writeBenchCsv(a.csv, r.csv());
    return kOk;
}

struct RegionArgs {
    RegionBenchOptions o;
    std::string scene, csv = "bench-regions.csv";
};

int runRegionBenchCmd(RegionArgs a) {
    a.o.scene = a.scene;
    const RegionBenchResult r = runRegionBench(a.o);
    const RegionBenchRow& b = r.rows.front();
    std::printf("%-15s %9s %10s %12s %11s %9s %8s %7s %7s %7s\n", "setting", "max_depth", "pixels",
                "rays", "nnz", "T MB", "seconds", "rays", "bytes", "seconds");
    for (const RegionBenchRow& row : r.rows)
        std::printf("%-15s %9d %10llu %12llu %11zu %9.2f %8.3f %6.3fx %6.3fx %6.3fx\n",
                    row.name.c_str(), row.maxDepth, static_cast<unsigned long long>(row.pixels),
                    static_cast<unsigned long long>(row.rays), row.nnz,
                    static_cast<double>(row.bytes) / 1e6, row.seconds,
                    static_cast<double>(row.rays) / static_cast<double>(b.rays),
                    static_cast<double>(row.bytes) / static_cast<double>(b.bytes),
                    row.seconds / b.seconds);
    for (const RegionBenchRow& row : r.rows)
        std::printf("  %s: %s\n", row.name.c_str(), row.detail.c_str());
    std::printf(
        "(%dx%d image, %d spp in two halves; seconds: median of %d interleaved runs; ratios to "
        "'every pixel'; footprint's T is the baseline's bit for bit: %s)\n",
        r.width, r.height, a.o.spp, a.o.repeats, r.rows[1].sameAsBaseline ? "yes" : "NO");
    writeBenchCsv(a.csv, r.csv());
    return r.rows[1].sameAsBaseline ? kOk : kRuntimeError;
}

void addRenderBench(CLI::App* c, std::function<int()>& run) {
    auto a = std::make_shared<RenderBenchArgs>();
    c->add_option("scene", a->scene, "Also measure this scene (optional)");
    addSceneOverrides(c, a->o.sceneOverrides, false);
    c->add_option("--sizes", a->o.sizes, "Synthetic height-map sizes (N for NxN)")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--size", a->o.resolution, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spp", a->o.spp, "Samples per pixel")
        ->check(inRange(1, 4096))
        ->capture_default_str();
    c->add_option("--repeats", a->o.repeats, "Runs per measurement (median)")
        ->check(inRange(1, 50))
        ->capture_default_str();
    c->add_option("--threads", a->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", a->csv, "CSV output")->capture_default_str();
    c->callback([a, &run] { run = [a] { return runRenderBenchCmd(*a); }; });
}

void addTransportBench(CLI::App* c, std::function<int()>& run) {
    auto b = std::make_shared<TransportBenchArgs>();
    c->add_option("scene", b->scene, "Scene file (default: the bundled scenes/default)");
    addSceneOverrides(c, b->o.sceneOverrides, false);
    c->add_option("--size", b->o.resolution, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spp", b->o.spp, "Samples per pixel")
        ->check(inRange(1, 65536))
        ->capture_default_str();
    c->add_option("--iterations", b->o.iterations, "Adam iterations")
        ->check(inRange(1, 1000000))
        ->capture_default_str();
    c->add_option("--repeats", b->o.repeats, "Runs per tracing measurement (median)")
        ->check(inRange(1, 50))
        ->capture_default_str();
    c->add_option("--threads", b->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", b->csv, "CSV output")->capture_default_str();
    c->callback([b, &run] { run = [b] { return runTransportBenchCmd(*b); }; });
}

void addScratchMapBench(CLI::App* c, std::function<int()>& run) {
    auto m = std::make_shared<ScratchMapBenchArgs>();
    c->add_option("--sizes", m->o.sizes, "Height-map sizes (N for NxN)")
        ->delimiter(',')
        ->check(inRange(1, 100000))
        ->capture_default_str();
    c->add_option("--kernel", m->o.map.kernel, "Moving-average window (samples)")
        ->capture_default_str();
    c->add_option("--patch", m->o.map.patch, "Patch side (samples)")->capture_default_str();
    c->add_option("--threshold", m->o.map.threshold, "Patch range threshold in [0, 1]")
        ->capture_default_str();
    c->add_option("--repeats", m->o.repeats, "Runs per size (median)")
        ->check(inRange(1, 10000))
        ->capture_default_str();
    c->add_option("-o,--output", m->csv, "CSV output")->capture_default_str();
    c->callback([m, &run] { run = [m] { return runScratchMapBenchCmd(*m); }; });
}

void addReadBench(CLI::App* c, std::function<int()>& run) {
    auto rb = std::make_shared<ReadBenchArgs>();
    c->add_option("--size", rb->o.size, "N for the NxN height map")
        ->check(inRange(2, 20000))
        ->capture_default_str();
    c->add_option("--repeats", rb->o.repeats, "Reads per file (median)")
        ->check(inRange(1, 50))
        ->capture_default_str();
    c->add_option("-o,--output", rb->csv, "CSV output")->capture_default_str();
    c->callback([rb, &run] { run = [rb] { return runReadBenchCmd(*rb); }; });
}

void addLoadBench(CLI::App* c, std::function<int()>& run) {
    auto lb = std::make_shared<LoadBenchArgs>();
    c->add_option("files", lb->files, "Height-map files (any format a command reads)")->required();
    c->add_option("--repeats", lb->o.repeats, "Interleaved runs (median)")
        ->check(inRange(1, 100))
        ->capture_default_str();
    c->add_option("-o,--output", lb->csv, "CSV output")->capture_default_str();
    c->callback([lb, &run] { run = [lb] { return runLoadBenchCmd(*lb); }; });
}

void addLampsBench(CLI::App* c, std::function<int()>& run) {
    auto lb = std::make_shared<LampsBenchArgs>();
    c->add_option("--parts", lb->o.parts, "bundled and/or race parts")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--objectives", lb->objectives, "Objectives (default: unbiased,paper,defects)")
        ->delimiter(',');
    c->add_option("--count", lb->o.count, "Lamps (K)")->check(inRange(1, 8))->capture_default_str();
    c->add_option("--size", lb->o.size, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--work", lb->o.workDir, "Folder for the parts, runs and cache")
        ->capture_default_str();
    c->add_option("-o,--output", lb->csv, "CSV output")->capture_default_str();
    c->callback([lb, &run] { run = [lb] { return runLampsBenchCmd(*lb); }; });
}

void addTargetsBench(CLI::App* c, std::function<int()>& run) {
    auto tb = std::make_shared<TargetsBenchArgs>();
    c->add_option("--scene", tb->o.scene, "Scene file (default: the bundled part)");
    c->add_option("--size", tb->o.size, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spp", tb->o.spp, "spp of T (two halves)")
        ->check(inRange(2, 65536))
        ->capture_default_str();
    c->add_option("--lambda", tb->o.lambda, "The other lambda of the re-optimization")
        ->check(nonNegativeNumber())
        ->capture_default_str();
    c->add_option("--count", tb->o.lampCount, "Lamps (K)")
        ->check(inRange(1, 8))
        ->capture_default_str();
    c->add_option("--repeats", tb->o.repeats, "Timed runs of each target")
        ->check(inRange(1, 50))
        ->capture_default_str();
    c->add_option("--work", tb->o.workDir, "Folder for T, the cache and the runs' outputs")
        ->capture_default_str();
    c->add_option("-o,--output", tb->csv, "CSV output")->capture_default_str();
    c->callback([tb, &run] { run = [tb] { return runTargetsBenchCmd(*tb); }; });
}

void addJndBench(CLI::App* c, std::function<int()>& run) {
    auto jb = std::make_shared<JndBenchArgs>();
    c->add_option("--sizes", jb->o.sizes, "Image sizes (N for NxN) of the evaluation rows")
        ->delimiter(',')
        ->check(inRange(16, 4096))
        ->capture_default_str();
    c->add_option("--spp", jb->o.evaluationSpp, "spp of T (two halves) for the evaluation rows")
        ->check(inRange(2, 65536))
        ->capture_default_str();
    c->add_option("--evaluations", jb->o.evaluations, "Timed evaluations per size and method")
        ->check(inRange(1, 100))
        ->capture_default_str();
    c->add_option("--optimize-size", jb->o.optimizeSize,
                  "Image size of the optimize rows (0: no optimize rows)")
        ->check(inRange(0, 4096))
        ->capture_default_str();
    c->add_option("--repeats", jb->o.repeats, "Interleaved optimize runs per measure")
        ->check(inRange(1, 20))
        ->capture_default_str();
    c->add_option("--work", jb->o.workDir, "Folder for T, the caches and the runs' outputs")
        ->capture_default_str();
    c->add_option("-o,--output", jb->csv, "CSV output")->capture_default_str();
    c->callback([jb, &run] { run = [jb] { return runJndBenchCmd(*jb); }; });
}

void addDefectMapBench(CLI::App* c, std::function<int()>& run) {
    auto dm = std::make_shared<DefectMapBenchArgs>();
    c->add_option("--sizes", dm->o.sizes, "Height-map sizes (N for NxN)")
        ->delimiter(',')
        ->check(inRange(2, 100000))
        ->capture_default_str();
    c->add_option("--repeats", dm->o.repeats, "Runs per size (median)")
        ->check(inRange(1, 50))
        ->capture_default_str();
    c->add_option("--texture-sectors", dm->o.map.textureSectors,
                  "auto: orientation sectors of the texture-change test (1: the texture whole)")
        ->check(inRange(1, 16))
        ->capture_default_str();
    c->add_option("--measured", dm->o.measured,
                  "Also time auto on the heights read as a measured texture (the selfsim method)")
        ->capture_default_str();
    c->add_option("-o,--output", dm->csv, "CSV output")->capture_default_str();
    c->callback([dm, &run] { run = [dm] { return runDefectMapBenchCmd(*dm); }; });
}

void addNoiseBench(CLI::App* c, std::function<int()>& run) {
    auto n = std::make_shared<NoiseArgs>();
    c->add_option("scene", n->o.scene, "Scene file")->required();
    addSceneOverrides(c, n->o.sceneOverrides, false);
    c->add_option("--size", n->o.resolution, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spps", n->o.spps, "Training spp values (even)")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--heldout-spp", n->o.heldOutSpp, "spp of the shared held-out estimate")
        ->capture_default_str();
    c->add_option("--seeds", n->o.seeds, "Training seeds per spp (medians over them)")
        ->check(inRange(1, 100))
        ->capture_default_str();
    c->add_option("--optimizers", n->optimizers,
                  "METHOD[:BUDGET],... (budget: adam steps, NLopt evaluations, Ceres "
                  "iterations)")
        ->capture_default_str();
    c->add_option("--threads", n->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", n->csv, "CSV output")->capture_default_str();
    c->add_flag("--plot", n->plot, "Also run scripts/plot_noise.py on the CSV");
    c->callback([n, &run] { run = [n] { return runNoiseBenchCmd(*n); }; });
}

void addSamplingBench(CLI::App* c, std::function<int()>& run) {
    auto sa = std::make_shared<SamplingArgs>();
    c->add_option("scene", sa->scene, "Scene file (default: the bundled scenes/default)");
    addSceneOverrides(c, sa->o.sceneOverrides, false);
    c->add_option("--alphas", sa->o.alphas,
                  "Parts: 0 = the scene's material, else the scene with material.alpha = A")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--envmap", sa->o.envmap, "Light: a file, const:V or a preset")
        ->capture_default_str();
    c->add_option("--size", sa->o.resolution, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spps", sa->o.spps, "Sample counts compared")
        ->delimiter(',')
        ->capture_default_str();
    c->add_option("--reference-spp", sa->o.referenceSpp, "spp of the reference (two halves, even)")
        ->capture_default_str();
    c->add_option("--threads", sa->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", sa->csv, "CSV output")->capture_default_str();
    c->callback([sa, &run] { run = [sa] { return runSamplingBenchCmd(*sa); }; });
}

void addDepthBench(CLI::App* c, std::function<int()>& run) {
    auto da = std::make_shared<DepthArgs>();
    c->add_option("scene", da->scene, "Scene file (default: the bundled scenes/default)");
    addSceneOverrides(c, da->o.sceneOverrides, false);
    c->add_option("--size", da->o.resolution, "Image width and height")
        ->check(inRange(8, 4096))
        ->capture_default_str();
    c->add_option("--spp", da->o.spp, "Samples per pixel")
        ->check(inRange(1, 65536))
        ->capture_default_str();
    c->add_option("--max-depth", da->o.maxDepth, "Longest path length measured")
        ->check(inRange(3, 64))
        ->capture_default_str();
    c->add_option("--threshold", da->o.threshold,
                  "Stop when the next bounce adds less than this share of the image")
        ->capture_default_str();
    c->add_option("--threads", da->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", da->csv, "CSV output")->capture_default_str();
    c->callback([da, &run] { run = [da] { return runDepthBenchCmd(*da); }; });
}

void addRegionsBench(CLI::App* c, std::function<int()>& run) {
    auto ra = std::make_shared<RegionArgs>();
    c->add_option("scene", ra->scene, "Scene file (default: the bundled scenes/default)");
    addSceneOverrides(c, ra->o.sceneOverrides, false);
    c->add_option("--size", ra->o.resolution, "Image width and height")
        ->check(inRange(8, 8192))
        ->capture_default_str();
    c->add_option("--spp", ra->o.spp, "Samples per pixel (even: two halves)")
        ->check(inRange(2, 65536))
        ->capture_default_str();
    c->add_option("--repeats", ra->o.repeats, "Interleaved runs (median)")
        ->check(inRange(1, 100))
        ->capture_default_str();
    c->add_option("--threads", ra->o.threads, "Worker threads (0: all)")->capture_default_str();
    c->add_option("-o,--output", ra->csv, "CSV output")->capture_default_str();
    c->callback([ra, &run] { run = [ra] { return runRegionBenchCmd(*ra); }; });
}

}  // namespace

/// Every `bench X`, in `bench --help`'s order: its name, its help line and what adds its options
/// (defined beside the command it measures where that shares them: `race` and `settings` in
/// RaceCmd.cpp, `gradients` in GradCheckCmd.cpp, `view` in ViewCmd.cpp).
const std::vector<BenchCommand>& benchCommands() {
    static const std::vector<BenchCommand> table = {
        {"render", "Renderer rays/s vs bare Embree closest-hit rays/s; height-field build cost",
         addRenderBench},
        {"transport", "Precompute vs render rays/s; Adam on T; one iteration vs a read of T",
         addTransportBench},
        {"scratchmap", "Seconds of the paper's scratch map on synthetic NxN height maps",
         addScratchMapBench},
        {"read",
         "Seconds to read an NxN height map from instrument files (X3P by our reader and by "
         "Gwyddion's, Gwyddion's .gwy) against the same heights from EXR",
         addReadBench},
        {"load",
         "Where loading your height-map files goes: each file's reader (decode, fill, resample) "
         "and levelling, seconds and MB/s, against a raw read of the same bytes",
         addLoadBench},
        {"lamps",
         "K lamps against E* on the judge's parts per objective (judge scores), and the fit's "
         "seconds with products over the lamps' texels vs over all of T",
         addLampsBench},
        {"targets",
         "Issue 32's wall-clock targets, a row each with its ratio to the bound: re-optimizing a "
         "cached T with another lambda (held-out none, and the judge's), the first answer from the "
         "scene (nothing cached), lamps K = 3",
         addTargetsBench},
        {"jnd",
         "Seconds of one JND evaluation per image size (band filters direct vs Fourier, and the "
         "ratio measure), and of optimize --truth on the bundled part, jnd vs ratio, by phase",
         addJndBench},
        {"defectmap",
         "Seconds of the defect map (auto) next to the paper's scratch map on the NxN ball-end "
         "test part",
         addDefectMapBench},
        {"noise",
         "Speed against quality: spp sweep over training seeds, paper vs noise-unbiased objective, "
         "each optimizer's budget, scored on one shared high-spp independent estimate",
         addNoiseBench},
        {"sampling",
         "Noise per ray: relative RMSE against a converged reference at equal spp, BSDF-only vs "
         "MIS sampling, on the scene and on mirror-like variants; rays/s",
         addSamplingBench},
        {"depth",
         "Energy each further bounce adds under a white light, and the max_depth after which the "
         "next bounce adds less than a threshold of the image",
         addDepthBench},
        {"regions",
         "What tracing only what the scene needs saves: every pixel, the part's footprint, a "
         "mask's pixels, max_depth auto (rays, bytes, seconds)",
         addRegionsBench},
        {"race", "Race optimizer configurations on generated parts, scored by the judge",
         addRaceBench},
        {"settings",
         "Speed against error: the judge's score of E* against seconds for spp x sampling x "
         "max_depth",
         addSettingsBench},
        {"gradients",
         "Seconds against gradient error for exact, autodiff, FD and SPSA, and loss against "
         "wall-clock seconds for whole optimizations (CSV + plots)",
         addGradientsBench},
        {"view", "The viewer's latency: relight + PNG encode + transfer under an HTTP client",
         addViewBench},
    };
    return table;
}

void registerBench(CLI::App& app, std::function<int()>& run) {
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks (print a table, write CSV)");
    bench->require_subcommand(1);
    for (const BenchCommand& b : benchCommands()) b.add(bench->add_subcommand(b.name, b.help), run);
}

}  // namespace sl::cli
