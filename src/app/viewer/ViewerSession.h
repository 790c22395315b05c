// The live relighting viewer's session (README "view"): a ViewerSession holds T, the judge
// (when there is an estimate), two lights A and B and the optimizer from the current light, as
// plain functions the API calls (app/viewer/ViewerApi.h handleViewerRequest: a request in, a
// response out), so everything but the sockets is tested without a server
// (app/viewer/ViewerServer.h serves it over HTTP).
//
// Inputs (ViewerOptions::input):
//   part.tm     T as stored; the judge scores on T's own halves when it has two (else none)
//   SCENE.json  T traced at the scene's spp (or `spp`) as two halves (optimize's objectives
//               need them; T·E is their mean), cached by fingerprint, and the judge's
//               own estimate (app/pipeline/Judge.h, `judgeSpp`), exactly as `judge SCENE.json`
//               scores
//   OUTDIR      an optimize output directory: its summary.json's transport file, its E*
//               (envmap.exr, the preset "optimized"; the paper's light, "paper"), its truth
//               (when recorded) or else its defect regions' layer (view-regions.png), and the
//               judge on optimize's held-out estimate (cached; the report's numbers); or a
//               `lamps` output directory (summary.json names its input and has "greedy"): that
//               scene or .tm as above (the scene without the lamps run's overrides: give them
//               again), its E* (target-envmap.exr, "optimized")
//   In a directory, lamps.json (or ViewerOptions::lamps) gives the preset "lamps": light A is
//   E* when there is one and B the lamps, else A the lamps and B studio.
// A truth label mask (height-map space) gives the judge per-region visibility and the page its
// defect overlay (the regions' outlines, app/report/Preview.h colours).
//
// The page's API, its router and the page: app/viewer/ViewerApi.h.
//
// CONVENTION: the server never writes outside ViewerOptions::outDir.
//
// The optimizer from the current light: on an optimize OUTDIR, the objective that made the
// output (ViewerObjective: summary.json's objective, λ, smooth_abs, its mask.png and, for the
// defects objective, its regions-defects.png / regions-reference.png); otherwise optimize's
// defaults (app/pipeline/Defaults.h defaultObjective: the defects objective when the session has
// defect labels (a truth) and T has halves, the noise-unbiased one with halves, eq. 2 without;
// λ and the loss mask "object" as optimize's defaults). Always optimize's default method at its
// default budget, one start: the slot's light clamped into the optimizer's box [0, 1], one
// estimate of T (the session's T; `estimates` 1). On an OUTDIR of the defects objective without a
// truth the judge scores the same regions as optimize's judge did (one region, "defects", and
// its reference), at the output's λ.
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/pipeline/Cache.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Transport.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "scene/Lamp.h"

namespace sl {

/// The largest texel value a light may hold.
inline constexpr double kViewerMaxTexel = 1e6;
/// The most lamps a light may have.
inline constexpr size_t kViewerMaxLamps = 32;
/// The largest iteration budget POST /api/optimize accepts.
inline constexpr int kViewerMaxIterations = 100000;

struct ViewerOptions {
    std::filesystem::path input;              // part.tm, SCENE.json or an optimize OUTDIR
    std::vector<std::string> sceneOverrides;  // -D key=value on a scene
    std::filesystem::path outDir = "out/view";
    std::optional<int> spp;           // T of a scene: samples per pixel (default: the scene's)
    int judgeSpp = kJudgeDefaultSpp;  // the judge's estimate of a scene
    bool judge = true;                // false: no judge numbers (faster start)
    std::filesystem::path truth;      // label mask in height-map space (optional)
    /// lamps.json (io/LampsFile.h); empty: OUTDIR/lamps.json when the input is a directory that
    /// has one. Loaded lamps are the preset "lamps".
    std::filesystem::path lamps;
    CacheLocation cache;
    int threads = 0;
    int pngLevel = 1;  // zlib level of the images (0..9)
};

/// The objective that made an optimize output, as the viewer reads it back.
struct ViewerObjective {
    ObjectiveKind kind = ObjectiveKind::Unbiased;
    ObjectiveOptions options;   // λ, smooth_abs (summary.json)
    std::vector<uint8_t> mask;  // the loss mask (mask.png; empty: the part)
    std::vector<uint8_t> defects,
        reference;                // the defects objective's regions (app/pipeline/Truth.h)
    bool defectsByShape = false;  // the region is the defect map's own (auto): labelled by shape
};
/// Reads it from an optimize OUTDIR (summary.json "objective", "lambda", "smooth_abs", mask.png,
/// the region files) for a T of width×height; InputError naming the file when one is unfit.
ViewerObjective readViewerObjective(const std::filesystem::path& outDir, int width, int height);

/// What GET /api/optimize reports.
struct ViewerOptimizeStatus {
    std::string state = "idle";  // idle, running, done, stopped, failed
    int slot = 0;
    int run = 0;  // runs started so far
    int iteration = 0, budget = 0;
    double loss = 0, initialLoss = 0, seconds = 0;
    std::string objective, method, error;
    std::vector<std::pair<int, double>> history;  // (iteration, loss), thinned to <= 200 rows
};

/// Timings of the last image request (bench view).
struct ViewerTimings {
    double relightMs = 0, encodeMs = 0;
    size_t pngBytes = 0;
};

class ViewerSession {
  public:
    explicit ViewerSession(const ViewerOptions& options);
    /// A session on a given T (and optional judge estimate with image-space labels; the lamps
    /// of options.lamps), for tests and benchmarks.
    ViewerSession(TransportSource t, std::optional<TransportSource> estimate,
                  const ViewerOptions& options, std::vector<uint8_t> labels = {},
                  std::vector<RegionLabel> legend = {});
    ~ViewerSession();
    ViewerSession(const ViewerSession&) = delete;
    ViewerSession& operator=(const ViewerSession&) = delete;

