// The live relighting viewer (app/viewer/ViewerSession.h, ViewerApi.h, ViewerServer.h): the
// session's relight is T·E, its judge numbers are the Judge's, every request is validated; the
// server survives malformed requests and connections closed mid-transfer; and the page, driven in
// headless Chromium, paints a texel and shows the image and judge numbers that `relight` and
// `judge` give for the saved light (screenshot at build/test-artifacts/viewer-screenshot.png);
// lamps set through the API are exactly their rasterization (scene/Lamp.h), and dragging one on the
// page's hemisphere gives the E, image and judge numbers that the rasterizer, `relight` and `judge`
// give; the optimizer from the current light lowers optimize's loss and reports its progress;
// saving writes only inside the output directory.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "Sockets.h"
#include "TestUtil.h"
#include "app/host/Plot.h"
#include "app/jobs/OptimizeJob.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/LossMask.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/Transport.h"
#include "app/viewer/ViewerApi.h"
#include "app/viewer/ViewerServer.h"
#include "core/Error.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/LampsFile.h"
#include "io/SceneFile.h"
#include "objective/ObjectiveKind.h"
#include "scene/Scene.h"

namespace fs = std::filesystem;
using namespace sl;
using json = nlohmann::json;

namespace {

/// T of the bundled scene at size×size with two halves (its own judge estimate).
TransportSource smallTransport(int size, int spp = 2, bool halves = true) {
    auto scene = loadScene(bundledDefaultScene(), {"camera.width=" + std::to_string(size),
                                                   "camera.height=" + std::to_string(size)});
    PrecomputeOptions po;
    po.spp = spp;
    po.sampleSets = halves ? 2 : 1;
    return transportForScene(*scene, po, {});
}

ViewerResponse call(ViewerSession& s, const std::string& method, const std::string& path,
                    const std::string& body = {}, std::map<std::string, std::string> query = {}) {
    ViewerRequest r;
    r.method = method;
    r.path = path;
    r.body = body;
    r.query = std::move(query);
    return handleViewerRequest(s, r);
}

std::vector<double> randomLight(size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 2.0);
    std::vector<double> e(n);
    for (auto& v : e) v = u(rng);
    return e;
}

using test::connectTo;
using test::sendAll;

/// Two lamps (a disk and a bar) as `scratchlight lamps` writes them.
std::vector<Lamp> twoLamps() {
    const double deg = std::numbers::pi / 180;
    Lamp disk;
    disk.kind = LampKind::Disk;
    disk.radiance = 3;
    disk.azimuth = 20 * deg;
    disk.elevation = 50 * deg;
    disk.size = 12 * deg;
    Lamp bar;
    bar.kind = LampKind::Bar;
    bar.radiance = 1.5;
    bar.azimuth = 200 * deg;
    bar.elevation = 25 * deg;
    bar.size = 20 * deg;
    bar.width = 4 * deg;
    bar.roll = 10 * deg;
    return {disk, bar};
}

fs::path writeLamps(const fs::path& file, const std::vector<Lamp>& lamps) {
    test::writeText(file, lampsToJson(lamps, 400).dump(2));
    return file;
}

}  // namespace

TEST(ViewerSession, RelightIsTTimesEAndTheJudgeScoresTheSameLight) {
    TransportSource t = smallTransport(24);
    const TransportMatrix tm = t.file.matrix;
    TransportSource est = t;
    test::TempDir dir("viewer-session");
    ViewerOptions o;
    o.outDir = dir / "out";
    ViewerSession s(std::move(t), std::move(est), o);
    ASSERT_TRUE(s.hasJudge());
    const std::vector<double> e = randomLight(tm.cols(), 7);
    s.setLight(1, e);
    std::vector<double> want(tm.rows());
    tm.applyLuminance(e, want);
    const std::vector<double> got = s.relight(1);
    ASSERT_EQ(got.size(), want.size());
    for (size_t p = 0; p < want.size(); ++p) ASSERT_EQ(got[p], want[p]) << p;

    // The judge numbers are the Judge's on the same estimate.
    const auto j = s.judgeJson(1);
    TransportSource again = smallTransport(24);
    JudgeOptions jo;
    jo.spp = again.file.provenance.spp;
    Judge reference(again, jo);
    const JudgeScore ref = reference.score(e);
    EXPECT_DOUBLE_EQ(j["judge"]["eq2"].get<double>(), ref.eq2.total);
    EXPECT_DOUBLE_EQ(j["judge"]["unbiased"].get<double>(), ref.unbiased.total);

    // The PNG is the render at the exposure, sRGB-encoded.
    const std::string png = s.imagePng(1, 0.5);
    test::writeText(dir / "i.png", png);
    const Image img = readImage(dir / "i.png");  // decoded back to linear
    ASSERT_EQ(img.width, tm.width);
    ASSERT_EQ(img.channels, 1);
    for (size_t p = 0; p < want.size(); ++p)
        EXPECT_NEAR(img.data[p], std::min(1.0, want[p] * 0.5), 0.02) << p;
}

