// POV-Ray as a black-box renderer (app/host/ExternalRenderer.h, io/PovrayExport.h): the exported
// scene renders what our tracer renders (a tilted mirror under a one-texel env map lights the
// same pixels), the render is linear in the light, T from basis renders reproduces a direct
// render, SPSA through POV-Ray lowers the loss, and failures are clear errors. Tiny images.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "TestUtil.h"
#include "app/host/ExternalRenderer.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "io/ImageIO.h"
#include "io/SceneFile.h"
#include "objective/Objective.h"
#include "optimize/BlackBox.h"
#include "render/Render.h"
#include "render/Renderer.h"
#include "scene/Scene.h"

namespace sl {
namespace {

bool havePovray() {
    return std::system("command -v povray > /dev/null 2>&1") == 0;
}

#define REQUIRE_POVRAY()                                                         \
    if (!havePovray()) {                                                         \
        GTEST_SKIP() << "povray is not installed (scripts/install-deps has it)"; \
    }

/// An n×n plane h = sx·x + sz·z (x, z in mm, scene/Heightfield.h's frame), pitch p.
std::vector<float> tiltedPlane(int n, double p, double sx, double sz) {
    std::vector<float> h(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            h[static_cast<size_t>(j) * n + i] =
                static_cast<float>(sx * (i - 0.5 * (n - 1)) * p + sz * (j - 0.5 * (n - 1)) * p);
    return h;
}

std::unique_ptr<Scene> makeScene(const test::TempDir& dir, const std::vector<float>& h, int n,
                                 const std::string& material, int px, int envW = 50,
                                 int envH = 25) {
    test::writeNpyF32(dir / "h.npy", n, n, h);
    const std::string json = R"({"heightmap": {"path": "h.npy", "pixel_pitch": 0.25},
        "material": )" + material +
                             R"(,
        "camera": {"width": )" +
                             std::to_string(px) + R"(, "height": )" + std::to_string(px) +
                             R"(, "fov": 30},
        "envmap": {"width": )" +
                             std::to_string(envW) + R"(, "height": )" + std::to_string(envH) + R"(},
        "render": {"spp": 16, "max_depth": 2, "seed": 3}})";
    return loadScene(parseScene(json, dir.path(), "test scene"));
}

std::vector<double> lum(const Image& img) {
    std::vector<double> y(img.pixelCount());
    for (size_t p = 0; p < y.size(); ++p) {
        const float* c = img.data.data() + p * img.channels;
        y[p] = luminance<double>(c[0], c[1], c[2]);
    }
    return y;
}

// An interrupt (Ctrl-C, SIGTERM to us) stops the external renderer too: it gets SIGTERM, or
// SIGKILL 2 s later when it ignores that, is reaped, and Interrupted is thrown. No povray needed.
TEST(ExternalRenderer, InterruptStopsTheRenderer) {
    test::TempDir dir("renderer-interrupt");
    for (const std::string script :
         {"echo $$ > child.pid; exec sleep 60",
          "trap '' TERM; echo $$ > child.pid; while :; do sleep 0.05; done"}) {
        SCOPED_TRACE(script);
        clearInterrupt();
        std::filesystem::remove(dir / "child.pid");
        std::thread asker([&] {
            for (int i = 0; i < 500 && !std::filesystem::exists(dir / "child.pid"); ++i)
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
            requestInterrupt(SIGTERM);
        });
        const auto start = std::chrono::steady_clock::now();
        EXPECT_THROW(runProcess({"sh", "-c", script}, dir.path(), 60.0), Interrupted);
        const double waited =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        asker.join();
        clearInterrupt();
        EXPECT_LT(waited, 20.0);  // not the 60 s the child would run
        const pid_t child = static_cast<pid_t>(std::stol(test::readFile(dir / "child.pid")));
        errno = 0;
        EXPECT_EQ(kill(child, 0), -1) << "the renderer " << child << " is still there";
        EXPECT_EQ(errno, ESRCH);
    }
}

