// summary.json of an optimize OUTDIR as its readers take it (io/OptimizeOutDir.h lists its keys):
// the viewer and the report read the file through readOptimizeSummary, each listed key typed
// once here instead of by JSON pointers at each reader.
#pragma once

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace sl::outdir {

/// The keys of optimizeSummaryKeys() that a C++ reader uses, typed; an absent key keeps its
/// default. `document` is the whole file, for what a page shows as written (the judge's
/// scores under /compare, the run's settings).
struct OptimizeSummary {
    std::string objective;                                     // /objective ("" when absent)
    double lambda = std::numeric_limits<double>::quiet_NaN();  // /lambda
    bool smoothAbs = false;                                    // /smooth_abs
    std::string reg = "envmap";                                // /reg: envmap or image
    std::string defectsMeasure;                                // /defects_measure ("" when absent)
    std::string optimizer;                                     // /optimizer ("" when absent)
    std::string transportFile;                                 // /transport/file ("" when absent)
    std::string truth;              // /truth: the truth label file ("" when absent)
    nlohmann::json initialLoss;     // /initial_loss: a number or null (absent: null)
    nlohmann::json finalLoss;       // /final_loss
    nlohmann::json metrics;         // /metrics: an object (absent: null)
    nlohmann::json metricsInitial;  // /metrics_initial
    nlohmann::json compare;         // /compare: an object (absent: null)
    std::optional<int> judgeSpp;    // /compare/judge_spp
    nlohmann::json document;        // the whole summary.json
};

/// A parsed summary.json typed; InputError naming `where` and the key when a listed key has
/// another type (or the document is not a JSON object).
OptimizeSummary optimizeSummaryFromJson(nlohmann::json document, const std::string& where);

/// OUTDIR/summary.json read (bounded, io/InputFile.h) and typed; InputError naming the file when
/// it is missing or malformed, and the key when one has another type.
OptimizeSummary readOptimizeSummary(const std::filesystem::path& outDir);

}  // namespace sl::outdir
