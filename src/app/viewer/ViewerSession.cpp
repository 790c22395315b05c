#include "app/viewer/ViewerSession.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "app/pipeline/Defaults.h"
#include "app/pipeline/JudgeEstimate.h"
#include "app/pipeline/LossMask.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Truth.h"
#include "app/report/Preview.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Progress.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/LampsFile.h"
#include "io/OptimizeOutDir.h"
#include "io/OptimizeSummary.h"
#include "io/PngBuffer.h"
#include "io/SceneFile.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

json readJsonFile(const fs::path& file) {
    return readJsonInput(file, "a summary");
}

/// The regions' boundary pixels in their outline colours, transparent elsewhere.
std::string outlinePng(const std::vector<uint8_t>& labels, int w, int h) {
    std::vector<uint8_t> rgba(static_cast<size_t>(w) * h * 4, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t p = static_cast<size_t>(y) * w + x;
            const uint8_t v = labels[p];
            if (!v) continue;
            const bool edge = x == 0 || y == 0 || x == w - 1 || y == h - 1 || labels[p - 1] != v ||
                              labels[p + 1] != v || labels[p - w] != v || labels[p + w] != v;
            if (!edge) continue;
            const OutlineColour& c = outlineOf(v);
            rgba[4 * p + 0] = static_cast<uint8_t>(std::lround(255.0f * srgbEncode(c.r)));
            rgba[4 * p + 1] = static_cast<uint8_t>(std::lround(255.0f * srgbEncode(c.g)));
            rgba[4 * p + 2] = static_cast<uint8_t>(std::lround(255.0f * srgbEncode(c.b)));
            rgba[4 * p + 3] = 255;
        }
    return encodePng8(rgba, w, h, 4, 6);
}

}  // namespace

ViewerObjective readViewerObjective(const fs::path& dir, int width, int height) {
    const fs::path file = dir / outdir::kSummary;
    const outdir::OptimizeSummary s = outdir::readOptimizeSummary(dir);
    if (s.objective.empty() || !std::isfinite(s.lambda))
        throw inputError(file.string(), "has no usable objective: no objective or no lambda",
                         "run view on the output of a current optimize");
    ViewerObjective o;
    o.kind = parseObjectiveKind(s.objective, file.string());
    o.options.lambda = s.lambda;
    o.options.smoothAbs = s.smoothAbs;
    o.options.reg = s.reg == "image" ? RegTarget::Image : RegTarget::EnvMap;
    o.options.defectMeasure = parseDefectMeasure(
        s.defectsMeasure.empty() ? std::string(defectMeasureName(DefectMeasure::Ratio))
                                 : s.defectsMeasure,
        file.string() + ": defects_measure");
    if (fs::exists(dir / outdir::kMaskPng)) {
        o.mask = loadImageMask(dir / outdir::kMaskPng, width, height);
        for (uint8_t& v : o.mask) v = v ? 1 : 0;  // masks hold 0/1 (app/pipeline/LossMask.h)
    }
    if (o.kind == ObjectiveKind::Defects) {
        auto regions = readDefectRegions(dir, width, height);
        if (!regions)
            throw inputError(file.string(),
                             std::string("names the defects objective, but ") +
                                 kRegionsDefectsFile + " is missing",
                             "run optimize again to write it");
        o.defects = std::move(regions->defects);
        o.reference = std::move(regions->reference);
        o.defectsByShape = s.defects == kAutoRegion;
    }
    return o;
}

void checkViewerFileName(const std::string& name, const std::string& extension) {
    const bool charsOk = std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
    });
    if (name.empty() || name.size() > 64 || !charsOk || name[0] == '.' ||
        name.find("..") != std::string::npos || name.size() <= extension.size() ||
        name.substr(name.size() - extension.size()) != extension) {
        std::string fix = "use 1-64 letters, digits, '-', '_' or '.', ending in ";
        fix += extension;
        throw inputError("name",
                         "\"" + name.substr(0, 80) +
                             "\" is not a file name in the output directory (paths are refused)",
                         fix);
    }
}

