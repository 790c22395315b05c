// summary.json of an optimize OUTDIR as its readers take it (io/OptimizeOutDir.h lists its keys):
// the viewer, the report and its figures read the file through readOptimizeSummary (or a
// summary in memory through optimizeSummaryFromJson), each listed key typed once here instead of
// by JSON pointers at each reader; the comparison of the three lights (/compare: the user's
// lamp, the paper's light, the optimized one, and the judge's scores of each) as the report's
// headline and table read it, the self-check (/answer), the env map's marked directions, the
// held-out figures, the warnings and the part.
#pragma once

#include <array>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace sl::outdir {

/// One defect region of a judge score (/visibility/k of app/pipeline/Judge.h toJson).
struct JudgedRegion {
    std::string name;                                              // name
    int value = 0;                                                 // value: its label (absent: 0)
    double pixels = 0;                                             // pixels (absent: 0)
    double visibility = std::numeric_limits<double>::quiet_NaN();  // visibility
    double jnd = std::numeric_limits<double>::quiet_NaN();         // jnd
    double contrast = std::numeric_limits<double>::quiet_NaN();    // contrast
};

/// A light's judge score as summary.json records it (app/pipeline/Judge.h toJson); a number
/// that was not finite (written as null) or is absent is NaN.
struct JudgedLight {
    double unbiased = std::numeric_limits<double>::quiet_NaN();    // unbiased: U
    double eq2 = std::numeric_limits<double>::quiet_NaN();         // eq2
    double brightness = std::numeric_limits<double>::quiet_NaN();  // brightness
    double meanE = std::numeric_limits<double>::quiet_NaN();       // mean_E
    double sparsity = std::numeric_limits<double>::quiet_NaN();    // sparsity
    /// visibility: the defect regions; absent (a score without them) is not the same as empty.
    std::optional<std::vector<JudgedRegion>> regions;
    /// se/least_visible_jnd: the least visible kind's JND's standard error (NaN: not estimated).
    double leastVisibleJndSe = std::numeric_limits<double>::quiet_NaN();
};

/// One light of /compare: lamp (the user's), paper (the paper's method on T), optimized.
struct ComparedLight {
    std::string name;                                                // name ("" when absent)
    double trainingLoss = std::numeric_limits<double>::quiet_NaN();  // training/loss
    std::optional<JudgedLight> judge;  // judge: with the judge's estimate
};

/// /compare/answer: a reference (or a finer light) that beat E* on the validation estimate and
/// is the answer (envmap.exr), with what it was chosen on.
struct ComparedAnswer {
    std::string name;          // name ("" when absent)
    std::string merit;         // merit: what the lights were compared by ("" when absent)
    std::string optimizedWhy;  // optimized_why: the check E* failed ("" when it passed)
    double meritAnswer = std::numeric_limits<double>::quiet_NaN();     // merit_answer
    double meritOptimized = std::numeric_limits<double>::quiet_NaN();  // merit_optimized
    std::optional<JudgedLight> judge;                                  // judge
};

/// /compare typed: the three lights side by side, on T and (with the judge's estimate) by the
/// judge; written by app/jobs/OptimizeOutputs.cpp, read by the report
/// (app/report/OptimizeReport.cpp).
struct Comparison {
    std::string objective;               // objective: the objective the training losses are of
    std::optional<std::string> regions;  // regions: where the defect regions came from
    std::string viewing;  // viewing/text: the judge's viewing model in words ("" when absent)
    ComparedLight lamp, paper, optimized;
    std::optional<ComparedAnswer> answer;
};

/// One candidate of the self-check (/answer/candidates/k, app/pipeline/Answer.h answerJson).
struct AnswerCandidate {
    std::string name;                                         // name ("" when absent)
    std::string kind;                                         // kind: optimized, reference, ...
    double merit = std::numeric_limits<double>::quiet_NaN();  // merit (null or absent: NaN)
    bool eligible = true;                                     // eligible (absent: true)
    std::string why;  // why: the check it failed ("" when it passed)
};

/// /answer: the self-check on the validation estimate (app/pipeline/Answer.h answerJson): the
/// light returned, what the candidates were compared by, and each candidate.
struct AnswerCheck {
    std::string light;  // light: the candidate returned ("" when absent)
    std::string kind;   // kind: the returned candidate's kind ("reference": a reference won)
    std::string merit;  // merit: what the candidates were compared by ("" when absent)
    std::vector<AnswerCandidate> candidates;  // candidates
};

/// A direction of /envmap_directions in degrees (scene/EnvMapBasis.h; NaN when absent).
struct EnvDirection {
    double azimuthDeg = std::numeric_limits<double>::quiet_NaN();    // azimuth_deg
    double elevationDeg = std::numeric_limits<double>::quiet_NaN();  // elevation_deg
};

/// /envmap_directions: the directions the report and its figures mark on the env map.
struct EnvDirections {
    std::optional<EnvDirection> camera;   // camera: toward the camera (with a scene)
    std::optional<EnvDirection> mirror;   // mirror: what a flat part reflects into the camera
    std::vector<EnvDirection> brightest;  // brightest: the light's brightest directions
};

/// The keys of optimizeSummaryKeys() that a C++ reader uses, typed; an absent key keeps its
/// default. `document` is the whole file, for what a page shows as written (the run's settings).
struct OptimizeSummary {
    std::string objective;                                     // /objective ("" when absent)
    double lambda = std::numeric_limits<double>::quiet_NaN();  // /lambda
    bool smoothAbs = false;                                    // /smooth_abs
    std::string reg = "envmap";                                // /reg: envmap or image
    std::string defectsMeasure;                                // /defects_measure ("" when absent)
    std::string defects;    // /defects: the defects objective's region as written ("" when absent)
    std::string optimizer;  // /optimizer ("" when absent)
    std::string transportFile;             // /transport/file ("" when absent)
    std::string truth;                     // /truth: the truth label file ("" when absent)
    nlohmann::json initialLoss;            // /initial_loss: a number or null (absent: null)
    nlohmann::json finalLoss;              // /final_loss
    nlohmann::json metrics;                // /metrics: an object (absent: null)
    nlohmann::json metricsInitial;         // /metrics_initial
    nlohmann::json compare;                // /compare: an object as written (absent: null)
    std::optional<Comparison> comparison;  // /compare typed (absent: none)
    std::optional<int> judgeSpp;           // /compare/judge_spp
    std::optional<AnswerCheck> answer;     // /answer: the self-check (absent: none)
    std::optional<EnvDirections> envmapDirections;  // /envmap_directions (absent: none)
    std::vector<std::string> warnings;              // /warnings
    nlohmann::json heightmap;  // /heightmap: the part as read, an object as written (absent: null)
    std::optional<std::array<int, 2>> image;  // /transport/image: T's image width and height
    double heldoutLoss = std::numeric_limits<double>::quiet_NaN();  // /heldout_loss (null: NaN)
    double heldoutU = std::numeric_limits<double>::quiet_NaN();     // /heldout_U
    nlohmann::json document;                                        // the whole summary.json
};

/// A parsed summary.json typed; InputError naming `where` and the key when a listed key has
/// another type (or the document is not a JSON object).
OptimizeSummary optimizeSummaryFromJson(nlohmann::json document, const std::string& where);

/// OUTDIR/summary.json read (bounded, io/InputFile.h) and typed; InputError naming the file when
/// it is missing or malformed, and the key when one has another type.
OptimizeSummary readOptimizeSummary(const std::filesystem::path& outDir);

}  // namespace sl::outdir
