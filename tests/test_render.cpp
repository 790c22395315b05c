// Renderer physics that holds exactly: white furnace, analytic mirror mapping, determinism,
// and format independence of the height-map input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "TestUtil.h"
#include "core/Rng.h"
#include "io/HeightmapIO.h"
#include "io/ImageIO.h"
#include "io/SceneFile.h"
#include "render/Footprint.h"
#include "render/Render.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

std::vector<float> flatHeights(int w, int h) {
    return std::vector<float>(size_t(w) * h, 0.0f);
}

/// Gentle sinusoidal bumps (slopes < 0.3), in mm.
std::vector<float> bumpyHeights(int w, int h, double pitch) {
    std::vector<float> v(size_t(w) * h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            v[size_t(j) * w + i] =
                static_cast<float>(0.02 * std::sin(i * pitch * 9.0) * std::cos(j * pitch * 7.0));
    return v;
}

SceneDesc baseDesc(double pitch = 0.05) {
    SceneDesc d;
    d.heightmap.pitch = pitch;
    d.material.params.ior = ComplexIor{Rgb{0.0f}, Rgb{1.0f}};  // "none": F == 1
    d.camera.width = 32;
    d.camera.height = 32;
    return d;
}

/// Orthographic camera looking at the origin along `dir`, covering the central part of the map.
CameraSpec orthoLooking(const Vec3d& dir, double widthMm) {
    CameraSpec c;
    c.type = CameraDesc::Type::Orthographic;
    c.origin = -normalize(dir) * 20.0;
    c.target = Vec3d{0, 0, 0};
    c.up = Vec3d{0, 1, 0};
    c.widthMm = widthMm;
    c.width = c.height = 16;
    return c;
}

RenderOptions opts(int spp, int depth, int threads = 0) {
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = depth;
    o.seed = 3;
    o.threads = threads;
    return o;
}

EnvMap randomEnv(int w, int h, uint64_t seed) {
    EnvMap e = EnvMap::constant(w, h, 0.0f);
    Pcg32 rng(seed, 1);
    for (float& t : e.texels) t = rng.nextFloat();
    return e;
}

}  // namespace

TEST(Furnace, SmoothMirrorOnFlatPlaneIsExactlyOne) {
    SceneDesc d = baseDesc();
    d.material.params.smooth = true;
    Scene s(d, 64, 64, flatHeights(64, 64));
    RenderResult r = render(s, EnvMap::constant(50, 25, 1.0f), opts(4, 2));
    int masked = 0;
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        if (!r.summary.objectMask[p]) continue;
        ++masked;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(r.image.data[3 * p + c], 1.0f, 1e-6f);
    }
    EXPECT_GT(masked, 200);  // the default camera frames the whole part
}

TEST(Furnace, SmoothMirrorOnBumpySurfaceIsOne) {
    SceneDesc d = baseDesc();
    d.material.params.smooth = true;
    Scene s(d, 64, 64, bumpyHeights(64, 64, 0.05));
    RenderResult r = render(s, EnvMap::constant(50, 25, 1.0f), opts(4, 32));
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        if (!r.summary.objectMask[p]) continue;
        EXPECT_NEAR(r.image.data[3 * p + 1], 1.0f, 1e-5f) << p;
    }
}

TEST(Furnace, RoughConductorIsAtMostOneAndTendsToOne) {
    double previous = 0;
    for (float alpha : {0.3f, 0.05f, 0.001f}) {
        for (Microfacet dist : {Microfacet::GGX, Microfacet::Beckmann}) {
            SceneDesc d = baseDesc();
            d.material.params.alphaU = d.material.params.alphaV = alpha;
            d.material.params.distribution = dist;
            Scene s(d, 64, 64, flatHeights(64, 64));
            RenderResult r = render(s, EnvMap::constant(50, 25, 1.0f), opts(16, 2));
            double sum = 0, sum2 = 0;
            int n = 0;
            for (size_t p = 0; p < r.image.pixelCount(); ++p) {
                if (!r.summary.objectMask[p]) continue;
                double v = r.image.data[3 * p];
                sum += v;
                sum2 += v * v;
                ++n;
                // Every sample weight is F·G1 <= 1; Mitsuba's rational approximation of the
                // Beckmann G1 (which we reproduce) overshoots 1 by up to ~3e-5.
                EXPECT_LE(v, dist == Microfacet::GGX ? 1.0 + 1e-6 : 1.0 + 5e-5);
            }
            double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
            EXPECT_LE(mean, 1.0 + 3 * se);
            if (alpha == 0.001f) {
                EXPECT_GT(mean, 0.999) << "alpha " << alpha;
            }
            if (alpha == 0.05f) {
                EXPECT_GT(mean, 0.95) << "alpha " << alpha;
            }
            if (dist == Microfacet::GGX) {
                EXPECT_GE(mean, previous - 3 * se) << "albedo should grow as alpha -> 0";
                previous = mean;
            }
        }
    }
}