namespace {

/// The folder saves go into, checked when the viewer starts (not at the first save, which
/// answered a raw 500): not a file, under a directory, writable.
void checkSaveDir(const fs::path& dir) {
    const std::string where = option("output") + " " + dir.string();
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        throw inputError(where, "is a file, not a directory", "give a folder to save into");
    fs::path p = fs::absolute(dir, ec).lexically_normal();
    while (p.has_relative_path() && !fs::exists(p, ec)) p = p.parent_path();
    if (!fs::is_directory(p, ec))
        throw inputError(where, p.string() + " is a file, not a directory",
                         "give a folder to save into");
    if (::access(p.c_str(), W_OK | X_OK) != 0)
        throw inputError(where, p.string() + " is not writable", "give a writable folder");
}

}  // namespace

ViewerSession::ViewerSession(const ViewerOptions& options) : options_(options) {
    checkSaveDir(options.outDir);
    fs::path in = options.input;
    fs::path lampsFile = options.lamps;
    // A `lamps` output directory: its input (the scene or .tm), its E* and its lamps.
    fs::path lampsDir;
    if (fs::is_directory(in) && fs::exists(in / "summary.json")) {
        const json s = readJsonFile(in / "summary.json");
        if (!s.contains("transport") && s.contains("greedy") && s.contains("input") &&
            s["input"].is_string()) {
            lampsDir = in;
            in = s["input"].get<std::string>();
            if (!fs::exists(in))
                throw inputError((lampsDir / "summary.json").string(),
                                 "names the input " + in.string() + ", which is gone",
                                 "run view on the scene or the .tm the lamps were fitted on");
        }
    }
    if (lampsFile.empty() && fs::is_directory(options.input) &&
        fs::exists(options.input / "lamps.json"))
        lampsFile = options.input / "lamps.json";
    if (!lampsFile.empty()) loadLamps(lampsFile);
    JudgeOptions jo;
    jo.spp = options.judgeSpp;
    jo.truth = options.truth;
    jo.cacheDir = cacheDirectory(options.cache);
    jo.threads = options.threads;
    fs::path truth = options.truth;
    std::unique_ptr<Scene> scene;
    if (fs::is_directory(in)) {
        const fs::path summaryFile = in / outdir::kSummary;
        if (!fs::exists(summaryFile))
            throw inputError(in.string(), "is a directory without summary.json",
                             "give an optimize output directory, a .tm or a scene file");
        const outdir::OptimizeSummary s = outdir::readOptimizeSummary(in);
        if (s.transportFile.empty())
            throw inputError(summaryFile.string(), "records no transport file",
                             "run view on the scene or the .tm the optimization used");
        const fs::path tm = s.transportFile;
        if (!fs::exists(tm))
            throw inputError(summaryFile.string(),
                             "names the transport file " + tm.string() + ", which is gone",
                             "run view on the scene or the .tm the optimization used");
        t_ = std::make_unique<TransportSource>();
        t_->file = readTransportFile(tm);
        t_->path = tm;
        if (truth.empty() && !s.truth.empty()) truth = s.truth;
        const auto& t = t_->file.matrix;
        for (const auto& [name, file] :
             {std::pair<std::string, std::string>{"optimized", outdir::kEnvMap},
              {"paper", outdir::kPaperEnvMap},
              {"lamp", outdir::kLampEnvMap}})
            if (fs::exists(in / file))
                extraPresets_[name] =
                    envMapToE(loadEnvMap(in / file, t.envWidth, t.envHeight, 1), 1);
        // The objective (and regions) that made the output: the optimizer's, and the judge's
        // regions when there is no truth (as optimize's judge scored them).
        made_ = readViewerObjective(in, t.width, t.height);
        // The both measure's gains are over the lamp the output was compared with (an output
        // written before the lamp's env map was: the studio preset, objectiveOnT's fallback).
        if (made_->options.defectMeasure == DefectMeasure::Both && extraPresets_.count("lamp"))
            made_->options.anchorLight = extraPresets_.at("lamp");
        if (truth.empty() && made_->kind == ObjectiveKind::Defects) {
            JudgedDefectLabels judged = judgedDefectLabels(made_->defects, made_->defectsByShape);
            labels_ = std::move(judged.labels);
            legend_ = std::move(judged.legend);
            reference_ = made_->reference;
        }
        // The regions optimize outlined (a transparent layer), when there are no labels here.
        if (truth.empty() && labels_.empty() && fs::exists(in / outdir::kViewRegions)) {
            overlay_ = readInputFile(in / outdir::kViewRegions, "the regions' overlay", 1ull << 28);
        }
        if (options.judge) {
            // The optimization's held-out estimate (cached by optimize), as its report scores.
            const int spp = s.judgeSpp.value_or(options.judgeSpp);
            scene = sceneOfTransport(t_->file, "the viewer's judge");
            estimate_ = std::make_unique<TransportSource>(
                judgeEstimateFor(t_->file, *scene, spp, jo.cacheDir));
        }
    } else {
        PrecomputeOptions po;  // a scene's trace
        po.spp = options.spp;
        po.threads = options.threads;
        po.label = "view: trace T";
        po.sampleSets = 2;  // the halves: the optimizer's objective is optimize's default
        InputTransport input =
            transportOfInput(in, options.sceneOverrides, po, cacheDirectory(options.cache));
        t_ = std::make_unique<TransportSource>(std::move(input.transport));
        scene = std::move(input.scene);
        if (!scene) {  // a .tm
            if (options.judge && t_->file.matrix.planes == 2)
                estimate_ = std::make_unique<TransportSource>(*t_);
            if (!truth.empty()) scene = sceneOfTransport(t_->file, "the truth's projection");
        } else if (options.judge) {
            JudgeOptions sj = jo;
            sj.truth.clear();  // projected below, once
            estimate_ = std::make_unique<TransportSource>(judgeEstimate(*scene, sj));
        }
    }
    if (!lampsDir.empty() && fs::exists(lampsDir / "target-envmap.exr")) {
        const auto& t = t_->file.matrix;
        extraPresets_["optimized"] =
            envMapToE(loadEnvMap(lampsDir / "target-envmap.exr", t.envWidth, t.envHeight, 1), 1);
    }
    if (!truth.empty() && scene) {
        LabelMask m = projectTruth(*scene, truth, options.threads);
        labels_ = std::move(m.labels);
        legend_ = std::move(m.legend);
    }
    if (scene) viewing_ = viewingFor(*scene);
    finishSetup();
}