namespace {

/// Whether process `pid` is gone or a zombie (killed, not yet reaped by its new parent), polled
/// for up to `seconds`: a SIGKILL is delivered at once, but not synchronously with kill().
bool processEnded(pid_t pid, double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    for (;;) {
        const std::string stat = test::readFile("/proc/" + std::to_string(pid) + "/stat");
        const size_t paren = stat.rfind(')');
        if (stat.empty() || paren == std::string::npos ||
            (paren + 2 < stat.size() && stat[paren + 2] == 'Z'))
            return true;
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
}

}  // namespace

// Issue 35: after --renderer-timeout or SIGTERM the renderer's children kept running (only its
// pid was signalled). It runs in its own process group now, and the group is killed: on the
// timeout, on an interrupt, and what it leaves running when it exits.
TEST(ExternalRenderer, ItsChildrenDoNotOutliveIt) {
    test::TempDir dir("renderer-group");
    const std::string script = "sleep 60 & echo $! > child.pid; wait";
    auto childPid = [&] {
        return static_cast<pid_t>(std::stol(test::readFile(dir / "child.pid")));
    };
    {  // the timeout
        clearInterrupt();
        const ProcessResult r = runProcess({"sh", "-c", script}, dir.path(), 0.5);
        EXPECT_TRUE(r.timedOut);
        EXPECT_TRUE(processEnded(childPid(), 10)) << "the renderer's child is still there";
    }
    {  // an interrupt (Ctrl-C, SIGTERM to us)
        std::filesystem::remove(dir / "child.pid");
        clearInterrupt();
        std::thread asker([&] {
            for (int i = 0; i < 500 && !std::filesystem::exists(dir / "child.pid"); ++i)
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
            requestInterrupt(SIGTERM);
        });
        EXPECT_THROW(runProcess({"sh", "-c", script}, dir.path(), 60.0), Interrupted);
        asker.join();
        clearInterrupt();
        EXPECT_TRUE(processEnded(childPid(), 10)) << "the renderer's child is still there";
    }
    {  // a renderer that exits and leaves a child running
        std::filesystem::remove(dir / "child.pid");
        const ProcessResult r =
            runProcess({"sh", "-c", "sleep 60 & echo $! > child.pid"}, dir.path(), 60.0);
        EXPECT_EQ(r.exitCode, 0);
        EXPECT_TRUE(processEnded(childPid(), 10)) << "the renderer's child is still there";
    }
}

TEST(Povray, TiltedMirrorUnderOneTexelLightsTheSamePixelsAsOurTracer) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-mirror");
    const int n = 41, px = 32;
    auto scene = makeScene(dir, tiltedPlane(n, 0.25, 0.12, -0.07), n,
                           R"({"type": "conductor", "material": "none"})", px);
    // The texel nearest the mirror direction of the camera's centre ray off the plane.
    const CameraDesc& c = scene->camera.desc();
    const Vec3d d = normalize(c.target - c.origin);
    const Vec3d nrm = normalize(Vec3d{-0.12, 1.0, 0.07});
    const Vec3d r = d - nrm * (2 * dot(d, nrm));
    const TexelWeights w = scene->basis.weights(
        Vec3f{static_cast<float>(r.x), static_cast<float>(r.y), static_cast<float>(r.z)});
    const size_t texel =
        w.index[std::max_element(w.weight.begin(), w.weight.end()) - w.weight.begin()];
    EnvMap env = EnvMap::constant(50, 25, 0.0f);
    env.texels[texel] = 1.0f;