TEST(Mirror, OrthographicPixelsReadTheReflectedTexel) {
    const int W = 50, H = 25;
    EnvMap env = randomEnv(W, H, 11);
    for (auto [row, col] :
         {std::pair{8, 10}, std::pair{5, 0}, std::pair{11, 37}, std::pair{3, 49}}) {
        // Reflected direction = centre of texel (row, col): θ = rowπ/(H−1), u = (col+½)/W.
        double theta = row * std::numbers::pi / (H - 1),
               phi = 2 * std::numbers::pi * (col + 0.5) / W;
        Vec3d r{std::sin(phi) * std::sin(theta), std::cos(theta), -std::cos(phi) * std::sin(theta)};
        Vec3d incoming{r.x, -r.y, r.z};  // mirror about the +Y plane
        SceneDesc d = baseDesc();
        d.material.params.smooth = true;
        d.camera = orthoLooking(incoming, 0.5);
        Scene s(d, 160, 160, flatHeights(160, 160));  // 8 mm: holds the grazing footprints
        RenderResult res = render(s, env, opts(4, 2));
        float expected = env.texels[size_t(row) * W + col];
        for (size_t p = 0; p < res.image.pixelCount(); ++p) {
            ASSERT_TRUE(res.summary.objectMask[p]);
            EXPECT_NEAR(res.image.data[3 * p], expected, 2e-4f) << "texel " << row << "," << col;
        }
    }
}

TEST(Mirror, OrthographicPixelsBetweenTexelsAreBilinear) {
    const int W = 50, H = 25;
    EnvMap env = randomEnv(W, H, 5);
    // u at a quarter between columns 20 and 21, θ at 0.7 between rows 6 and 7.
    double u = (20.5 + 0.25) / W, theta = (6 + 0.7) * std::numbers::pi / (H - 1);
    double phi = 2 * std::numbers::pi * u;
    Vec3d r{std::sin(phi) * std::sin(theta), std::cos(theta), -std::cos(phi) * std::sin(theta)};
    SceneDesc d = baseDesc();
    d.material.params.smooth = true;
    d.camera = orthoLooking({r.x, -r.y, r.z}, 0.5);
    Scene s(d, 32, 32, flatHeights(32, 32));
    RenderResult res = render(s, env, opts(1, 2));
    auto E = [&](int j, int i) { return double(env.texels[size_t(j) * W + i]); };
    double expected = 0.75 * 0.3 * E(6, 20) + 0.25 * 0.3 * E(6, 21) + 0.75 * 0.7 * E(7, 20) +
                      0.25 * 0.7 * E(7, 21);
    for (size_t p = 0; p < res.image.pixelCount(); ++p)
        EXPECT_NEAR(res.image.data[3 * p], expected, 2e-4);
}

TEST(Mirror, MaterialFresnelScalesTheMirrorImage) {
    // A smooth conductor with eta, k reflects F(cos θ) of the env map at normal incidence.
    SceneDesc d = baseDesc();
    d.material.params.smooth = true;
    d.material.params.ior = ComplexIor{Rgb{1.5f, 0.5f, 0.2f}, Rgb{3.0f, 2.5f, 4.0f}};
    d.camera = orthoLooking({0.0, -1.0, 1e-3}, 0.5);
    d.camera.up = Vec3d{0, 0, -1};
    Scene s(d, 32, 32, flatHeights(32, 32));
    RenderResult res = render(s, EnvMap::constant(50, 25, 1.0f), opts(1, 2));
    for (int c = 0; c < 3; ++c) {
        double eta = d.material.params.ior.eta[c], k = d.material.params.ior.k[c];
        double f0 = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
        EXPECT_NEAR(res.image.data[3 * 100 + c], f0, 1e-4) << "channel " << c;
    }
}