ViewerSession::ViewerSession(TransportSource t, std::optional<TransportSource> estimate,
                             const ViewerOptions& options, std::vector<uint8_t> labels,
                             std::vector<RegionLabel> legend)
    : options_(options), labels_(std::move(labels)), legend_(std::move(legend)) {
    checkSaveDir(options.outDir);
    t_ = std::make_unique<TransportSource>(std::move(t));
    if (estimate) estimate_ = std::make_unique<TransportSource>(std::move(*estimate));
    if (!options.lamps.empty()) loadLamps(options.lamps);
    finishSetup();
}

ViewerSession::~ViewerSession() {
    optStop_ = true;
    if (optThread_.joinable()) optThread_.join();
}

void ViewerSession::loadLamps(const fs::path& file) {
    const LampsFile f = readLampsFile(file);
    if (f.lamps.size() > kViewerMaxLamps)
        throw inputError(file.string(),
                         "has more than " + std::to_string(kViewerMaxLamps) + " lamps",
                         "keep at most " + std::to_string(kViewerMaxLamps));
    loadedLamps_ = f.lamps;
    lampDistanceMm_ = f.distanceMm;
}

const LampRasterizer& ViewerSession::rasterizer() const {
    return *rasterizer_;
}

void ViewerSession::finishSetup() {
    TransportMatrix& t = t_->file.matrix;
    t.threads = options_.threads;
    rasterizer_ = std::make_unique<LampRasterizer>(EnvMapBasis(t.envWidth, t.envHeight));
    if (!labels_.empty() && labels_.size() != t.rows())
        throw inputError("truth", "its projection does not match T's image size");
    if (estimate_) {
        const TransportMatrix& e = estimate_->file.matrix;
        if (e.planes != 2 || e.width != t.width || e.height != t.height ||
            e.envWidth != t.envWidth || e.envHeight != t.envHeight)
            throw inputError("judge estimate",
                             "does not match T (two halves, same image and grid)");
        JudgeOptions jo;
        jo.spp = estimate_->file.provenance.spp;
        jo.threads = options_.threads;
        jo.viewing = viewing_;
        if (made_) jo.objective.lambda = made_->options.lambda;  // the output's judge's λ
        judge_ = std::make_unique<Judge>(*estimate_, jo, labels_, legend_, reference_);
    }
    if (!labels_.empty()) overlay_ = outlinePng(labels_, t.width, t.height);  // else as read
    if (extraPresets_.count("optimized")) {
        lights_[0] = extraPresets_.at("optimized");
        setPreset(1, loadedLamps_.empty() ? "studio" : "lamps");
    } else if (!loadedLamps_.empty()) {
        setPreset(0, "lamps");
        setPreset(1, "studio");
    } else {
        setPreset(0, "studio");
        setPreset(1, "uniform");
    }
}

