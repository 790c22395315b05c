#include "app/Viewer.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "app/Preview.h"
#include "app/Truth.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Stopwatch.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/PngBuffer.h"
#include "io/SceneFile.h"
#include "scene/EnvMapPresets.h"
#include "scene/Scene.h"

namespace sl {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

#include "ViewerPage.inc"

std::vector<double> toVector(const EnvMap& env) {
    std::vector<double> e(env.texelCount());
    for (size_t k = 0; k < e.size(); ++k) {
        if (env.channels == 3) {
            const float* c = &env.texels[3 * k];
            e[k] = luminance(c[0], c[1], c[2]);
        } else {
            e[k] = env.texels[k];
        }
    }
    return e;
}

json readJsonFile(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw inputError(file.string(), "cannot be read");
    std::stringstream ss;
    ss << in.rdbuf();
    try {
        return json::parse(ss.str());
    } catch (const std::exception& e) {
        throw inputError(file.string(), std::string("is not valid JSON: ") + e.what());
    }
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

ViewerResponse jsonResponse(const json& j, int status = 200) {
    ViewerResponse r;
    r.status = status;
    r.body = j.dump();
    return r;
}

ViewerResponse errorResponse(int status, const std::string& message) {
    return jsonResponse(json{{"error", message}}, status);
}

std::string queryValue(const ViewerRequest& r, const std::string& key,
                       const std::string& fallback) {
    const auto it = r.query.find(key);
    return it == r.query.end() ? fallback : it->second;
}

double parseExposure(const std::string& text) {
    double v = 0;
    size_t used = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != text.size() || !std::isfinite(v) || v <= 0 || v > 1e9)
        throw inputError("exposure", "\"" + text + "\" is not a number in (0, 1e9]",
                         "give e.g. exposure=1.5");
    return v;
}

}  // namespace

const std::string& viewerPageHtml() {
    static const std::string page(kViewerPage);
    return page;
}

int viewerSlot(const std::string& text) {
    if (text.empty() || text == "a") return 0;
    if (text == "b") return 1;
    throw inputError("slot", "\"" + text.substr(0, 16) + "\" is not a light slot", "use a or b");
}

void checkViewerFileName(const std::string& name) {
    const bool charsOk = std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
    });
    if (name.empty() || name.size() > 64 || !charsOk || name[0] == '.' ||
        name.find("..") != std::string::npos || name.size() < 5 ||
        name.substr(name.size() - 4) != ".exr")
        throw inputError("name",
                         "\"" + name.substr(0, 80) +
                             "\" is not a file name in the output directory (paths are refused)",
                         "use 1-64 letters, digits, '-', '_' or '.', ending in .exr");
}