TEST(Render, BackgroundIsZeroAndOutsideTheMask) {
    SceneDesc d = baseDesc();
    d.camera.type = CameraDesc::Type::Orthographic;
    d.camera.widthMm = 6.0;  // wider than the 3.15 mm part
    Scene s(d, 64, 64, flatHeights(64, 64));
    RenderResult r = render(s, EnvMap::constant(50, 25, 1.0f), opts(4, 2));
    int background = 0;
    for (size_t p = 0; p < r.image.pixelCount(); ++p)
        if (r.summary.coverage[p] == 0.0f) {
            ++background;
            EXPECT_EQ(r.summary.objectMask[p], 0);
            EXPECT_EQ(r.image.data[3 * p], 0.0f);
        }
    EXPECT_GT(background, 100);
}

TEST(Render, ProgressCountsTheFootprintsSamplesRowByRow) {
    // Rows are traced in order; the progress is the share of the footprint's samples done, so
    // rows that miss the part add nothing and the fraction grows with the work (the ETA holds).
    SceneDesc d = baseDesc();
    d.camera.type = CameraDesc::Type::Orthographic;
    d.camera.widthMm = 6.0;  // wider than the 3.15 mm part: the first and last rows miss it
    Scene s(d, 64, 64, flatHeights(64, 64));
    const std::vector<PixelSpan> spans = partFootprint(s);
    std::vector<double> expected;
    double total = 0, done = 0;
    for (const PixelSpan& sp : spans) total += sp.end - sp.begin;
    for (const PixelSpan& sp : spans) expected.push_back((done += sp.end - sp.begin) / total);
    ASSERT_EQ(spans.front().end - spans.front().begin, 0);  // a row outside the footprint
    RenderOptions o = opts(4, 2, 1);                        // one thread: every row reported
    std::vector<double> reported;
    o.progress = [&](double f) { reported.push_back(f); };
    render(s, EnvMap::constant(50, 25, 1.0f), o);
    ASSERT_EQ(reported.size(), expected.size());
    for (size_t k = 0; k < reported.size(); ++k) EXPECT_DOUBLE_EQ(reported[k], expected[k]) << k;
    EXPECT_EQ(reported.front(), 0.0);
    EXPECT_EQ(reported.back(), 1.0);
}

TEST(Render, BitIdenticalForAnyThreadCount) {
    SceneDesc d = baseDesc();
    d.material.params.alphaU = 0.2f;
    d.material.params.alphaV = 0.05f;
    Scene s(d, 64, 64, bumpyHeights(64, 64, 0.05));
    EnvMap env = randomEnv(50, 25, 2);
    RenderResult a = render(s, env, opts(8, 4, 1));
    RenderResult b = render(s, env, opts(8, 4, 2));
    RenderResult c = render(s, env, opts(8, 4, 7));
    ASSERT_EQ(a.image.data.size(), b.image.data.size());
    EXPECT_EQ(0, std::memcmp(a.image.data.data(), b.image.data.data(), a.image.data.size() * 4));
    EXPECT_EQ(0, std::memcmp(a.image.data.data(), c.image.data.data(), a.image.data.size() * 4));
    // A different seed gives a different image.
    RenderOptions o = opts(8, 4);
    o.seed = 4;
    RenderResult e = render(s, env, o);
    EXPECT_NE(0, std::memcmp(a.image.data.data(), e.image.data.data(), a.image.data.size() * 4));
}