std::vector<std::string> ViewerSession::presets() const {
    std::vector<std::string> names{"uniform"};
    for (const auto& n : presetNames()) names.push_back(n);
    for (const auto& [n, e] : extraPresets_) names.push_back(n);
    if (!loadedLamps_.empty()) names.push_back("lamps");
    return names;
}

void ViewerSession::setLight(int slot, std::vector<double> E, const std::string& where) {
    const size_t n = transport().cols();
    if (E.size() != n)
        throw inputError(where, "has " + std::to_string(E.size()) + " values",
                         "give " + std::to_string(n) + " (the env map's " +
                             std::to_string(transport().envWidth) + "x" +
                             std::to_string(transport().envHeight) + " texels, row-major)");
    for (size_t k = 0; k < n; ++k)
        if (!std::isfinite(E[k]) || E[k] < 0 || E[k] > kViewerMaxTexel)
            throw inputError(where, "value " + std::to_string(k) + " is not in [0, 1e6]",
                             "texels are finite, non-negative radiances");
    lights_.at(slot) = std::move(E);
    lamps_.at(slot).clear();
}

void ViewerSession::setLamps(int slot, std::vector<Lamp> lamps) {
    if (lamps.size() > kViewerMaxLamps)
        throw inputError("lamps", "has " + std::to_string(lamps.size()) + " lamps",
                         "give at most " + std::to_string(kViewerMaxLamps));
    for (size_t k = 0; k < lamps.size(); ++k) {
        // What viewerLampFromJson checks, for lamps that come from elsewhere.
        const Lamp& l = lamps[k];
        const bool ok = std::isfinite(l.azimuth) && std::abs(l.elevation) <= std::numbers::pi / 2 &&
                        l.size > 0 && l.size <= std::numbers::pi / 2 && l.width > 0 &&
                        l.width <= std::numbers::pi / 2 && std::isfinite(l.roll) &&
                        l.radiance >= 0 && l.radiance <= kViewerMaxTexel;
        if (!ok)
            throw inputError("lamps[" + std::to_string(k) + "]", "has a field out of range",
                             "elevation in [-90, 90], size and width in (0, 90] degrees, radiance "
                             "in [0, 1e6]");
    }
    std::vector<double> e = rasterizer_->rasterize(lamps);
    for (double& v : e) v = std::min(v, kViewerMaxTexel);  // overlapping lamps
    lights_.at(slot) = std::move(e);
    lamps_.at(slot) = std::move(lamps);
}

void ViewerSession::setPreset(int slot, const std::string& name) {
    const TransportMatrix& t = transport();
    if (name == "lamps" && !loadedLamps_.empty()) {
        setLamps(slot, loadedLamps_);
        return;
    }
    lamps_.at(slot).clear();
    if (name == "uniform") {
        lights_.at(slot).assign(t.cols(), 0.5);
        return;
    }
    if (const auto it = extraPresets_.find(name); it != extraPresets_.end()) {
        lights_.at(slot) = it->second;
        return;
    }
    const auto& names = presetNames();
    if (std::find(names.begin(), names.end(), name) == names.end()) {
        std::string list = "uniform";
        for (const auto& n : presets())
            if (n != "uniform") list += ", " + n;
        throw inputError("preset", "\"" + name.substr(0, 32) + "\" is not a preset",
                         "use one of: " + list);
    }
    lights_.at(slot) = envMapToE(presetEnvMap(name, t.envWidth, t.envHeight), 1);
}

std::vector<double> ViewerSession::relight(int slot) const {
    const TransportMatrix& t = transport();
    std::vector<double> y(t.rows());
    t.applyLuminance(lights_.at(slot), y);
    return y;
}

std::array<int, 2> ViewerSession::hotTexel() const {
    const TransportMatrix& t = transport();
    const std::vector<double> ones(t.rows(), 1.0);
    std::vector<double> sums(t.cols());
    t.applyTransposeLuminance(ones, sums);
    const auto k = static_cast<int>(std::max_element(sums.begin(), sums.end()) - sums.begin());
    return {k / t.envWidth, k % t.envWidth};
}

double ViewerSession::autoExposure(int slot) const {
    return exposureScale(relight(slot), transport().objectMask);
}