TEST(ViewerApi, RefusesBadRequestsAndWritesOnlyIntoItsDirectory) {
    test::TempDir dir("viewer-api");
    ViewerOptions o;
    o.outDir = dir / "out";
    ViewerSession s(smallTransport(16, 1, false), std::nullopt, o);
    const size_t n = s.transport().cols();
    EXPECT_EQ(call(s, "GET", "/api/info").status, 200);
    EXPECT_NE(call(s, "GET", "/").body.find("scratchlight view"), std::string::npos);
    using Query = std::map<std::string, std::string>;
    auto check = [&](const std::string& method, const std::string& path, const std::string& body,
                     const std::string& expect, const Query& query = {}, int status = 400) {
        SCOPED_TRACE(method + " " + path + " " + body.substr(0, 40));
        const ViewerResponse r = call(s, method, path, body, query);
        EXPECT_EQ(r.status, status) << r.body;
        EXPECT_NE(r.body.find(expect), std::string::npos) << r.body;
    };
    const std::string longBody(kViewerMaxBody + 1, ' ');
    check("POST", "/api/light", "{not json", "not valid JSON");
    check("POST", "/api/light", "[1,2]", "not a JSON object");
    check("POST", "/api/light", R"({"E": [1, 2, 3]})", "give " + std::to_string(n));
    check("POST", "/api/light", R"({"E": "bright"})", "not an array");
    check("POST", "/api/light", R"({"E": [1, "x"]})", "not a number");
    check("POST", "/api/light", R"({"slot": "c", "preset": "studio"})", "use a or b");
    check("POST", "/api/light", R"({"preset": "disco"})", "use one of: uniform, studio");
    check("POST", "/api/light", R"({"slot": "a"})", "neither");
    check("POST", "/api/save", R"({"name": "../escape.exr"})", "paths are refused");
    check("POST", "/api/save", R"({"name": "/tmp/escape.exr"})", "paths are refused");
    check("POST", "/api/save", R"({"name": "sub/escape.exr"})", "paths are refused");
    check("POST", "/api/save", R"({"name": ".hidden.exr"})", "paths are refused");
    check("POST", "/api/save", R"({"name": "e.png"})", "ending in .exr");
    check("POST", "/api/save", R"({})", "is missing");
    check("GET", "/api/image.png", "", "exposure", {{"exposure", "bright"}});
    check("GET", "/api/image.png", "", "exposure", {{"exposure", "-1"}});
    check("GET", "/api/image.png", "", "exposure", {{"exposure", "nan"}});
    check("GET", "/api/judge", "", "use a or b", {{"slot", "z"}});
    check("POST", "/api/light", longBody, "too large", Query{}, 413);
    check("GET", "/api/nothing", "", "not found", Query{}, 404);
    check("GET", "/../etc/passwd", "", "not found", Query{}, 404);
    check("PUT", "/api/light", "", "not allowed", Query{}, 405);
    // A value out of range: named with its index; the light is unchanged.
    const std::vector<double> before = s.light(0);
    std::vector<double> e(n, 1.0);
    e[5] = -1;
    auto r = call(s, "POST", "/api/light", json{{"E", e}}.dump());
    EXPECT_EQ(r.status, 400);
    EXPECT_NE(r.body.find("value 5"), std::string::npos) << r.body;
    e[5] = 1e300;
    EXPECT_EQ(call(s, "POST", "/api/light", json{{"E", e}}.dump()).status, 400);
    EXPECT_EQ(s.light(0), before);
    // Nothing was written anywhere.
    EXPECT_FALSE(fs::exists(o.outDir));
    EXPECT_FALSE(fs::exists(dir / "escape.exr"));

    // A good light and a save: E and T·E in the output directory, E loads back unchanged.
    e[5] = 3;
    r = call(s, "POST", "/api/light", json{{"slot", "b"}, {"E", e}}.dump());
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_TRUE(json::parse(r.body)["judge"].is_null());  // no estimate given
    r = call(s, "POST", "/api/save", R"({"slot": "b", "name": "mine.exr"})");
    ASSERT_EQ(r.status, 200) << r.body;
    const auto& t = s.transport();
    const EnvMap saved = loadEnvMap(o.outDir / "mine.exr", t.envWidth, t.envHeight, 1);
    for (size_t k = 0; k < n; ++k) EXPECT_FLOAT_EQ(saved.texels[k], static_cast<float>(e[k]));
    EXPECT_TRUE(fs::exists(o.outDir / "mine-render.exr"));
    size_t files = 0;
    for (const auto& f : fs::recursive_directory_iterator(dir.path())) files += f.is_regular_file();
    EXPECT_EQ(files, 2u);
    // Presets.
    r = call(s, "POST", "/api/light", R"({"slot": "a", "preset": "uniform"})");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(s.light(0), std::vector<double>(n, 0.5));
}

TEST(ViewerServer, SurvivesMalformedRequestsAndClosedConnections) {
    std::signal(SIGPIPE, SIG_IGN);
    ViewerOptions o;
    o.pngLevel = 0;  // a large response, so that closing mid-transfer happens mid-transfer
    ViewerSession s(smallTransport(256, 1, false), std::nullopt, o);
    ViewerServer server(s, "127.0.0.1", 0);
    server.start();
    ASSERT_GT(server.port(), 0);
    httplib::Client c("127.0.0.1", server.port());
    auto r = c.Get("/api/info");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200);
    // Malformed JSON: 400, and the server keeps serving.
    r = c.Post("/api/light", "{\"E\": [1, 2", "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400);
    // Garbage that is not HTTP; a request line with no end; a body larger than allowed.
    for (const std::string& garbage :
         {std::string("GARBAGE\r\n\r\n"), std::string("GET /api/info HTTP/1.1\r\nHost: x"),
          std::string(
              "POST /api/light HTTP/1.1\r\nHost: x\r\nContent-Length: 99999999\r\n\r\n{")}) {
        const int fd = connectTo(server.port());
        ASSERT_GE(fd, 0);
        sendAll(fd, garbage);
        ::shutdown(fd, SHUT_WR);
        char buf[256];
        [[maybe_unused]] const ssize_t got = ::recv(fd, buf, sizeof buf, 0);
        ::close(fd);
    }
    // Connections closed mid-transfer of a 64 KB image, a few times.
    for (int k = 0; k < 5; ++k) {
        const int fd = connectTo(server.port());
        ASSERT_GE(fd, 0);
        sendAll(fd, "GET /api/image.png?exposure=1 HTTP/1.1\r\nHost: x\r\n\r\n");
        char buf[100];
        [[maybe_unused]] const ssize_t got = ::recv(fd, buf, sizeof buf, 0);
        linger l{1, 0};  // reset, not a graceful close
        ::setsockopt(fd, SOL_SOCKET, SO_LINGER, &l, sizeof l);
        ::close(fd);
    }
    r = c.Get("/api/image.png?exposure=2");
    ASSERT_TRUE(r) << "the server stopped answering";
    EXPECT_EQ(r->status, 200);
    EXPECT_GT(r->body.size(), 65536u);
    EXPECT_EQ(r->body.substr(1, 3), "PNG");
    server.stop();
}