    const BuiltinRenderer ours(*scene, renderOptionsFor(*scene));
    const ExternalRenderer pov(*scene, {});
    const std::vector<double> a = lum(ours.render(env, 3, 0));
    const std::vector<double> b = lum(pov.render(env, 3, 0));
    ASSERT_EQ(a.size(), b.size());
    double sa = 0, sb = 0, cxA = 0, cyA = 0, cxB = 0, cyB = 0, diff = 0, norm = 0;
    int litA = 0, litB = 0, both = 0;
    for (int y = 0; y < px; ++y)
        for (int x = 0; x < px; ++x) {
            const size_t p = static_cast<size_t>(y) * px + x;
            sa += a[p];
            sb += b[p];
            cxA += x * a[p];
            cyA += y * a[p];
            cxB += x * b[p];
            cyB += y * b[p];
            diff += (a[p] - b[p]) * (a[p] - b[p]);
            norm += a[p] * a[p];
            litA += a[p] > 0.25;
            litB += b[p] > 0.25;
            both += a[p] > 0.25 && b[p] > 0.25;
        }
    std::printf(
        "ours: sum %.2f lit %d centroid (%.2f, %.2f); POV-Ray: sum %.2f lit %d centroid "
        "(%.2f, %.2f); both lit %d; relative L2 difference %.3f\n",
        sa, litA, cxA / sa, cyA / sa, sb, litB, cxB / sb, cyB / sb, both, std::sqrt(diff / norm));
    ASSERT_GT(litA, 20);  // the texel lights a patch of the image, not all of it
    ASSERT_LT(litA, px * px / 2);
    EXPECT_NEAR(sb / sa, 1.0, 0.05);
    EXPECT_NEAR(cxB / sb, cxA / sa, 0.3);
    EXPECT_NEAR(cyB / sb, cyA / sa, 0.3);
    EXPECT_GE(both, 0.9 * std::max(litA, litB));
    EXPECT_LT(std::sqrt(diff / norm), 0.15);
}

TEST(Povray, RoughConductorBlurIsCloseToOurGgx) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-rough");
    const int n = 64;
    std::vector<float> h(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            h[static_cast<size_t>(j) * n + i] =
                static_cast<float>(0.02 * std::sin(0.15 * i) * std::cos(0.11 * j));
    auto scene =
        makeScene(dir, h, n, R"({"type": "roughconductor", "alpha": 0.1, "material": "Al"})", 48);
    EnvMap env = EnvMap::constant(50, 25, 0.0f);  // a checker of 3 rows x 4 columns
    for (int r = 0; r < 25; ++r)
        for (int c = 0; c < 50; ++c)
            env.texels[static_cast<size_t>(r) * 50 + c] = ((r / 3 + c / 4) % 2) ? 1.0f : 0.0f;
    RenderOptions ro = renderOptionsFor(*scene);
    ro.spp = 256;
    const Image a = BuiltinRenderer(*scene, ro).render(env, 3, 0);
    const Image b = ExternalRenderer(*scene, {}).render(env, 0, 0);
    double d = 0, nn = 0, sa = 0, sb = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        d += (a.data[i] - b.data[i]) * (a.data[i] - b.data[i]);
        nn += a.data[i] * a.data[i];
        sa += a.data[i];
        sb += b.data[i];
    }
    std::printf("alpha 0.1: POV-Ray against ours: relative L2 %.3f, mean ratio %.3f\n",
                std::sqrt(d / nn), sb / sa);
    EXPECT_LT(std::sqrt(d / nn), 0.2);  // bumpsPerAlpha 1 gave 0.49 (io/PovrayExport.h)
    EXPECT_NEAR(sb / sa, 1.0, 0.1);
}

TEST(Povray, RenderIsLinearInTheLight) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-linear");
    const int n = 40;
    auto scene = makeScene(dir, test::bumpyHeightMap(n), n,
                           R"({"type": "roughconductor", "alpha": 0.1, "material": "Al"})", 24);
    const ExternalRenderer pov(*scene, {});
    const auto [e1, e2] = linearityPair(50, 25, 5);
    const double err = linearityError(pov, e1, e2, 0, 0);
    std::printf("POV-Ray linearity error %.3g\n", err);
    EXPECT_LT(err, 2e-3);  // POV-Ray's half-float EXR rounds at 2^-11
}