std::string ViewerSession::imagePng(int slot, double exposure, ViewerTimings* timings) const {
    Stopwatch clock;
    const std::vector<double> y = relight(slot);
    const double relightMs = clock.seconds() * 1e3;
    // sRGB encoding through a 4096-entry table of the exposed value in [0, 1].
    static const std::vector<uint8_t> lut = [] {
        std::vector<uint8_t> l(4097);
        for (size_t k = 0; k < l.size(); ++k)
            l[k] = static_cast<uint8_t>(
                std::lround(255.0f * srgbEncode(static_cast<float>(k) / 4096.0f)));
        return l;
    }();
    std::vector<uint8_t> px(y.size());
    for (size_t p = 0; p < y.size(); ++p) {
        const double v = std::clamp(y[p] * exposure, 0.0, 1.0);
        px[p] = lut[static_cast<size_t>(std::lround(v * 4096.0))];
    }
    const TransportMatrix& t = transport();
    std::string png = encodePng8(px, t.width, t.height, 1, options_.pngLevel);
    if (timings) {
        timings->relightMs = relightMs;
        timings->encodeMs = clock.seconds() * 1e3 - relightMs;
        timings->pngBytes = png.size();
    }
    return png;
}

json ViewerSession::judgeJson(int slot) const {
    json j;
    j["slot"] = slot == 0 ? "a" : "b";
    j["judge"] = judge_ ? toJson(judge_->score(lights_.at(slot), slot == 0 ? "A" : "B")) : json();
    return j;
}

namespace {

/// outDir/name, after checking that it resolves inside outDir (symbolic links included): the
/// name is a plain file name (checkViewerFileName) and an existing file there must not be a link.
fs::path insideOutDir(const fs::path& outDir, const std::string& name) {
    fs::create_directories(outDir);
    const fs::path dir = fs::canonical(outDir);
    const fs::path file = dir / name;
    if (fs::is_symlink(file) || file.parent_path() != dir)
        throw inputError("name", "\"" + name + "\" is a link or leaves the output directory",
                         "give a new file name");
    return file;
}

}  // namespace

fs::path ViewerSession::saveLamps(int slot, const std::string& name) const {
    checkViewerFileName(name, ".json");
    const auto& lamps = lamps_.at(slot);
    if (lamps.empty())
        throw inputError("lamps", std::string("light ") + (slot == 0 ? "A" : "B") + " has no lamps",
                         "choose the preset lamps or add a lamp first");
    insideOutDir(options_.outDir, name);
    const fs::path file = options_.outDir / name;
    writeTextAtomically(file, lampsToJson(lamps, lampDistanceMm_).dump(2) + "\n");
    return file;
}

fs::path ViewerSession::save(int slot, const std::string& name) const {
    checkViewerFileName(name);
    const TransportMatrix& t = transport();
    insideOutDir(options_.outDir, name);
    EnvMap env = EnvMap::constant(t.envWidth, t.envHeight, 0.0f);
    const auto& e = lights_.at(slot);
    for (size_t k = 0; k < e.size(); ++k) env.texels[k] = static_cast<float>(e[k]);
    const fs::path file = options_.outDir / name;
    const std::vector<double> y = relight(slot);
    Image img(t.width, t.height, 1);
    for (size_t p = 0; p < y.size(); ++p) img.data[p] = static_cast<float>(y[p]);
    std::string stem = name.substr(0, name.size() - 4);
    stem += "-render.exr";
    insideOutDir(options_.outDir, stem);
    writeExr(options_.outDir / stem, img);
    writeEnvMap(file, env);
    return file;
}

void ViewerSession::startOptimize(int slot, int iterations) {
    if (iterations < 0 || iterations > kViewerMaxIterations)
        throw inputError("iterations", std::to_string(iterations) + " is out of range",
                         "give 1.." + std::to_string(kViewerMaxIterations) +
                             " (0 or none: the method's default budget)");
    const TransportMatrix& t = transport();
    if (t.channels != 1)
        throw inputError("optimize", "the viewer optimizes a gray E; this T is RGB",
                         "run scratchlight optimize with its RGB options instead");
    {
        std::lock_guard lock(optMutex_);
        if (opt_.state == "running")
            throw inputError("optimize", "an optimization is running",
                             "wait for it or stop it ({\"stop\": true})");
    }
    // Not running: the last thread has left the session's mutex and is about to end.
    if (optThread_.joinable()) optThread_.join();
    optStop_ = false;
    {
        std::lock_guard lock(optMutex_);
        const int run = opt_.run + 1;
        opt_ = ViewerOptimizeStatus{};
        opt_.state = "running";
        opt_.slot = slot;
        opt_.run = run;
    }
    optThread_ = std::thread(&ViewerSession::runOptimize, this, slot, lights_.at(slot), iterations);
}

