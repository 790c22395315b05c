// The live relighting viewer's API: the router from a request to the session
// (app/viewer/ViewerSession.h) and back, as plain functions (a request in, a response out), and
// the page; app/viewer/ViewerServer.h serves them over HTTP.
//
// The API (JSON unless said; every request validated, errors 400 {"error": "..."}):
//   GET  /                 the page (src/app/viewer/ViewerPage.html, embedded at build time)
//   GET  /api/info         image and env-map size, presets, judge and overlay present, the
//                          auto exposure of A, the texel that lights the most of the image,
//                          "lamps" (how many lamps.json holds), "lamp_kinds"
//   GET  /api/light?slot=a E of a slot:  {"slot": "a", "E": [...]}
//   POST /api/light        {"slot": "a"|"b", "E": [...]} or {"slot": ..., "preset": NAME}:
//                          sets the light, answers with its judge numbers (as GET /api/judge)
//   GET  /api/judge?slot=a {"slot", "judge": toJson(JudgeScore) or null, "auto_exposure"}
//                          (POST /api/light answers the same without "auto_exposure")
//   GET  /api/image.png?slot=a&exposure=X   T·E's luminance, ×X, sRGB-encoded 8-bit gray PNG
//   GET  /api/overlay.png  the defect regions' outlines as RGBA (404 without regions)
//   GET  /api/lamps?slot=a {"slot", "lamps": [lamp...], "distance_mm"}: the lamps the slot's
//                          light is made of (empty when it is painted or a preset without lamps)
//   POST /api/lamps        {"slot", "lamps": [lamp...]}: the light becomes the lamps rasterized
//                          into the basis (scene/Lamp.h LampRasterizer, default quadrature);
//                          answers as POST /api/light. A lamp: {"kind": disk|bar|ring,
//                          "azimuth_deg", "elevation_deg" in [-90, 90], "size_deg" (Lamp::size:
//                          disk radius, bar half-length, ring half-height; (0, 90]),
//                          "width_deg" (bar half-width, (0, 90]), "roll_deg", "radiance" in
//                          [0, 1e6]}; at most kViewerMaxLamps.
//   POST /api/optimize     {"slot", "iterations"?: N}: starts optimize's search
//   (app/pipeline/Search.h,
//                          optimize's default method and objective, below) on T from the slot's
//                          current light, in a background thread, one at a time (409 while one
//                          runs); {"stop": true} stops it at its next iteration (the best
//                          iterate so far is kept, as optimize does on Ctrl-C)
//   GET  /api/optimize     {"state": idle|running|done|stopped|failed, "slot", "iteration",
//                          "budget", "loss", "initial_loss", "objective", "method", "seconds",
//                          "run" (counts runs), "history" [[iteration, loss]...], "error"}; when
//                          a run ends its E* becomes the slot's light (its lamps are dropped)
//   POST /api/save         {"slot": "a", "name": "NAME.exr"}: writes E as OUTDIR/NAME.exr and
//                          T·E as OUTDIR/NAME-render.exr; {"slot", "name": "NAME.json"}: the
//                          slot's lamps as lamps.json (io/LampsFile.h). Atomic (io/AtomicFile.h);
//                          NAME: letters, digits, - _ . and nothing else (no paths).
#pragma once

#include <cstddef>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "app/viewer/ViewerSession.h"
#include "scene/Lamp.h"

namespace sl {

/// Request limits: bodies, paths and query values longer than these are refused (400/413).
inline constexpr size_t kViewerMaxBody = 1 << 20;
inline constexpr size_t kViewerMaxPath = 256;
inline constexpr size_t kViewerMaxQueryValue = 64;

struct ViewerRequest {
    std::string method;  // "GET" or "POST"
    std::string path;    // "/api/image.png"
    std::map<std::string, std::string> query;
    std::string body;
};

struct ViewerResponse {
    int status = 200;
    std::string contentType = "application/json";
    std::string body;
};

/// The slot a query or body names: "a" (or missing) → 0, "b" → 1; InputError otherwise.
int viewerSlot(const std::string& text);

/// A lamp of the API (degrees, see above) and back; fromJson validates (InputError naming
/// `where` and the field).
nlohmann::ordered_json viewerLampJson(const Lamp& lamp);
Lamp viewerLampFromJson(const nlohmann::ordered_json& j, const std::string& where);

/// Answers one request (locks the session's mutex). Never throws: bad input is 400 with
/// {"error": message}, an unknown path 404, anything else 500.
ViewerResponse handleViewerRequest(ViewerSession& session, const ViewerRequest& request);

/// The page (embedded at build time from src/app/viewer/ViewerPage.html).
const std::string& viewerPageHtml();

}  // namespace sl