TEST(Render, EveryHeightMapFormatGivesTheSameRender) {
    test::TempDir dir("formats");
    const int W = 48, H = 40;  // non-square
    // Heights q·2^-20 mm with 16-bit q: exact in float, in half-free EXR, npy and PNG16 with
    // height_range [0, 65535·2^-20].
    std::vector<float> h(size_t(W) * H);
    Image img(W, H, 1);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            int q = static_cast<int>(32767.5 + 32767 * std::sin(i * 0.4) * std::cos(j * 0.3));
            h[size_t(j) * W + i] = static_cast<float>(std::ldexp(q, -20));
            img.at(i, j) = static_cast<float>(q / 65535.0);
        }
    Image exr(W, H, 1);
    exr.data = h;
    writeExr(dir / "h.exr", exr);
    writePng16(dir / "h.png", img);
    test::writeNpyF32(dir / "h.npy", H, W, h);

    HeightmapOptions floatOpt, intOpt;
    intOpt.heightRange = std::array<double, 2>{0.0, std::ldexp(65535.0, -20)};
    std::vector<Image> renders;
    for (auto [file, o] :
         {std::pair{"h.exr", floatOpt}, std::pair{"h.npy", floatOpt}, std::pair{"h.png", intOpt}}) {
        HeightmapData m = loadHeightmap(dir / file, o);
        ASSERT_EQ(m.width, W);
        ASSERT_EQ(m.height, H);
        EXPECT_EQ(m.heights, h) << file;
        SceneDesc d = baseDesc(0.05);
        Scene s(d, m.width, m.height, std::move(m.heights));
        renders.push_back(render(s, randomEnv(50, 25, 9), opts(4, 3)).image);
    }
    EXPECT_EQ(renders[0].data, renders[1].data);
    EXPECT_EQ(renders[0].data, renders[2].data);
}

TEST(Render, NoCameraRaySlipsThroughTheSurface) {
    // Every camera sample of a pixel well inside the part's outline must hit the height field.
    // Embree's default (non-watertight) grid intersection let about 1 in 10^5 rays through the
    // cracks between triangles: 1627 of 20100 interior pixels at 256², 1024 spp.
    SceneDesc d = readSceneFile(SL_SOURCE_DIR "/scenes/default/scene.json");
    d.camera.width = d.camera.height = 128;
    auto s = loadScene(d);
    RenderOptions o = opts(512, 1);
    struct NullSink : PathSink {
        void consume(const PixelPaths&) override {}
    } sink;
    TraceSummary t = PathTracer(*s).trace(o, sink);
    const int W = 128;
    int interior = 0, missed = 0;
    for (int y = 2; y < W - 2; ++y)
        for (int x = 2; x < W - 2; ++x) {
            bool inside = true;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) inside &= t.coverage[(y + dy) * W + x + dx] > 0;
            if (!inside) continue;
            ++interior;
            missed += t.coverage[y * W + x] < 1.0f;
        }
    std::printf("[ measured ] %d interior pixels, %d with a camera sample through the surface\n",
                interior, missed);
    EXPECT_GT(interior, 3000);
    EXPECT_EQ(missed, 0);
}

TEST(Heightfield, TheBvhIsBuiltOnTheFirstQueryAndAnswersAsBefore) {
    // A flat 5×4 map at height 0.25, pitch 0.5: nothing is built until a ray is asked about;
    // then a ray straight down hits at the plane's height, exactly where it was aimed.
    const std::vector<float> h(20, 0.25f);
    Heightfield hf(5, 4, 0.5, h);
    EXPECT_FALSE(hf.built());
    EXPECT_EQ(hf.minHeight(), 0.25f);
    EXPECT_EQ(hf.maxHeight(), 0.25f);
    SurfaceHit hit;
    ASSERT_TRUE(hf.intersect(Ray{Vec3f{0.3f, 2.0f, -0.2f}, Vec3f{0, -1, 0}}, 0.0f, hit));
    EXPECT_TRUE(hf.built());
    EXPECT_FLOAT_EQ(hit.t, 1.75f);
    EXPECT_FLOAT_EQ(hit.position.y, 0.25f);
    EXPECT_FLOAT_EQ(hit.normal.y, 1.0f);
    EXPECT_FALSE(hf.intersect(Ray{Vec3f{0.3f, 2.0f, -0.2f}, Vec3f{0, 1, 0}}, 0.0f, hit));
    EXPECT_TRUE(hf.occluded(Ray{Vec3f{0.0f, 1.0f, 0.0f}, Vec3f{0, -1, 0}}, 0.0f));
    // The build's figures include the vertex buffer, ours and shared with Embree.
    EXPECT_EQ(hf.stats().vertexBytes, 20 * 3 * sizeof(float));
    EXPECT_GT(hf.stats().embreeBytes, hf.stats().vertexBytes);
    // Another map's stats() builds it too.
    Heightfield other(5, 4, 0.5, h);
    EXPECT_EQ(other.stats().gridCount, 1);
    EXPECT_TRUE(other.built());
}