// `render --renderer povray`: the same scene and light through POV-Ray from the command line,
// an EXR of the camera's size with a PNG beside it, as close to our tracer's render of the same
// scene as the export makes it (a diffuse-looking rough conductor under a smooth sky).
TEST(Povray, RenderCommandWithPovray) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-render-cli");
    const int n = 40;
    auto scene = makeScene(dir, test::bumpyHeightMap(n), n,
                           R"({"type": "roughconductor", "alpha": 0.3, "material": "Al"})", 24);
    test::writeText(dir / "scene.json", scene->desc.canonicalJson);
    const std::string sceneFile = (dir / "scene.json").string();
    auto r = test::runCli("render " + sceneFile + " --renderer povray --envmap studio -o " +
                          (dir / "pov.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("with povray"), std::string::npos) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir / "pov.png"));
    r = test::runCli("render " + sceneFile + " --envmap studio --spp 64 -o " +
                     (dir / "ours.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Image pov = readImage(dir / "pov.exr"), ours = readImage(dir / "ours.exr");
    ASSERT_EQ(pov.width, 24);
    ASSERT_EQ(pov.height, 24);
    ASSERT_EQ(ours.width, 24);
    const std::vector<double> a = lum(pov), b = lum(ours);
    double d = 0, nn = 0;
    for (size_t p = 0; p < a.size(); ++p) {
        d += (a[p] - b[p]) * (a[p] - b[p]);
        nn += b[p] * b[p];
    }
    std::printf("render --renderer povray vs ours: relative RMS difference %.3f\n",
                std::sqrt(d / nn));
    EXPECT_LT(std::sqrt(d / nn), 0.3);
}

// Bad combinations are refused before any work, naming the option; no output is written.
TEST(ExternalRenderer, RenderCommandRefusesBadCombinations) {
    test::TempDir dir("render-cli-refused");
    const int n = 16;
    auto scene = makeScene(dir, test::bumpyHeightMap(n), n, R"({"type": "conductor"})", 8);
    test::writeText(dir / "scene.json", scene->desc.canonicalJson);
    const std::string base =
        "render " + (dir / "scene.json").string() + " -o " + (dir / "x.exr").string();
    auto r = test::runCli(base + " --renderer command");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--renderer-cmd"), std::string::npos) << r.output;
    r = test::runCli(base + " --renderer povray --max-depth 3");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--max-depth"), std::string::npos) << r.output;
    r = test::runCli(base + " --renderer povray --spp 64");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--spp"), std::string::npos) << r.output;
    // a command that writes an image of the wrong size (the env map): a clear error
    r = test::runCli(base + " --renderer-cmd 'cp {envmap} {output}'");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("cp"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "x.exr"));
    EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

TEST(Povray, TransportFromBasisRendersMatchesADirectRender) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-basis");
    const int n = 40;
    auto scene =
        makeScene(dir, test::bumpyHeightMap(n), n,
                  R"({"type": "roughconductor", "alpha": 0.1, "material": "Al"})", 16, 6, 4);
    ExternalRendererOptions ro;
    ro.povray.supersample = 2;
    ro.povray.roughSamples = 4;
    const ExternalRenderer pov(*scene, ro);
    BasisTransportOptions bo;
    bo.cacheDir = dir / "cache";
    const BasisTransportResult r = basisTransport(*scene, pov, bo);
    EXPECT_EQ(r.rendered, 24);
    EXPECT_EQ(r.reused, 0);
    const TransportMatrix& T = r.file.matrix;
    ASSERT_EQ(T.cols(), 24u);
    ASSERT_EQ(T.rows(), 256u);
    // T·E against a direct render of a random E.
    auto [e1, e2] = linearityPair(6, 4, 9);
    const std::vector<double> E(e1.texels.begin(), e1.texels.end());
    std::vector<double> Y(T.rows());
    T.applyLuminance(E, Y);
    const std::vector<double> direct = lum(pov.render(e1, 0, 0));
    double diff = 0, norm = 0;
    for (size_t p = 0; p < Y.size(); ++p) {
        diff += (Y[p] - direct[p]) * (Y[p] - direct[p]);
        norm += direct[p] * direct[p];
    }
    std::printf("T.E vs direct POV-Ray render: relative L2 %.3g (linearity error %.3g)\n",
                std::sqrt(diff / norm), r.linearityError);
    EXPECT_GT(r.linearityError, 0.0);  // measured on renders that are not black
    EXPECT_LT(r.directError, 3e-3);
    EXPECT_LT(r.linearityError, 2e-3);
    ASSERT_GT(norm, 0);
    EXPECT_LT(std::sqrt(diff / norm), 3e-3);
    // A second run reads every column from the cache.
    const BasisTransportResult again = basisTransport(*scene, pov, bo);
    EXPECT_EQ(again.rendered, 0);
    EXPECT_EQ(again.reused, 24);
    EXPECT_EQ(again.file.matrix.values, T.values);
}

TEST(Povray, SpsaThroughPovrayLowersTheLoss) {
    REQUIRE_POVRAY();
    test::TempDir dir("povray-spsa");
    const int n = 64;
    auto scene = makeScene(dir, test::bumpyHeightMap(n), n,
                           R"({"type": "roughconductor", "alpha": 0.1, "material": "Al"})", 64);
    ExternalRendererOptions ro;
    ro.povray.supersample = 1;
    ro.povray.roughSamples = 4;
    const ExternalRenderer pov(*scene, ro);
    RenderOptions opt = renderOptionsFor(*scene);
    ObjectiveOptions oo;
    oo.lambda = 30;
    const ImageObjective objective(64, 64, objectMaskFor(*scene, opt), oo);
    const RenderLoss loss(pov, 50, 25, 0, objective);
    // Not a constant start: with POV-Ray's constant Fresnel factor a uniform light renders a
    // uniform image (no contrast, the loss's G = 0), see io/PovrayExport.h.
    std::vector<double> E(loss.dimension());
    for (size_t i = 0; i < E.size(); ++i)
        E[i] = 0.5 + 0.3 * std::sin(0.731 * static_cast<double>(i) + 0.3);
    OptimizerOptions o;
    o.method = OptimizerMethod::Spsa;
    o.iterations = 6;
    BlackBoxOptions bb;
    bb.spsa.calibrationEstimates = 1;
    const double before = loss.evaluate(E, 0).total;
    const OptimizerSummary s = minimizeBlackBox(loss, E, o, bb);
    const double after = loss.evaluate(E, 0).total;
    std::printf("SPSA through POV-Ray: loss %.5f -> %.5f in %d renders, %.2f s\n", before, after,
                s.evaluations, s.seconds);
    EXPECT_LT(after, before);
}

TEST(Povray, FailuresAreClearErrors) {
    test::TempDir dir("povray-errors");
    const int n = 20;
    auto scene = makeScene(dir, test::bumpyHeightMap(n), n,
                           R"({"type": "conductor", "material": "none"})", 8);
    ExternalRendererOptions missing;
    missing.program = "no-such-povray-binary";
    try {
        ExternalRenderer r(*scene, missing);
        FAIL() << "a missing binary must be refused";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no-such-povray-binary"), std::string::npos);
    }
    const EnvMap env = EnvMap::constant(50, 25, 0.5f);
    ExternalRendererOptions fails;
    fails.command = "false {output}";
    try {
        ExternalRenderer(*scene, fails).render(env, 0, 1);
        FAIL() << "a failing command must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("failed (exit 1)"), std::string::npos) << e.what();
    }
    ExternalRendererOptions noOutput;
    noOutput.command = "true {scene} {envmap} {output}";
    try {
        ExternalRenderer(*scene, noOutput).render(env, 0, 1);
        FAIL() << "a command without output must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("wrote no image"), std::string::npos) << e.what();
    }
    ExternalRendererOptions wrongSize;  // the env map itself is a 50x25 image, not 8x8
    wrongSize.command = "cp {envmap} {output}";
    try {
        ExternalRenderer(*scene, wrongSize).render(env, 0, 1);
        FAIL() << "a wrong-sized output must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("expected 8x8"), std::string::npos) << e.what();
    }
    ExternalRendererOptions slow;
    slow.command = "sh -c 'sleep 5' {output}";
    slow.timeoutSeconds = 0.2;
    try {
        ExternalRenderer(*scene, slow).render(env, 0, 1);
        FAIL() << "a render past the timeout must throw";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("did not finish within"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(expandCommand("render {scene}", "s", "e", "o"), InputError);  // no {output}
    EXPECT_EQ(expandCommand("r '{scene} x' {output}", "S", "E", "O"),
              (std::vector<std::string>{"r", "S x", "O"}));
}

}  // namespace
}  // namespace sl
