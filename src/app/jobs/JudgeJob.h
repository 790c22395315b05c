// The `judge` job: scores env-map files (and the built-in references) on the judge's
// independent estimate of a scene, and writes what a person looks at.
//
// OUTDIR holds:
//   judge.json    one entry per light (app/pipeline/Judge.h toJson, with its standard errors) plus the
//                 estimate's facts (its spp and the rounds that chose it)
//   judge.csv     one row per light: name, eq2, unbiased, mean_E, sparsity, brightness,
//                 per-region visibility, contrast and Weber contrast
//   renders.exr   the mean renders side by side (linear luminance, one panel per light, in
//                 table order)
//   renders.png   the same, each panel exposed on its own (99th percentile of the part → 0.8)
//   report.html   a page a browser opens: per light its render with the truth regions
//                 outlined (light-<k>.png; plain: light-<k>-render.png), its env map
//                 (light-<k>-envmap.png) and its scores,
//                 per-region visibility and contrast side by side
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/pipeline/Cache.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Truth.h"

namespace sl {

struct JudgeJobOptions {
    std::filesystem::path scene;
    std::vector<std::string> sceneOverrides;  // -D key=value on the scene (io/SceneFile.h)
    /// Env-map files (EXR/HDR/PNG…), or optimize output directories (their envmap.exr).
    std::vector<std::filesystem::path> lights;
    bool references = true;  // also score uniform 0.5 and the studio preset
    /// The defects objective's regions, as optimize takes them (app/pipeline/Truth.h): with `defects`
    /// (a mask, TRUTH.png:LABEL,... with judge.truth, or auto: the defect map) the visibility is
    /// that of this one region, "defects", as optimize's held-out judge scores it, instead of
    /// the truth's labels; `reference` (optional) is the surface it is compared with (default:
    /// the part away from the defects).
    RegionSpec defects, reference;
    JudgeOptions judge;   // its cacheDir is set from `cache`
    CacheLocation cache;  // where the estimate is cached (app/pipeline/Cache.h)
    std::filesystem::path outDir = "out/judge";
    std::string commandLine;  // how the run was asked for: recorded in judge.json, not parsed
};

struct JudgeJobSummary {
    TransportSource estimate;
    std::vector<JudgeScore> scores;  // lights in the order given, then the references
    JudgedRounds rounds;             // the spp the scores' standard errors asked for
    std::string json;                // the text of judge.json
};

JudgeJobSummary runJudgeJob(const JudgeJobOptions& options);

/// Writes `images` (each width×height luminance) side by side as EXR and PNG (`stem`.exr/.png).
void writeSideBySide(const std::filesystem::path& stem,
                     const std::vector<std::vector<double>>& images, int width, int height,
                     const std::vector<uint8_t>& partMask);

}  // namespace sl