ViewerSession::ViewerSession(const ViewerOptions& options) : options_(options) {
    const fs::path& in = options.input;
    JudgeOptions jo;
    jo.spp = options.judgeSpp;
    jo.truth = options.truth;
    jo.cacheDir = cacheDirectory(options.cache);
    jo.threads = options.threads;
    fs::path truth = options.truth;
    std::unique_ptr<Scene> scene;
    if (fs::is_directory(in)) {
        const fs::path summaryFile = in / "summary.json";
        if (!fs::exists(summaryFile))
            throw inputError(in.string(), "is a directory without summary.json",
                             "give an optimize output directory, a .tm or a scene file");
        const json s = readJsonFile(summaryFile);
        if (!s.contains("transport") || !s["transport"].contains("file") ||
            !s["transport"]["file"].is_string() ||
            s["transport"]["file"].get<std::string>().empty())
            throw inputError(summaryFile.string(), "records no transport file",
                             "run view on the scene or the .tm the optimization used");
        const fs::path tm = s["transport"]["file"].get<std::string>();
        if (!fs::exists(tm))
            throw inputError(summaryFile.string(),
                             "names the transport file " + tm.string() + ", which is gone",
                             "run view on the scene or the .tm the optimization used");
        t_ = std::make_unique<TransportSource>();
        t_->file = readTransportFile(tm);
        t_->path = tm;
        if (truth.empty() && s.contains("truth") && s["truth"].is_string())
            truth = s["truth"].get<std::string>();
        const auto& t = t_->file.matrix;
        for (const auto& [name, file] :
             {std::pair<std::string, std::string>{"optimized", "envmap.exr"},
              {"paper", "compare-paper-envmap.exr"}})
            if (fs::exists(in / file))
                extraPresets_[name] = toVector(loadEnvMap(in / file, t.envWidth, t.envHeight, 1));
        // The defect regions optimize outlined (a transparent layer), when there is no truth.
        if (truth.empty() && fs::exists(in / "view-regions.png")) {
            std::ifstream f(in / "view-regions.png", std::ios::binary);
            std::stringstream ss;
            ss << f.rdbuf();
            overlay_ = ss.str();
        }
        if (options.judge) {
            // The optimization's held-out estimate (cached by optimize), as its report scores.
            int spp = options.judgeSpp;
            if (s.contains("compare") && s["compare"].contains("judge_spp"))
                spp = s["compare"]["judge_spp"].get<int>();
            scene = sceneOfTransport(t_->file, "the viewer's judge");
            estimate_ = std::make_unique<TransportSource>(
                judgeEstimateFor(t_->file, *scene, spp, jo.cacheDir));
        }
    } else if (isTransportFile(in)) {
        t_ = std::make_unique<TransportSource>();
        t_->file = readTransportFile(in);
        t_->path = in;
        if (options.judge && t_->file.matrix.planes == 2)
            estimate_ = std::make_unique<TransportSource>(*t_);
        if (!truth.empty()) scene = sceneOfTransport(t_->file, "the truth's projection");
    } else {
        scene = loadScene(in, options.sceneOverrides);
        PrecomputeOptions po;
        po.spp = options.spp;
        po.threads = options.threads;
        po.label = "view: trace T";
        t_ = std::make_unique<TransportSource>(
            transportForScene(*scene, po, cacheDirectory(options.cache)));
        if (options.judge) {
            JudgeOptions sj = jo;
            sj.truth.clear();  // projected below, once
            estimate_ = std::make_unique<TransportSource>(judgeEstimate(*scene, sj));
        }
    }
    if (!truth.empty() && scene) {
        LabelMask m = projectTruth(*scene, truth, options.threads);
        labels_ = std::move(m.labels);
        legend_ = std::move(m.legend);
    }
    finishSetup();
}

ViewerSession::ViewerSession(TransportSource t, std::optional<TransportSource> estimate,
                             const ViewerOptions& options, std::vector<uint8_t> labels,
                             std::vector<RegionLabel> legend)
    : options_(options), labels_(std::move(labels)), legend_(std::move(legend)) {
    t_ = std::make_unique<TransportSource>(std::move(t));
    if (estimate) estimate_ = std::make_unique<TransportSource>(std::move(*estimate));
    finishSetup();
}

ViewerSession::~ViewerSession() = default;

void ViewerSession::finishSetup() {
    TransportMatrix& t = t_->file.matrix;
    t.threads = options_.threads;
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
        judge_ = std::make_unique<Judge>(*estimate_, jo, labels_, legend_);
    }
    if (!labels_.empty()) overlay_ = outlinePng(labels_, t.width, t.height);  // else as read
    if (extraPresets_.count("optimized")) {
        lights_[0] = extraPresets_.at("optimized");
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
}