TEST(ViewerLamps, SettingLampsGivesTheirRasterizationAndSavesLampsJson) {
    test::TempDir dir("viewer-lamps");
    ViewerOptions o;
    o.outDir = dir / "out";
    o.lamps = writeLamps(dir / "given-lamps.json", twoLamps());
    ViewerSession s(smallTransport(16, 1, false), std::nullopt, o);
    const auto& t = s.transport();
    const LampRasterizer raster(EnvMapBasis(t.envWidth, t.envHeight));
    const LampsFile given = readLampsFile(o.lamps);
    // The preset "lamps" is light A at the start: the rasterization of lamps.json.
    const auto presets = s.presets();
    EXPECT_NE(std::find(presets.begin(), presets.end(), "lamps"), presets.end());
    ASSERT_EQ(s.lamps(0).size(), 2u);
    EXPECT_EQ(s.light(0), raster.rasterize(given.lamps));
    EXPECT_DOUBLE_EQ(s.lampDistanceMm(), 400);
    auto r = call(s, "GET", "/api/lamps", "", {{"slot", "a"}});
    ASSERT_EQ(r.status, 200) << r.body;
    json lj = json::parse(r.body);
    ASSERT_EQ(lj["lamps"].size(), 2u);
    EXPECT_NEAR(lj["lamps"][0]["azimuth_deg"].get<double>(), 20, 1e-9);
    EXPECT_NEAR(lj["lamps"][1]["size_deg"].get<double>(), 20, 1e-9);

    // Move lamp 1 and resize lamp 2 through the API: E is exactly the rasterizer's, and the
    // light's power is the lamps' (Σ E_t Ω_t = Σ R·∫m dω, scene/Lamp.h).
    lj["lamps"][0]["azimuth_deg"] = 75.0;
    lj["lamps"][0]["elevation_deg"] = 33.0;
    lj["lamps"][1]["size_deg"] = 30.0;
    lj["lamps"][1]["radiance"] = 0.75;
    const std::vector<double> before = s.light(0);
    r = call(s, "POST", "/api/lamps", json{{"slot", "a"}, {"lamps", lj["lamps"]}}.dump());
    ASSERT_EQ(r.status, 200) << r.body;
    const double deg = std::numbers::pi / 180;
    ASSERT_EQ(s.lamps(0).size(), 2u);
    EXPECT_NEAR(s.lamps(0)[0].azimuth, 75 * deg, 1e-12);
    EXPECT_NEAR(s.lamps(0)[0].elevation, 33 * deg, 1e-12);
    EXPECT_NEAR(s.lamps(0)[1].size, 30 * deg, 1e-12);
    EXPECT_EQ(s.lamps(0)[1].kind, LampKind::Bar);
    const std::vector<double> want = raster.rasterize(s.lamps(0));
    EXPECT_EQ(s.light(0), want);
    EXPECT_NE(s.light(0), before);
    double power = 0, lampsPower = 0;
    for (size_t k = 0; k < want.size(); ++k) power += want[k] * raster.texelSolidAngles()[k];
    for (const Lamp& l : s.lamps(0)) lampsPower += l.radiance * raster.solidAngle(l);
    EXPECT_NEAR(power, lampsPower, 1e-9 * lampsPower);
    // ... and the image is T·E of that E.
    std::vector<double> y(t.rows());
    t.applyLuminance(want, y);
    EXPECT_EQ(s.relight(0), y);

    // Bad lamps are refused with the field named; the light is unchanged.
    auto bad = [&](json lamp, const std::string& expect) {
        SCOPED_TRACE(lamp.dump());
        const ViewerResponse b =
            call(s, "POST", "/api/lamps", json{{"lamps", json::array({lamp})}}.dump());
        EXPECT_EQ(b.status, 400) << b.body;
        EXPECT_NE(b.body.find(expect), std::string::npos) << b.body;
        EXPECT_EQ(s.light(0), want);
    };
    json good = lj["lamps"][0];
    json l = good;
    l["kind"] = "spot";
    bad(l, "lamps[0] kind");
    l = good;
    l["elevation_deg"] = 95;
    bad(l, "elevation_deg");
    l = good;
    l["size_deg"] = 0;
    bad(l, "size_deg");
    l = good;
    l["radiance"] = -1;
    bad(l, "radiance");
    l = good;
    l.erase("azimuth_deg");
    bad(l, "azimuth_deg");
    l = good;
    l["radiance"] = "bright";
    bad(l, "radiance");
    r = call(s, "POST", "/api/lamps", json{{"lamps", json::array()}}.dump());
    EXPECT_EQ(r.status, 200);  // no lamps: a dark light
    EXPECT_EQ(s.light(0), std::vector<double>(t.cols(), 0.0));
    json many = json::array();
    for (size_t k = 0; k <= kViewerMaxLamps; ++k) many.push_back(good);
    r = call(s, "POST", "/api/lamps", json{{"lamps", many}}.dump());
    EXPECT_EQ(r.status, 400) << r.body;
    r = call(s, "POST", "/api/lamps", json{{"slot", "a"}, {"lamps", lj["lamps"]}}.dump());
    ASSERT_EQ(r.status, 200) << r.body;

    // lamps.json: written into the output directory only, and it reads back as the lamps.
    r = call(s, "POST", "/api/save", R"({"slot": "a", "name": "mine.json"})");
    ASSERT_EQ(r.status, 200) << r.body;
    const LampsFile back = readLampsFile(o.outDir / "mine.json");
    ASSERT_EQ(back.lamps.size(), 2u);
    EXPECT_DOUBLE_EQ(back.distanceMm, 400);
    for (size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(back.lamps[k].kind, s.lamps(0)[k].kind);
        EXPECT_NEAR(back.lamps[k].azimuth, s.lamps(0)[k].azimuth, 1e-12);
        EXPECT_NEAR(back.lamps[k].elevation, s.lamps(0)[k].elevation, 1e-12);
        EXPECT_NEAR(back.lamps[k].size, s.lamps(0)[k].size, 1e-12);
        EXPECT_DOUBLE_EQ(back.lamps[k].radiance, s.lamps(0)[k].radiance);
    }
    // Refused: paths, a light without lamps, a link that leads out of the directory.
    for (const char* name : {"../escape.json", "/tmp/escape.json", "sub/escape.json", "..json",
                             ".hidden.json", "x.txt"}) {
        r = call(s, "POST", "/api/save", json{{"name", name}}.dump());
        EXPECT_EQ(r.status, 400) << name << ": " << r.body;
    }
    r = call(s, "POST", "/api/save", R"({"slot": "b", "name": "b.json"})");
    EXPECT_EQ(r.status, 400) << r.body;
    EXPECT_NE(r.body.find("has no lamps"), std::string::npos) << r.body;
    fs::create_symlink(dir / "outside.json", o.outDir / "link.json");
    fs::create_symlink(dir / "outside.exr", o.outDir / "link.exr");
    r = call(s, "POST", "/api/save", R"({"name": "link.json"})");
    EXPECT_EQ(r.status, 400) << r.body;
    r = call(s, "POST", "/api/save", R"({"name": "link.exr"})");
    EXPECT_EQ(r.status, 400) << r.body;
    EXPECT_FALSE(fs::exists(dir / "outside.json"));
    EXPECT_FALSE(fs::exists(dir / "outside.exr"));
    EXPECT_FALSE(fs::exists(dir / "escape.json"));
    size_t files = 0;
    for (const auto& f : fs::recursive_directory_iterator(o.outDir))
        files += f.is_regular_file() && !f.is_symlink();
    EXPECT_EQ(files, 1u);  // mine.json

    // Painting replaces the lamps: the light is no longer theirs.
    r = call(s, "POST", "/api/light",
             json{{"slot", "a"}, {"E", std::vector<double>(t.cols(), 1.0)}}.dump());
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_TRUE(s.lamps(0).empty());
    // The preset brings them back.
    r = call(s, "POST", "/api/light", R"({"slot": "a", "preset": "lamps"})");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(s.light(0), raster.rasterize(given.lamps));
}

