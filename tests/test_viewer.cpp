// The live relighting viewer (app/Viewer.h, app/ViewerServer.h): the session's relight is T·E,
// its judge numbers are the Judge's, every request is validated; the server survives malformed
// requests and connections closed mid-transfer; and the page, driven in headless Chromium,
// paints a texel and shows the image and judge numbers that `relight` and `judge` give for the
// saved light (screenshot at build/test-artifacts/viewer-screenshot.png).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <string>

#include "TestUtil.h"
#include "app/Judge.h"
#include "app/Plot.h"
#include "app/Transport.h"
#include "app/Viewer.h"
#include "app/ViewerServer.h"
#include "core/Error.h"
#include "io/EnvMapIO.h"
#include "io/ImageIO.h"
#include "io/SceneFile.h"
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

/// A raw TCP connection to 127.0.0.1:port (−1 on failure).
int connectTo(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(fd);
        return -1;
    }
    return fd;
}

void sendAll(int fd, const std::string& s) {
    [[maybe_unused]] const ssize_t n = ::send(fd, s.data(), s.size(), MSG_NOSIGNAL);
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

TEST(ViewerBrowser, PaintingATexelMatchesRelightAndJudge) {
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

    // `relight` on the same T (precompute at the same spp and seed) gives the viewer's render.
    const std::string tm = (dir / "p.tm").string(), relit = (dir / "relit.exr").string();
    ASSERT_EQ(test::runCli("precompute " + scene + " --spp 4 -o " + tm).exitCode, 0);
    auto r = test::runCli("relight " + tm + " --envmap " + saved.string() + " -o " + relit);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Image a = readImage(relit), b = readImage(o.outDir / "selftest-render.exr");
    ASSERT_EQ(a.data.size(), b.data.size());
    for (size_t p = 0; p < a.data.size(); ++p) ASSERT_FLOAT_EQ(a.data[p], b.data[p]) << p;
    // ...and the page's image is that render at the page's exposure.
    test::writeText(dir / "page.png", session.imagePng(0, self["exposure"].get<double>()));
    const Image shown = readImage(dir / "page.png");
    for (size_t p = 0; p < a.data.size(); ++p)
        ASSERT_NEAR(shown.data[p], std::min(1.0, a.data[p] * self["exposure"].get<double>()), 0.02);

    // `judge` on the saved light gives the page's numbers.
    r = test::runCli("judge " + scene + " " + saved.string() + " --spp 16 --truth " + truth +
                     " --no-references --cache " + cache + " -o " + (dir / "judge").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json jj = json::parse(test::readFile(dir / "judge" / "judge.json"))["lights"][0];
    const json& page = self["after"]["judge"];
    EXPECT_NEAR(page["eq2"].get<double>(), jj["eq2"].get<double>(),
                1e-9 * std::abs(jj["eq2"].get<double>()));
    EXPECT_NEAR(page["unbiased"].get<double>(), jj["unbiased"].get<double>(),
                1e-9 * std::abs(jj["unbiased"].get<double>()));
    ASSERT_EQ(page["visibility"].size(), jj["visibility"].size());
    ASSERT_FALSE(jj["visibility"].empty());
    for (size_t k = 0; k < jj["visibility"].size(); ++k)
        EXPECT_NEAR(page["visibility"][k]["visibility"].get<double>(),
                    jj["visibility"][k]["visibility"].get<double>(), 1e-9)
            << jj["visibility"][k]["name"];

    // A screenshot with the A/B split and the defect overlay.
    const fs::path shot =
        fs::path(SL_CLI_PATH).parent_path() / "test-artifacts" / "viewer-screenshot.png";
    fs::create_directories(shot.parent_path());
    fs::remove(shot);
    const auto sc = test::runShell(chromium + "--screenshot=" + shot.string() + " '" +
                                   server.url() + "?split=1&overlay=1'");
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
    // Light A is E*, and the judge scores it as the report did (E* stored as float32).
    const auto& t = s.transport();
    const EnvMap star = loadEnvMap(out / "envmap.exr", t.envWidth, t.envHeight, 1);
    for (size_t k = 0; k < t.cols(); ++k)
        ASSERT_EQ(s.light(0)[k], static_cast<double>(star.texels[k]));
    const json summary = json::parse(test::readFile(out / "summary.json"));
    const double reported = summary["compare"]["optimized"]["judge"]["eq2"].get<double>();
    EXPECT_NEAR(s.judgeJson(0)["judge"]["eq2"].get<double>(), reported, 1e-4 * reported);
    // An output directory without summary.json is refused with the fix.
    o.input = dir.path();
    try {
        ViewerSession bad(o);
        ADD_FAILURE() << "a directory without summary.json was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("summary.json"), std::string::npos) << e.what();
    }
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