void ViewerSession::setPreset(int slot, const std::string& name) {
    const TransportMatrix& t = transport();
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
    lights_.at(slot) = toVector(presetEnvMap(name, t.envWidth, t.envHeight));
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

fs::path ViewerSession::save(int slot, const std::string& name) const {
    checkViewerFileName(name);
    const TransportMatrix& t = transport();
    fs::create_directories(options_.outDir);
    EnvMap env = EnvMap::constant(t.envWidth, t.envHeight, 0.0f);
    const auto& e = lights_.at(slot);
    for (size_t k = 0; k < e.size(); ++k) env.texels[k] = static_cast<float>(e[k]);
    const fs::path file = options_.outDir / name;
    const std::vector<double> y = relight(slot);
    Image img(t.width, t.height, 1);
    for (size_t p = 0; p < y.size(); ++p) img.data[p] = static_cast<float>(y[p]);
    std::string stem = name.substr(0, name.size() - 4);
    stem += "-render.exr";
    writeExr(options_.outDir / stem, img);
    writeEnvMap(file, env);
    return file;
}

ViewerResponse handleViewerRequest(ViewerSession& session, const ViewerRequest& r) {
    try {
        if (r.path.size() > kViewerMaxPath) return errorResponse(414, "path too long");
        if (r.body.size() > kViewerMaxBody) return errorResponse(413, "request body too large");
        for (const auto& [k, v] : r.query)
            if (k.size() > kViewerMaxQueryValue || v.size() > kViewerMaxQueryValue)
                return errorResponse(400, "query parameter too long");
        std::lock_guard lock(session.mutex());
        const TransportMatrix& t = session.transport();
        if (r.method == "GET" && (r.path == "/" || r.path == "/index.html")) {
            ViewerResponse p;
            p.contentType = "text/html; charset=utf-8";
            p.body = viewerPageHtml();
            return p;
        }
        if (r.method == "GET" && r.path == "/api/info") {
            json j;
            j["image"] = {t.width, t.height};
            j["envmap"] = {t.envWidth, t.envHeight};
            j["presets"] = session.presets();
            j["judge"] = session.hasJudge();
            j["overlay"] = !session.overlayPng().empty();
            j["input"] = session.options().input.string();
            j["output"] = session.options().outDir.string();
            j["auto_exposure"] = session.autoExposure(0);
            j["hot_texel"] = session.hotTexel();
            return jsonResponse(j);
        }
        if (r.method == "GET" && r.path == "/api/light") {
            const int slot = viewerSlot(queryValue(r, "slot", "a"));
            return jsonResponse(json{{"slot", slot == 0 ? "a" : "b"}, {"E", session.light(slot)}});
        }
        if (r.method == "GET" && r.path == "/api/judge") {
            const int slot = viewerSlot(queryValue(r, "slot", "a"));
            json j = session.judgeJson(slot);
            j["auto_exposure"] = session.autoExposure(slot);
            return jsonResponse(j);
        }
        if (r.method == "GET" && r.path == "/api/image.png") {
            const int slot = viewerSlot(queryValue(r, "slot", "a"));
            const double exposure = parseExposure(queryValue(r, "exposure", "1"));
            ViewerResponse p;
            p.contentType = "image/png";
            p.body = session.imagePng(slot, exposure);
            return p;
        }
        if (r.method == "GET" && r.path == "/api/overlay.png") {
            if (session.overlayPng().empty()) return errorResponse(404, "no defect regions");
            ViewerResponse p;
            p.contentType = "image/png";
            p.body = session.overlayPng();
            return p;
        }
        if (r.method == "POST" && (r.path == "/api/light" || r.path == "/api/save")) {
            json body;
            try {
                body = json::parse(r.body);
            } catch (const std::exception&) {
                throw inputError("request body", "is not valid JSON", "send a JSON object");
            }
            if (!body.is_object())
                throw inputError("request body", "is not a JSON object", "send {\"slot\": ...}");
            int slot = 0;
            if (body.contains("slot")) {
                if (!body["slot"].is_string())
                    throw inputError("slot", "is not a string", "use \"a\" or \"b\"");
                slot = viewerSlot(body["slot"].get<std::string>());
            }
            if (r.path == "/api/save") {
                if (!body.contains("name") || !body["name"].is_string())
                    throw inputError("name", "is missing", "give {\"name\": \"NAME.exr\"}");
                const fs::path file = session.save(slot, body["name"].get<std::string>());
                return jsonResponse(json{{"saved", file.string()}});
            }
            if (body.contains("preset")) {
                if (!body["preset"].is_string())
                    throw inputError("preset", "is not a string", "give a preset's name");
                session.setPreset(slot, body["preset"].get<std::string>());
            } else if (body.contains("E")) {
                if (!body["E"].is_array())
                    throw inputError("E", "is not an array", "give the texels as numbers");
                std::vector<double> e;
                e.reserve(body["E"].size());
                for (const auto& v : body["E"]) {
                    if (!v.is_number()) throw inputError("E", "holds a value that is not a number");
                    e.push_back(v.get<double>());
                }
                session.setLight(slot, std::move(e));
            } else {
                throw inputError("request body", "has neither \"E\" nor \"preset\"",
                                 "give {\"slot\": \"a\", \"E\": [...]} or {\"preset\": NAME}");
            }
            return jsonResponse(session.judgeJson(slot));
        }
        if (r.method != "GET" && r.method != "POST")
            return errorResponse(405, "method not allowed");
        return errorResponse(404, "not found");
    } catch (const InputError& e) {
        return errorResponse(400, e.what());
    } catch (const std::exception& e) {
        return errorResponse(500, e.what());
    }
}

}  // namespace sl