TEST(ViewerOptimize, LowersOptimizesLossFromTheCurrentLightAndReportsProgress) {
    ViewerOptions o;
    ViewerSession s(smallTransport(24, 2, true), std::nullopt, o);
    const auto& t = s.transport();
    ASSERT_EQ(call(s, "POST", "/api/light", R"({"slot": "b", "preset": "studio"})").status, 200);
    std::vector<double> start = s.light(1);
    for (double& v : start) v = std::clamp(v, 0.0, 1.0);
    auto r = call(s, "GET", "/api/optimize");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(json::parse(r.body)["state"], "idle");
    r = call(s, "POST", "/api/optimize", R"({"slot": "b", "iterations": 30})");
    ASSERT_EQ(r.status, 200) << r.body;
    s.waitOptimize();
    r = call(s, "GET", "/api/optimize");
    ASSERT_EQ(r.status, 200);
    const json st = json::parse(r.body);
    ASSERT_EQ(st["state"], "done") << st.dump();
    EXPECT_EQ(st["slot"], "b");
    EXPECT_EQ(st["objective"], "unbiased");  // optimize's default on T with halves
    EXPECT_EQ(st["method"], methodName(optimizeDefaults().method));
    EXPECT_EQ(st["budget"], 30);
    EXPECT_GT(st["iteration"].get<int>(), 0);
    EXPECT_LE(st["iteration"].get<int>(), 30);
    // Progress: a row per iteration from the start's loss.
    ASSERT_GE(st["history"].size(), 2u);
    EXPECT_EQ(st["history"][0][0], 0);
    EXPECT_GT(st["history"].back()[0].get<int>(), 0);
    // The loss is optimize's own (the unbiased objective at λ 30 on the object mask) and it
    // went down; the light is the result and lies in the box.
    SearchInputs si;
    si.set = {&t};
    const OptimizeJobOptions defaults;
    si.mask = lossMask(defaults.mask, t, nullptr, defaults.scratch).pixels;
    si.objective = defaults.objective;
    si.objective.lambda = defaults.lambdas.front();
    const ObjectiveOnT own = objectiveOnT(ObjectiveKind::Unbiased, t, si, si.objective);
    const double initial = own.loss->evaluate(start, {}).total;
    const double final = own.loss->evaluate(s.light(1), {}).total;
    EXPECT_DOUBLE_EQ(st["initial_loss"].get<double>(), initial);
    EXPECT_NEAR(st["loss"].get<double>(), final, 1e-12 * std::abs(final));
    EXPECT_LT(final, initial);
    EXPECT_DOUBLE_EQ(st["history"][0][1].get<double>(), initial);
    for (double v : s.light(1)) ASSERT_TRUE(v >= 0 && v <= 1) << v;
    EXPECT_EQ(st["run"], 1);

    // Bad requests; one run at a time; a stop ends a long run early with a light in the box.
    EXPECT_EQ(call(s, "POST", "/api/optimize", R"({"iterations": 0.5})").status, 400);
    EXPECT_EQ(call(s, "POST", "/api/optimize", R"({"iterations": -3})").status, 400);
    EXPECT_EQ(call(s, "POST", "/api/optimize", R"({"stop": "yes"})").status, 400);
    r = call(s, "POST", "/api/optimize", R"({"slot": "a", "iterations": 100000})");
    ASSERT_EQ(r.status, 200) << r.body;
    r = call(s, "POST", "/api/optimize", R"({"slot": "a"})");
    const bool secondStarted = r.status == 200;  // only when the first had ended already
    if (!secondStarted) {
        EXPECT_EQ(r.status, 409) << r.body;
    }
    EXPECT_EQ(call(s, "POST", "/api/optimize", R"({"stop": true})").status, 200);
    s.waitOptimize();
    const auto after = s.optimizeStatus();
    std::cout << "optimize: " << st["initial_loss"] << " -> " << st["loss"] << " in "
              << st["iteration"] << " iterations; a stop ended run " << after.run << " ("
              << after.state << ") at iteration " << after.iteration << std::endl;
    EXPECT_TRUE(after.state == "stopped" || after.state == "done") << after.state;
    EXPECT_LT(after.iteration, 100000);
    EXPECT_EQ(after.run, secondStarted ? 3 : 2);
    for (double v : s.light(0)) ASSERT_TRUE(v >= 0 && v <= 1) << v;
}