void ViewerSession::stopOptimize() {
    optStop_ = true;
}

ViewerOptimizeStatus ViewerSession::optimizeStatus() const {
    std::lock_guard lock(optMutex_);
    return opt_;
}

void ViewerSession::waitOptimize() {
    std::unique_lock lock(optMutex_);
    optDone_.wait(lock, [this] { return opt_.state != "running"; });
}

void ViewerSession::runOptimize(int slot, std::vector<double> start, int iterations) {
    try {
        const TransportMatrix& t = transport();
        const Stopwatch clock;
        // optimize's defaults: objective, method, budget and λ (app/pipeline/Defaults.h), and
        // its default loss mask (the part: app/pipeline/LossMask.h) and objective options.
        SearchInputs si;
        si.set = {&t};
        si.mask = lossMask(LossMaskSpec{}, t, nullptr, ScratchMapOptions{}).pixels;
        si.objective = ObjectiveOptions{};
        si.objective.lambda = optimizeDefaults().lambda;
        const bool labelled =
            std::any_of(labels_.begin(), labels_.end(), [](uint8_t v) { return v != 0; });
        ObjectiveKind kind = defaultObjective(labelled, t.planes);
        if (kind == ObjectiveKind::Defects) {
            si.defects.resize(labels_.size());
            for (size_t p = 0; p < labels_.size(); ++p) si.defects[p] = labels_[p];  // the labels
        }
        if (made_) {  // the objective (and regions) that made the output
            kind = made_->kind;
            si.objective = made_->options;
            si.objective.viewing = viewing_;  // the JND measure sees what the judge sees
            if (!made_->mask.empty()) si.mask = made_->mask;
            si.defects = made_->defects;
            si.reference = made_->reference;
        }
        for (double& v : start) v = std::clamp(v, 0.0, 1.0);  // the optimizer's box
        si.startValues = {start};
        SearchOptions so;
        so.objective = kind;
        OptimizerOptions requested = optimizeJobOptimizerOptions();
        requested.iterations = iterations;  // 0: the method's default budget
        const OptimizerMethodRow& row = methodRow(requested.method);
        so.optimizer = resolveOptimizer(requested, kind, si.objective);  // the stall stop too
        so.estimates = 1;
        InitialState s0;
        s0.kind = InitialKind::EnvMapFile;
        s0.spec = "the viewer's light";
        so.starts = {s0};
        const double initial =
            objectiveOnT(kind, t, si, si.objective).loss->evaluate(start, {}).total;
        {
            std::lock_guard lock(optMutex_);
            opt_.objective = objectiveKindName(kind);
            opt_.method = row.name;
            opt_.budget = so.optimizer.iterations;
            opt_.initialLoss = initial;
            opt_.loss = initial;
            opt_.history.emplace_back(0, initial);
        }
        ProgressTask task("view: optimize", so.optimizer.iterations);
        si.callback = [&](const IterationRecord& r, std::span<const double>) {
            task.set(r.iteration);
            std::lock_guard lock(optMutex_);
            opt_.iteration = r.iteration;
            opt_.loss = r.loss;
            opt_.seconds = clock.seconds();
            auto& h = opt_.history;
            if (h.size() >= 200) {  // thin: keep every other row
                for (size_t k = 0; 2 * k < h.size(); ++k) h[k] = h[2 * k];
                h.resize((h.size() + 1) / 2);
            }
            if (h.empty() || h.back().first != r.iteration) h.emplace_back(r.iteration, r.loss);
            return !optStop_.load();
        };
        SearchResult result = search(si, so);
        {
            std::lock_guard lock(mutex_);
            lights_.at(slot) = std::move(result.e);
            lamps_.at(slot).clear();
        }
        std::lock_guard lock(optMutex_);
        opt_.loss = result.training.total;
        opt_.iteration = result.optimizer.iterations;
        opt_.seconds = clock.seconds();
        opt_.state = optStop_ ? "stopped" : "done";
    } catch (const std::exception& e) {
        std::lock_guard lock(optMutex_);
        opt_.state = "failed";
        opt_.error = e.what();
    }
    optDone_.notify_all();
}

}  // namespace sl
