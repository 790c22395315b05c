// The viewer's API (app/viewer/ViewerApi.h handleViewerRequest): the router from a request to the
// session's answer, the page, and the API's lamp JSON.
#include "app/viewer/ViewerApi.h"

#include <cmath>
#include <numbers>

#include "core/Error.h"
#include "core/Text.h"
#include "io/InputFile.h"
#include "scene/Lamp.h"

namespace sl {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

#include "ViewerPage.inc"

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
    const double v = parseFiniteNumber(text).value_or(0.0);
    if (v <= 0 || v > 1e9)
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

namespace {

constexpr double kDeg = 180 / std::numbers::pi;

double lampNumber(const json& j, const char* key, const std::string& where, double lo, double hi,
                  bool loOpen = false) {
    if (!j.contains(key) || !j[key].is_number())
        throw inputError(where + " " + key, "missing or not a number",
                         "give every lamp kind, azimuth_deg, elevation_deg, size_deg, radiance");
    const double v = j[key].get<double>();
    if (!std::isfinite(v) || v < lo || v > hi || (loOpen && v == lo)) {
        std::string range = loOpen ? "(" : "[";
        range += formatNumber(lo) + ", " + formatNumber(hi) + "]";
        throw inputError(where + " " + key, formatNumber(v) + " is not in " + range,
                         "give a value in " + range);
    }
    return v;
}

}  // namespace

json viewerLampJson(const Lamp& l) {
    json j;
    j["kind"] = lampKindName(l.kind);
    j["azimuth_deg"] = l.azimuth * kDeg;
    j["elevation_deg"] = l.elevation * kDeg;
    j["size_deg"] = l.size * kDeg;
    j["width_deg"] = l.width * kDeg;
    j["roll_deg"] = l.roll * kDeg;
    j["radiance"] = l.radiance;
    j["solid_angle_sr"] = lampSharpSolidAngle(l);
    return j;
}

Lamp viewerLampFromJson(const json& j, const std::string& where) {
    if (!j.is_object()) throw inputError(where, "is not a JSON object", "give {\"kind\": ...}");
    if (!j.contains("kind") || !j["kind"].is_string())
        throw inputError(where + " kind", "missing", "use disk, bar or ring");
    Lamp l;
    l.kind = parseLampKind(j["kind"].get<std::string>(), where + " kind");
    const bool ring = l.kind == LampKind::Ring, bar = l.kind == LampKind::Bar;
    l.azimuth =
        ring && !j.contains("azimuth_deg") ? 0.0 : lampNumber(j, "azimuth_deg", where, -1e4, 1e4);
    l.azimuth /= kDeg;
    l.elevation = lampNumber(j, "elevation_deg", where, -90, 90) / kDeg;
    l.size = lampNumber(j, "size_deg", where, 0, 90, true) / kDeg;
    if (bar || j.contains("width_deg"))
        l.width = lampNumber(j, "width_deg", where, 0, 90, true) / kDeg;
    if (bar || j.contains("roll_deg")) l.roll = lampNumber(j, "roll_deg", where, -1e4, 1e4) / kDeg;
    l.radiance = lampNumber(j, "radiance", where, 0, kViewerMaxTexel);
    return l;
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
            j["lamps"] = session.loadedLamps().size();
            j["lamp_kinds"] = json::array();
            for (const LampKindRow& k : lampKindTable()) j["lamp_kinds"].push_back(k.name);
            return jsonResponse(j);
        }
        if (r.method == "GET" && r.path == "/api/light") {
            const int slot = viewerSlot(queryValue(r, "slot", "a"));
            return jsonResponse(json{{"slot", slot == 0 ? "a" : "b"}, {"E", session.light(slot)}});
        }
        if (r.method == "GET" && r.path == "/api/lamps") {
            const int slot = viewerSlot(queryValue(r, "slot", "a"));
            json lamps = json::array();
            for (const Lamp& l : session.lamps(slot)) lamps.push_back(viewerLampJson(l));
            return jsonResponse(json{{"slot", slot == 0 ? "a" : "b"},
                                     {"lamps", lamps},
                                     {"distance_mm", session.lampDistanceMm()}});
        }
        if (r.method == "GET" && r.path == "/api/optimize") {
            const ViewerOptimizeStatus st = session.optimizeStatus();
            json j;
            j["state"] = st.state;
            j["slot"] = st.slot == 0 ? "a" : "b";
            j["run"] = st.run;
            j["iteration"] = st.iteration;
            j["budget"] = st.budget;
            j["loss"] = st.loss;
            j["initial_loss"] = st.initialLoss;
            j["objective"] = st.objective;
            j["method"] = st.method;
            j["seconds"] = st.seconds;
            json h = json::array();
            for (const auto& [it, loss] : st.history) h.push_back({it, loss});
            j["history"] = h;
            j["error"] = st.error;
            return jsonResponse(j);
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
        if (r.method == "POST" && (r.path == "/api/light" || r.path == "/api/save" ||
                                   r.path == "/api/lamps" || r.path == "/api/optimize")) {
            json body = parseJsonInput(r.body, "request body", "send a JSON object");
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
                    throw inputError("name", "is missing",
                                     "give {\"name\": \"NAME.exr\"} or {\"name\": \"NAME.json\"}");
                const std::string name = body["name"].get<std::string>();
                const bool lamps = name.size() > 5 && name.substr(name.size() - 5) == ".json";
                const fs::path file =
                    lamps ? session.saveLamps(slot, name) : session.save(slot, name);
                return jsonResponse(json{{"saved", file.string()}});
            }
            if (r.path == "/api/optimize") {
                if (body.contains("stop")) {
                    if (!body["stop"].is_boolean())
                        throw inputError("stop", "is not true or false", "give {\"stop\": true}");
                    if (body["stop"].get<bool>()) session.stopOptimize();
                    return jsonResponse(json{{"stopping", body["stop"].get<bool>()}});
                }
                int iterations = 0;
                if (body.contains("iterations")) {
                    if (!body["iterations"].is_number_integer())
                        throw inputError("iterations", "is not an integer",
                                         "give e.g. {\"iterations\": 50}");
                    const auto n = body["iterations"].get<int64_t>();
                    iterations =
                        static_cast<int>(std::clamp<int64_t>(n, -1, kViewerMaxIterations + 1));
                }
                if (session.optimizeStatus().state == "running")
                    return errorResponse(409,
                                         "an optimization is running: wait for it or stop "
                                         "it ({\"stop\": true})");
                session.startOptimize(slot, iterations);
                return jsonResponse(json{{"started", true}, {"slot", slot == 0 ? "a" : "b"}});
            }
            if (r.path == "/api/lamps") {
                if (!body.contains("lamps") || !body["lamps"].is_array())
                    throw inputError(
                        "lamps", "is missing or not an array",
                        "give {\"slot\": \"a\", \"lamps\": [{\"kind\": \"disk\", ...}]}");
                if (body["lamps"].size() > kViewerMaxLamps)
                    throw inputError("lamps",
                                     "has " + std::to_string(body["lamps"].size()) + " lamps",
                                     "give at most " + std::to_string(kViewerMaxLamps));
                std::vector<Lamp> lamps;
                for (size_t k = 0; k < body["lamps"].size(); ++k)
                    lamps.push_back(
                        viewerLampFromJson(body["lamps"][k], "lamps[" + std::to_string(k) + "]"));
                session.setLamps(slot, std::move(lamps));
                return jsonResponse(session.judgeJson(slot));
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