TEST(ViewerBrowser, PaintingATexelAndDraggingALampMatchRelightAndJudge) {
    if (!fs::exists("/usr/bin/chromium"))
        GTEST_SKIP() << "chromium is not installed (scripts/install-deps installs it)";
    std::signal(SIGPIPE, SIG_IGN);
    test::TempDir dir("viewer-browser");
    const std::string part = (dir / "part.exr").string(), scene = (dir / "scene.json").string(),
                      truth = (dir / "part-truth.png").string(), cache = (dir / "cache").string();
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    ViewerOptions o;
    o.input = scene;
    o.truth = truth;
    o.spp = 4;
    o.judgeSpp = 16;
    o.cache.dir = cache;
    o.outDir = dir / "view";
    o.lamps = writeLamps(dir / "lamps.json", twoLamps());
    ViewerSession session(o);
    ASSERT_TRUE(session.hasJudge());
    ASSERT_FALSE(session.overlayPng().empty());
    ViewerServer server(session, "127.0.0.1", 0);
    server.start();

    const fs::path profile = dir / "profile";
    const std::string chromium =
        "timeout 120 /usr/bin/chromium --headless --no-sandbox --disable-gpu --no-first-run "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--disable-extensions --hide-scrollbars --mute-audio --user-data-dir=" +
        profile.string() + " --window-size=1500,1000 --virtual-time-budget=20000 ";
    const auto dom = test::runShell(chromium + "--dump-dom '" + server.url() +
                                    "?selftest=1&value=20&name=selftest.exr'");
    const std::smatch m = [&] {
        std::smatch mm;
        static const std::regex re("<pre id=\"selfcheck\">(selfcheck: [a-zA-Z]+)\\n([^<]*)</pre>");
        std::regex_search(dom.output, mm, re);
        return mm;
    }();
    ASSERT_FALSE(m.empty()) << dom.output.substr(0, 4000);
    EXPECT_EQ(m[1].str(), "selfcheck: ok") << m[2].str();
    const json self = json::parse(m[2].str());
    // The image and the judge numbers changed.
    EXPECT_NE(self["before"]["image"]["hash"], self["after"]["image"]["hash"]);
    EXPECT_NE(self["before"]["judge"]["eq2"], self["after"]["judge"]["eq2"]);
    const fs::path saved = o.outDir / "selftest.exr";
    ASSERT_TRUE(fs::exists(saved));
    const EnvMap env = loadEnvMap(saved, 50, 25, 1);
    const auto hot = session.hotTexel();  // the texel the page paints by default
    EXPECT_EQ(self["texel"][0].get<int>(), hot[0]);
    EXPECT_EQ(self["texel"][1].get<int>(), hot[1]);
    EXPECT_FLOAT_EQ(env.texels[static_cast<size_t>(hot[0] * 50 + hot[1])], 20.0f);

    // `relight` on the same T (precompute at the same spp and seed, in halves as the viewer traces
    // it) gives the viewer's render of a saved light, the page's image is that render at the page's
    // exposure, and `judge` on the saved light gives the page's numbers.
    const std::string tm = (dir / "p.tm").string();
    ASSERT_EQ(test::runCli("precompute " + scene + " --spp 4 --halves -o " + tm).exitCode, 0);
    // rel: the judge numbers' relative tolerance (E is stored as float32); cliJudge: what
    // `judge` said.
    auto matchesCli = [&](const fs::path& savedE, const std::string& renderName, const json& report,
                          double rel, json* cliJudge) {
        SCOPED_TRACE(savedE.string());
        const std::string relit = (dir / ("relit-" + renderName)).string();
        auto r = test::runCli("relight " + tm + " --envmap " + savedE.string() + " -o " + relit);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const Image a = readImage(relit), b = readImage(o.outDir / renderName);
        ASSERT_EQ(a.data.size(), b.data.size());
        for (size_t p = 0; p < a.data.size(); ++p) ASSERT_FLOAT_EQ(a.data[p], b.data[p]) << p;
        const std::string png = (dir / ("page-" + renderName + ".png")).string();
        const double exposure = report["exposure"].get<double>();
        const int slot = 0;
        test::writeText(png, session.imagePng(slot, exposure));
        const Image shown = readImage(png);
        for (size_t p = 0; p < a.data.size(); ++p)
            ASSERT_NEAR(shown.data[p], std::min(1.0, a.data[p] * exposure), 0.02);
        const fs::path jd = dir / ("judge-" + renderName);
        r = test::runCli("judge " + scene + " " + savedE.string() + " --spp 16 --truth " + truth +
                         " --no-references --cache " + cache + " -o " + jd.string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const json jj = json::parse(test::readFile(jd / "judge.json"))["lights"][0];
        *cliJudge = jj;
        const json& page = report["after"]["judge"];
        EXPECT_NEAR(page["eq2"].get<double>(), jj["eq2"].get<double>(),
                    rel * std::abs(jj["eq2"].get<double>()));
        EXPECT_NEAR(page["unbiased"].get<double>(), jj["unbiased"].get<double>(),
                    rel * std::abs(jj["unbiased"].get<double>()));
        ASSERT_EQ(page["visibility"].size(), jj["visibility"].size());
        ASSERT_FALSE(jj["visibility"].empty());
        for (size_t k = 0; k < jj["visibility"].size(); ++k)
            EXPECT_NEAR(
                page["visibility"][k]["visibility"].get<double>(),
                jj["visibility"][k]["visibility"].get<double>(),
                rel * std::max(1.0, std::abs(jj["visibility"][k]["visibility"].get<double>())))
                << jj["visibility"][k]["name"];
    };
    json cliJudge;
    matchesCli(saved, "selftest-render.exr", self, 1e-6, &cliJudge);

    // Light A: the two lamps, the disk toward the texel that lights the most of the image (so
    // that the part is lit). Drag lamp 1 on the hemisphere widget (mouse events on the canvas)
    // 20° in azimuth and 8° down, then press "]": the lamp moved there and grew, the image and
    // the judge numbers changed,
    // the saved E is the rasterization of the saved lamps.json, and it matches `relight` and
    // `judge`.
    constexpr double kDeg = std::numbers::pi / 180;
    const Vec3d hotDir = EnvMapBasis::uvToDirection((hot[1] + 0.5) / 50, hot[0] / 24.0);
    const double hotEl = std::asin(hotDir.y) / kDeg;
    const double hotAz = std::fmod(std::atan2(hotDir.x, -hotDir.z) / kDeg + 360, 360);
    std::vector<Lamp> lit = twoLamps();
    lit[0].azimuth = hotAz * kDeg;
    lit[0].elevation = hotEl * kDeg;
    session.setLamps(0, lit);
    const double az = std::fmod(hotAz + 20, 360), el = std::clamp(hotEl - 8, 5.0, 85.0);
    const auto lampDom =
        test::runShell(chromium + "--dump-dom '" + server.url() +
                       "?selftest=lamp&az=" + std::to_string(az) + "&el=" + std::to_string(el) +
                       "&name=lamp-selftest.exr&lamps=lamp-selftest.json&optimize=50'");
    std::smatch lm;
    {
        static const std::regex re("<pre id=\"selfcheck\">(selfcheck: [a-zA-Z]+)\\n([^<]*)</pre>");
        std::regex_search(lampDom.output, lm, re);
    }
    ASSERT_FALSE(lm.empty()) << lampDom.output.substr(0, 4000);
    EXPECT_EQ(lm[1].str(), "selfcheck: ok") << lm[2].str();
    const json lself = json::parse(lm[2].str());
    EXPECT_NE(lself["before"]["image"]["hash"], lself["after"]["image"]["hash"]);
    EXPECT_NE(lself["before"]["judge"]["eq2"], lself["after"]["judge"]["eq2"]);
    // The handle is where it was dragged, to the widget's pixel (0.62° per pixel radially).
    std::cout << "lamp dragged from azimuth " << hotAz << ", elevation " << hotEl << " to " << az
              << ", " << el << std::endl;
    EXPECT_NEAR(lself["before"]["lamp"]["azimuth_deg"].get<double>(), hotAz, 1e-9);
    EXPECT_NEAR(lself["after"]["lamp"]["azimuth_deg"].get<double>(), az, 1.0);
    EXPECT_NEAR(lself["after"]["lamp"]["elevation_deg"].get<double>(), el, 1.0);
    EXPECT_GT(lself["after"]["image"]["mean"].get<double>(), 1.0);  // the part is lit
    // ... and the shortcut "]" made it 1.25 times as large.
    EXPECT_NEAR(lself["after"]["lamp"]["size_deg"].get<double>(),
                1.25 * lself["before"]["lamp"]["size_deg"].get<double>(), 1e-9);
    ASSERT_EQ(session.lamps(0).size(), 2u);
    const fs::path savedLamps = o.outDir / "lamp-selftest.json",
                   savedLampE = o.outDir / "lamp-selftest.exr";
    ASSERT_TRUE(fs::exists(savedLamps));
    ASSERT_TRUE(fs::exists(savedLampE));
    const LampRasterizer raster(EnvMapBasis(50, 25));
    const std::vector<double> exact = raster.rasterize(session.lamps(0));
    const std::vector<double> fromFile = raster.rasterize(readLampsFile(savedLamps).lamps);
    const EnvMap lampEnv = loadEnvMap(savedLampE, 50, 25, 1);
    double peak = 0;
    for (double v : exact) peak = std::max(peak, v);
    for (size_t k = 0; k < exact.size(); ++k) {
        ASSERT_EQ(lampEnv.texels[k], static_cast<float>(exact[k])) << k;
        ASSERT_NEAR(fromFile[k], exact[k], 1e-9 * peak) << k;
    }
    // The page judged the lamps' E in double, `judge` its float32 copy in the file: equal to
    // float rounding, and the session's judge on the file's E gives `judge`'s numbers.
    matchesCli(savedLampE, "lamp-selftest-render.exr", lself, 1e-6, &cliJudge);
    const std::vector<double> optimizedB = session.light(1);
    std::vector<double> stored(lampEnv.texels.begin(), lampEnv.texels.end());
    session.setLight(1, stored);
    const json onFile = session.judgeJson(1)["judge"];
    EXPECT_NEAR(onFile["eq2"].get<double>(), cliJudge["eq2"].get<double>(),
                1e-9 * std::abs(cliJudge["eq2"].get<double>()));
    EXPECT_NEAR(onFile["unbiased"].get<double>(), cliJudge["unbiased"].get<double>(),
                1e-9 * std::abs(cliJudge["unbiased"].get<double>()));
    // The page's optimizer button ran optimize's search from light B (studio) for 50
    // iterations: the loss went down, the progress bar reached the last iteration, and B is
    // the result, with the judge's numbers the page shows.
    const json& opt = lself["optimized"];
    ASSERT_TRUE(opt.is_object()) << lself.dump();
    EXPECT_EQ(opt["status"]["state"], "done");
    EXPECT_EQ(opt["status"]["slot"], "b");
    EXPECT_LT(opt["status"]["loss"].get<double>(), opt["status"]["initial_loss"].get<double>());
    EXPECT_EQ(opt["progress"], opt["status"]["iteration"]);
    EXPECT_NE(opt["image_before"]["hash"], opt["image_after"]["hash"]);
    session.setLight(1, optimizedB);
    const json judgedB = session.judgeJson(1)["judge"];
    EXPECT_DOUBLE_EQ(opt["judge_after"]["eq2"].get<double>(), judgedB["eq2"].get<double>());
    EXPECT_DOUBLE_EQ(opt["judge_after"]["unbiased"].get<double>(),
                     judgedB["unbiased"].get<double>());
    std::cout << "optimizer from the page: loss " << opt["status"]["initial_loss"] << " -> "
              << opt["status"]["loss"] << " in " << opt["status"]["iteration"]
              << " iterations; judge eq. 2 " << opt["judge_before"]["eq2"] << " -> "
              << opt["judge_after"]["eq2"] << std::endl;

    // A screenshot with the A/B split and the defect overlay.
    const fs::path shot =
        fs::path(SL_CLI_PATH).parent_path() / "test-artifacts" / "viewer-screenshot.png";
    fs::create_directories(shot.parent_path());
    fs::remove(shot);
    const auto sc = test::runShell(chromium + "--screenshot=" + shot.string() + " '" +
                                   server.url() + "?split=1&overlay=1'");  // A: the lamps
    std::cout << "viewer screenshot: " << shot.string() << std::endl;
    RecordProperty("screenshot", shot.string());
    EXPECT_TRUE(fs::exists(shot)) << sc.output;
    server.stop();
}

TEST(ViewerOutdir, OpensAnOptimizeOutputDirectoryWithItsLightRegionsAndJudge) {
    test::TempDir dir("viewer-outdir");
    const std::string part = (dir / "part.exr").string(), scene = (dir / "scene.json").string(),
                      truth = (dir / "part-truth.png").string(), cache = (dir / "cache").string();
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const fs::path out = dir / "opt";
    auto r =
        test::runCli("optimize " + scene + " --truth " + truth +
                     " --heldout-spp 16 --iterations 5 --cache " + cache + " -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    ViewerOptions o;
    o.input = out;
    o.cache.dir = cache;
    o.outDir = dir / "view";
    ViewerSession s(o);
    const auto presets = s.presets();
    EXPECT_NE(std::find(presets.begin(), presets.end(), "optimized"), presets.end());
    EXPECT_FALSE(s.overlayPng().empty());
    ASSERT_TRUE(s.hasJudge());
    // Light A is the answer (envmap.exr: E*, or the reference that beat it on validation), and
    // the judge scores it as the report did (stored as float32).
    const auto& t = s.transport();
    const EnvMap star = loadEnvMap(out / "envmap.exr", t.envWidth, t.envHeight, 1);
    for (size_t k = 0; k < t.cols(); ++k)
        ASSERT_EQ(s.light(0)[k], static_cast<double>(star.texels[k]));
    const json summary = json::parse(test::readFile(out / "summary.json"));
    const double reported = summary["judge"]["eq2"].get<double>();
    EXPECT_NEAR(s.judgeJson(0)["judge"]["eq2"].get<double>(), reported, 1e-4 * reported);
    // lamps.json in the directory: the preset "lamps", light B (A stays E*).
    writeLamps(out / "lamps.json", twoLamps());
    o.judge = false;
    {
        ViewerSession withLamps(o);
        const auto names = withLamps.presets();
        EXPECT_NE(std::find(names.begin(), names.end(), "lamps"), names.end());
        EXPECT_EQ(withLamps.lamps(1).size(), 2u);
        EXPECT_EQ(withLamps.light(1), withLamps.rasterizer().rasterize(withLamps.loadedLamps()));
        EXPECT_EQ(withLamps.light(0), s.light(0));
    }
    // A `lamps` output directory (summary.json names its input): T of that input, its E* as
    // "optimized" and its lamps.
    const fs::path lampsOut = dir / "lamps-out";
    fs::create_directories(lampsOut);
    test::writeText(lampsOut / "summary.json",
                    json{{"input", scene}, {"greedy", json::array()}}.dump());
    writeLamps(lampsOut / "lamps.json", twoLamps());
    fs::copy_file(out / "envmap.exr", lampsOut / "target-envmap.exr");
    o.input = lampsOut;
    {
        ViewerSession fromLamps(o);
        const auto names = fromLamps.presets();
        EXPECT_NE(std::find(names.begin(), names.end(), "lamps"), names.end());
        EXPECT_NE(std::find(names.begin(), names.end(), "optimized"), names.end());
        EXPECT_EQ(fromLamps.light(0), s.light(0));
        EXPECT_EQ(fromLamps.lamps(1).size(), 2u);
    }
    // An output directory without summary.json is refused with the fix.
    o.input = dir.path();
    try {
        ViewerSession bad(o);
        ADD_FAILURE() << "a directory without summary.json was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("summary.json"), std::string::npos) << e.what();
    }
}

// One output, one objective (issue 31 item 3): for an `optimize --objective defects` output on
// automatic regions, the terminal, summary.json (what the report shows), loss.csv, `judge
// --defects` and the viewer give the same numbers: the held-out figure is the defects loss on
// the independent estimate (U beside it), the judge's visibility is of the same region, and the
// viewer's optimizer runs the defects objective on the same regions from the same loss.
namespace {

/// The viewer's optimizer run for `iterations` from an optimize output's E* (envmap-optimized.exr
/// when a reference is the answer): its status once done.
ViewerOptimizeStatus optimizeFromTheOutputsLight(ViewerSession& v, const fs::path& out,
                                                 int iterations) {
    const auto& t = v.transport();
    const fs::path star = fs::exists(out / "envmap-optimized.exr") ? out / "envmap-optimized.exr"
                                                                   : out / "envmap.exr";
    const EnvMap e = loadEnvMap(star, t.envWidth, t.envHeight, 1);
    v.setLight(0, std::vector<double>(e.texels.begin(), e.texels.end()));
    v.startOptimize(0, iterations);
    v.waitOptimize();
    return v.optimizeStatus();
}

}  // namespace

TEST(ViewerOutdir, JudgeViewerReportAndTerminalAgreeOnTheObjectivesNumbers) {
    test::TempDir dir("one-objective");
    const std::string part = (dir / "part.exr").string(), scene = (dir / "scene.json").string(),
                      cache = (dir / "cache").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part +
                           " --width 160 --height 160 --scratches 3 --chatter-start 0.5 --scene " +
                           scene + " --image-size 40 --spp 8 --max-depth 3")
                  .exitCode,
              0);
    const fs::path out = dir / "opt";
    auto r =
        test::runCli("optimize " + scene +
                     " --objective defects --spp 16 --iterations 20 --heldout-spp 16 --cache " +
                     cache + " -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json s = json::parse(test::readFile(out / "summary.json"));
    ASSERT_EQ(s.value("objective", ""), "defects");
    EXPECT_EQ(s.value("heldout_objective", ""), "defects");
    const double held = s.at("heldout_loss").get<double>(), heldU = s.at("heldout_U").get<double>();
    // The held-out figure is the defects loss (the visibility term is negative), not U.
    EXPECT_NE(held, heldU);
    EXPECT_EQ(s.at("heldout").at("final").at("unbiased").at("loss").get<double>(), heldU);
    const json& judged = s.at("judge");
    const double vis = judged.at("visibility").at(0).at("visibility").get<double>();
    // auto's marks by shape (detect/MarkShapes.h): the scratches are lines
    ASSERT_EQ(judged.at("visibility").at(0).value("name", ""), "lines");

    // The terminal: the held-out line names the objective and prints both figures.
    std::smatch m;
    const std::regex line(
        "held out \\(lambda 30, 16 spp\\): the defects loss (\\S+) -> (\\S+) \\(lower is "
        "better\\); U there (\\S+) -> (\\S+)");
    ASSERT_TRUE(std::regex_search(r.output, m, line)) << r.output;
    EXPECT_NEAR(std::stod(m[2]), held, 1e-5 * std::abs(held));
    EXPECT_NEAR(std::stod(m[4]), heldU, 1e-5 * std::abs(heldU));
    // loss.csv's last row: the same held-out figures.
    {
        const std::string csv = test::readFile(out / "loss.csv");
        ASSERT_NE(csv.find("heldout_loss,heldout_paper_loss,heldout_U"), std::string::npos);
        std::string last = csv.substr(csv.rfind('\n', csv.size() - 2) + 1);
        std::vector<std::string> cells;
        std::stringstream ls(last);
        for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
        ASSERT_EQ(cells.size(), 9u) << last;
        EXPECT_NEAR(std::stod(cells[6]), held, 1e-9 * std::abs(held));
        EXPECT_NEAR(std::stod(cells[8]), heldU, 1e-9 * std::abs(heldU));
    }
    // The report shows the held-out rows with that objective's name.
    const std::string html = test::readFile(out / "report.html");
    EXPECT_NE(html.find("held out: the defects loss on the independent estimate"),
              std::string::npos);
    EXPECT_NE(html.find("held out: U on the independent estimate"), std::string::npos);

    // judge --defects auto on the output: the same region, the same visibility.
    r = test::runCli("judge " + scene + " " + out.string() + " --defects auto --spp 16 --cache " +
                     cache + " --no-references -o " + (dir / "judged").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json j = json::parse(test::readFile(dir / "judged" / "judge.json"));
    ASSERT_EQ(j.at("lights").at(0).at("visibility").size(), judged.at("visibility").size());
    const json& jv = j.at("lights").at(0).at("visibility").at(0);
    EXPECT_EQ(jv.value("name", ""), judged.at("visibility").at(0).value("name", "?"));
    EXPECT_EQ(jv.value("pixels", 0), judged.at("visibility").at(0).value("pixels", -1));
    EXPECT_NEAR(jv.value("visibility", 0.0), vis, 1e-5 * std::abs(vis));  // E* as float32
    EXPECT_NEAR(j.at("lights").at(0).value("unbiased", 0.0), judged.value("unbiased", -1.0),
                1e-5 * std::abs(judged.value("unbiased", 1.0)));

    // The viewer on the output: the judge's visibility of the same region at the same λ, and an
    // optimizer that runs the defects objective on the output's regions and T.
    ViewerOptions o;
    o.input = out;
    o.cache.dir = cache;
    o.outDir = dir / "view";
    ViewerSession v(o);
    ASSERT_TRUE(v.outputObjective());
    EXPECT_EQ(v.outputObjective()->kind, ObjectiveKind::Defects);
    ASSERT_TRUE(v.hasJudge());
    const json vj = json::parse(v.judgeJson(0).dump());
    ASSERT_EQ(vj.at("judge").at("visibility").size(), judged.at("visibility").size()) << vj.dump();
    EXPECT_NEAR(vj["judge"]["visibility"][0]["visibility"].get<double>(), vis,
                1e-5 * std::abs(vis));
    EXPECT_NEAR(vj["judge"]["unbiased"].get<double>(), judged.value("unbiased", -1.0),
                1e-5 * std::abs(judged.value("unbiased", 1.0)));
    // From E* (envmap-optimized.exr when a reference is the answer), the optimizer's starting
    // loss is the run's final training loss.
    const ViewerOptimizeStatus st = optimizeFromTheOutputsLight(v, out, 2);
    ASSERT_NE(st.state, "failed") << st.error;
    EXPECT_EQ(st.objective, "defects");
    const double final = s.at("final_loss").get<double>();
    EXPECT_NEAR(st.initialLoss, final, 1e-4 * std::abs(final) + 1e-6);
}

// The viewer's optimizer on a `both` output runs the objective that made it, gains over the lamp
// the output was compared with (compare-lamp-envmap.exr), not the studio preset: from E* its
// starting loss is the run's final training loss.
TEST(ViewerOutdir, TheBothMeasuresOptimizerGainsOverTheOutputsLamp) {
    test::TempDir dir("both-view");
    const std::string scene = (dir / "scene.json").string(),
                      truth = (dir / "part-truth.png").string(), cache = (dir / "cache").string();
    ASSERT_EQ(test::writeScratchedPart(dir.path()), 0);
    const auto out = dir / "out";
    const auto r = test::runCli("optimize " + scene + " --truth " + truth +
                                " --spp 16 --heldout none --iterations 30 --compare const:0.3" +
                                " --cache " + cache + " -o " + out.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto summary = json::parse(test::readFile(out / "summary.json"));
    ASSERT_EQ(summary.value("defects_measure", ""), "both");
    ViewerOptions o;
    o.input = out;
    o.cache.dir = cache;
    o.outDir = dir / "view";
    ViewerSession v(o);
    ASSERT_TRUE(v.outputObjective());
    const auto& t = v.transport();
    const std::vector<double>& anchor = v.outputObjective()->options.anchorLight;
    ASSERT_EQ(anchor.size(), t.cols());
    for (double e : anchor) EXPECT_NEAR(e, 0.3, 1e-7);
    const ViewerOptimizeStatus st = optimizeFromTheOutputsLight(v, out, 1);
    ASSERT_NE(st.state, "failed") << st.error;
    const double final = summary.at("final_loss").get<double>();
    EXPECT_NEAR(st.initialLoss, final, 1e-4 * std::abs(final) + 1e-6);
}

TEST(ViewerBench, PrintsItsTableAndWritesCsv) {
    test::TempDir dir("viewer-bench");
    const fs::path csv = dir / "bench-view.csv";
    const auto r =
        test::runCli("bench view --size 32,48 --spp 1 --repeats 3 --no-cache -o " + csv.string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("image ms"), std::string::npos) << r.output;
    const std::string text = test::readFile(csv);
    EXPECT_EQ(text.rfind("size,nnz,trace_s,image_ms_median", 0), 0u) << text;
    EXPECT_NE(text.find("\n32,"), std::string::npos) << text;
    EXPECT_NE(text.find("\n48,"), std::string::npos) << text;
}

// Issue 35: two viewers on one port both started and shared its requests; 16 idle connections
// delayed a request by 7.7 s (200 stopped it); `view -o <a file>` started and answered every
// save with a raw 500.
TEST(ViewerServer, OwnsItsPortOutlastsIdleClientsAndChecksItsFolder) {
    std::signal(SIGPIPE, SIG_IGN);
    test::TempDir dir("viewer-port");
    ViewerOptions o;
    o.outDir = dir / "saves";
    ViewerSession s(smallTransport(16, 1, false), std::nullopt, o);
    ViewerServer server(s, "127.0.0.1", 0);
    server.start();
    ASSERT_GT(server.port(), 0);
    try {
        ViewerServer second(s, "127.0.0.1", server.port());
        ADD_FAILURE() << "a second server bound port " << server.port();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("is taken"), std::string::npos) << e.what();
    }
    // ... and `view` asks before its setup: the same answer, at once
    try {
        checkViewerPort("127.0.0.1", server.port());
        ADD_FAILURE() << "checkViewerPort passed a taken port " << server.port();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("is taken"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(checkViewerPort("127.0.0.1", 0));
    // a server bound and never run lets its port go
    const int let = [&] { return std::make_unique<ViewerServer>(s, "127.0.0.1", 0)->port(); }();
    EXPECT_NO_THROW(checkViewerPort("127.0.0.1", let)) << let;
    // a port nobody holds passes (an ephemeral port, bound and let go)
    const int free = [] {
        const int fd = socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        socklen_t n = sizeof(a);
        bind(fd, reinterpret_cast<sockaddr*>(&a), n);
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &n);
        close(fd);
        return static_cast<int>(ntohs(a.sin_port));
    }();
    EXPECT_NO_THROW(checkViewerPort("127.0.0.1", free)) << free;
    // 40 idle connections (more than the workers), then a request: answered within seconds.
    std::vector<int> idle;
    for (int k = 0; k < 40; ++k) idle.push_back(connectTo(server.port()));
    const auto t0 = std::chrono::steady_clock::now();
    httplib::Client c("127.0.0.1", server.port());
    c.set_read_timeout(10, 0);
    auto r = c.Get("/api/info");
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(r) << "the server stopped answering";
    EXPECT_EQ(r->status, 200);
    EXPECT_LT(seconds, 3.0);
    for (const int fd : idle)
        if (fd >= 0) ::close(fd);
    server.stop();
    // A file where the saves go: refused when the session starts.
    test::writeText(dir / "afile", "x");
    ViewerOptions bad;
    bad.outDir = dir / "afile";
    try {
        ViewerSession refused(smallTransport(16, 1, false), std::nullopt, bad);
        ADD_FAILURE() << "a file accepted as the save folder";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("is a file, not a directory"), std::string::npos)
            << e.what();
    }
}

// Issue 35: 8 idle connections delayed a request by 3.7 s, 16 by 7.7 s, 200 stopped it (with a
// pool of 32 threads and 1-2 s timeouts, 200 still delayed it by ~6 s); 20 slow clients (a byte per
// 0.5 s) blocked it; of 50 pipelined requests on one connection 1 was answered. The bound (1 s)
// is generous for a loaded 2-core machine: a behaviour, not a speed target.
TEST(ViewerServer, IdleSlowAndPipelinedClientsAreAllServed) {
    std::signal(SIGPIPE, SIG_IGN);
    ViewerSession s(smallTransport(16, 1, false), std::nullopt, {});
    ViewerServer server(s, "127.0.0.1", 0);
    server.start();
    ASSERT_GT(server.port(), 0);
    auto timedInfo = [&server](double& seconds) {
        const auto t0 = std::chrono::steady_clock::now();
        httplib::Client c("127.0.0.1", server.port());
        c.set_read_timeout(10, 0);
        const auto r = c.Get("/api/info");
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return r && r->status == 200;
    };
    for (const int n : {8, 16, 200}) {
        std::vector<int> idle;
        for (int k = 0; k < n; ++k) idle.push_back(connectTo(server.port()));
        double seconds = 0;
        EXPECT_TRUE(timedInfo(seconds)) << n << " idle connections";
        EXPECT_LT(seconds, 1.0) << n << " idle connections";
        for (const int fd : idle)
            if (fd >= 0) ::close(fd);
    }
    // 20 clients sending a request a byte every 0.5 s.
    std::vector<int> slow;
    for (int k = 0; k < 20; ++k) slow.push_back(connectTo(server.port()));
    std::atomic<bool> done{false};
    std::thread dribbler([&] {
        const std::string request = "GET /api/info HTTP/1.1\r\nHost: x\r\n\r\n";
        for (size_t i = 0; i < request.size() && !done; ++i) {
            for (const int fd : slow) ::send(fd, &request[i], 1, MSG_NOSIGNAL);
            for (int t = 0; t < 10 && !done; ++t)
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(700));  // two bytes each sent
    for (int k = 0; k < 3; ++k) {
        double seconds = 0;
        EXPECT_TRUE(timedInfo(seconds)) << "beside 20 slow clients";
        EXPECT_LT(seconds, 1.0) << "beside 20 slow clients";
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    done = true;
    dribbler.join();
    for (const int fd : slow)
        if (fd >= 0) ::close(fd);
    // 50 requests pipelined on one connection: 50 answers, in order.
    const int fd = connectTo(server.port());
    ASSERT_GE(fd, 0);
    std::string fifty;
    for (int k = 0; k < 50; ++k) fifty += "GET /api/info HTTP/1.1\r\nHost: x\r\n\r\n";
    sendAll(fd, fifty);
    const test::Answers a = test::readAnswers(fd, 50, std::chrono::seconds(20));
    ::close(fd);
    EXPECT_EQ(a.statuses.size(), 50u);
    EXPECT_EQ(std::count(a.statuses.begin(), a.statuses.end(), 200), 50);
    EXPECT_FALSE(a.reset);
    server.stop();
}