    const TransportMatrix& transport() const { return t_->file.matrix; }
    const ViewerOptions& options() const { return options_; }
    bool hasJudge() const { return judge_ != nullptr; }
    /// The objective of the optimize OUTDIR the session was opened on (nullopt otherwise).
    const std::optional<ViewerObjective>& outputObjective() const { return made_; }
    std::vector<std::string> presets() const;

    /// Slot 0 = A, 1 = B.
    const std::vector<double>& light(int slot) const { return lights_.at(slot); }
    /// Validated: cols() values, finite, 0 <= v <= kViewerMaxTexel (InputError naming `where`).
    void setLight(int slot, std::vector<double> E, const std::string& where = "E");
    void setPreset(int slot, const std::string& name);

    /// Y = T·E (luminance, T's mean plane).
    std::vector<double> relight(int slot) const;
    /// The texel (row, column) that lights the most of the image: the largest column sum of T.
    std::array<int, 2> hotTexel() const;
    /// The auto exposure of a slot's render (app/report/Preview.h exposureScale).
    double autoExposure(int slot) const;
    /// The render as an 8-bit gray sRGB PNG at `exposure`.
    std::string imagePng(int slot, double exposure, ViewerTimings* timings = nullptr) const;
    /// The judge's numbers for a slot's light (null without a judge).
    nlohmann::ordered_json judgeJson(int slot) const;
    /// The regions' outlines as an RGBA PNG (empty without labels).
    const std::string& overlayPng() const { return overlay_; }
    /// Writes E as outDir/name and T·E as outDir/<stem>-render.exr; returns the E file's path.
    std::filesystem::path save(int slot, const std::string& name) const;
    /// Writes the slot's lamps as outDir/name (lamps.json); InputError without lamps.
    std::filesystem::path saveLamps(int slot, const std::string& name) const;

    /// The lamps a slot's light is made of (empty: painted or a preset without lamps).
    const std::vector<Lamp>& lamps(int slot) const { return lamps_.at(slot); }
    /// The lamps read from lamps.json (the preset "lamps"; empty without a file).
    const std::vector<Lamp>& loadedLamps() const { return loadedLamps_; }
    double lampDistanceMm() const { return lampDistanceMm_; }
    /// Validated (kViewerMaxLamps, each field as POST /api/lamps says; InputError naming
    /// lamps[i] and the field); the slot's light becomes rasterizer().rasterize(lamps).
    void setLamps(int slot, std::vector<Lamp> lamps);
    const LampRasterizer& rasterizer() const;

    /// Starts the optimizer from the slot's light (InputError when one is running or the
    /// budget is out of range; 0: the method's default budget).
    void startOptimize(int slot, int iterations = 0);
    /// Asks a running optimizer to stop at its next iteration (no-op otherwise).
    void stopOptimize();
    ViewerOptimizeStatus optimizeStatus() const;
    /// Blocks until no optimizer runs (tests).
    void waitOptimize();

    /// Serialises requests (the HTTP server's worker threads share one session).
    std::mutex& mutex() { return mutex_; }

  private:
    ViewerOptions options_;
    std::unique_ptr<TransportSource> t_, estimate_;
    std::unique_ptr<Judge> judge_;
    std::vector<uint8_t> labels_;
    ViewingModel viewing_ = defaultViewing();  // the judge's JND: the scene's when it has one
    std::vector<RegionLabel> legend_;
    std::vector<uint8_t> reference_;  // the judge's reference region (empty: the default)
    std::optional<ViewerObjective> made_;
    std::map<std::string, std::vector<double>> extraPresets_;  // "optimized" of an OUTDIR
    std::array<std::vector<double>, 2> lights_;
    std::array<std::vector<Lamp>, 2> lamps_;
    std::vector<Lamp> loadedLamps_;
    double lampDistanceMm_ = 500;
    mutable std::unique_ptr<LampRasterizer> rasterizer_;
    std::string overlay_;
    std::mutex mutex_;
    // The optimizer's thread and its status (guarded by optMutex_, not the session's mutex: the
    // page polls while it runs).
    mutable std::mutex optMutex_;
    std::condition_variable optDone_;
    ViewerOptimizeStatus opt_;
    std::atomic<bool> optStop_{false};
    std::thread optThread_;

    void finishSetup();
    void loadLamps(const std::filesystem::path& file);
    void runOptimize(int slot, std::vector<double> start, int iterations);
};

/// Checks a file name for POST /api/save: 1..64 characters of letters, digits, '-', '_', '.',
/// not starting with '.', no "..", ending in `extension` (".exr" or ".json"), no path
/// separators (InputError naming the fix).
void checkViewerFileName(const std::string& name, const std::string& extension = ".exr");

}  // namespace sl
