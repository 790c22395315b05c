// Direction sampling (render/PathTracer.h, CONVENTION (direction sampling)): the env-map
// sampling density is a density and its estimator of each texel's basis is unbiased; Sobol'
// points are nets; every sampler keeps the furnace, T·E == render(E) and the BSDF sampler's
// mean; `bsdf` traces without shadow rays.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "TestUtil.h"
#include "app/bench/SamplingBench.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Registry.h"
#include "core/Rng.h"
#include "io/SceneFile.h"
#include "render/Render.h"
#include "render/Sobol.h"
#include "scene/EnvMapPresets.h"
#include "scene/EnvSampler.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;

namespace {

constexpr double kPi = std::numbers::pi;

/// ∫ h(ω) dω by the midpoint rule on an n × 2n grid in (θ, φ).
template <class F>
double sphereIntegral(F h, int n = 600) {
    double sum = 0;
    const double dt = kPi / n, dp = 2 * kPi / (2 * n);
    for (int a = 0; a < n; ++a) {
        const double t = (a + 0.5) * dt, st = std::sin(t);
        for (int b = 0; b < 2 * n; ++b) {
            const double p = (b + 0.5) * dp;
            const Vec3f d(static_cast<float>(std::sin(p) * st), static_cast<float>(std::cos(t)),
                          static_cast<float>(-std::cos(p) * st));
            sum += h(d) * st;
        }
    }
    return sum * dt * dp;
}

std::vector<float> randomGuide(int n, uint64_t seed) {
    Pcg32 rng(seed, 5);
    std::vector<float> g(static_cast<size_t>(n));
    for (float& v : g) v = 0.2f + rng.nextFloat();  // bounded ratios: a reliable error bar
    return g;
}

std::unique_ptr<Scene> bumpyScene(float alphaU, float alphaV, bool mirrorIor, int res = 24) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.alphaU = alphaU;
    d.material.params.alphaV = alphaV;
    d.material.params.ior = mirrorIor ? ComplexIor{Rgb{0.0f}, Rgb{1.0f}}
                                      : ComplexIor{Rgb{1.6f, 0.9f, 0.5f}, Rgb{9.0f, 6.3f, 4.8f}};
    d.camera.width = d.camera.height = res;
    const int n = 48;
    return std::make_unique<Scene>(d, n, n, test::bumpyHeightMap(n));
}

RenderOptions opts(Sampling s, int spp, int depth = 4, uint64_t seed = 17) {
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = depth;
    o.seed = seed;
    o.sampling = s;
    return o;
}

/// Mean luminance over the pixels every camera sample of which hit the part.
double maskedMean(const RenderResult& r) {
    double sum = 0;
    size_t n = 0;
    for (size_t p = 0; p < r.image.pixelCount(); ++p) {
        if (!r.summary.objectMask[p]) continue;
        sum += luminance<double>(r.image.data[3 * p], r.image.data[3 * p + 1],
                                 r.image.data[3 * p + 2]);
        ++n;
    }
    return n ? sum / static_cast<double>(n) : 0;
}

struct MeanAndError {
    double mean = 0, se = 0;
};

/// The image mean over `seeds` independent renders, with its standard error from their spread.
MeanAndError meanOverSeeds(const Scene& s, const EnvMap& env, Sampling sampling, int spp,
                           int seeds) {
    std::vector<double> m;
    for (int k = 0; k < seeds; ++k)
        m.push_back(maskedMean(render(s, env, opts(sampling, spp, 4, 100 + k))));
    double mean = 0, var = 0;
    for (double v : m) mean += v;
    mean /= seeds;
    for (double v : m) var += (v - mean) * (v - mean);
    var /= seeds - 1;
    return {mean, std::sqrt(var / seeds)};
}

const char* name(Sampling s) {
    return registryRow(samplingTable(), s).name;
}

}  // namespace

// Four states in flight are the same stream: nextU32s gives the values of as many nextU32 calls,
// for counts below, at and past a multiple of four, and leaves the stream where they would.
TEST(Sampling, BulkDrawsAreTheStreamsDraws) {
    for (size_t n : {0, 1, 3, 4, 5, 8, 1027}) {
        Pcg32 one(12345, 678), bulk(12345, 678);
        std::vector<uint32_t> expected(n), got(n);
        for (uint32_t& x : expected) x = one.nextU32();
        bulk.nextU32s(got.data(), n);
        EXPECT_EQ(got, expected) << n << " draws";
        EXPECT_EQ(bulk.nextU32(), one.nextU32()) << "after " << n << " draws";
    }
}

TEST(EnvSampler, DensityIntegratesToOne) {
    const EnvMapBasis basis(50, 25);
    for (int guided = 0; guided < 2; ++guided) {
        const std::vector<float> g =
            guided ? randomGuide(basis.texelCount(), 3) : std::vector<float>{};
        const EnvSampler es(basis, g);
        const double total = sphereIntegral([&](const Vec3f& d) { return es.pdf(d); });
        EXPECT_NEAR(total, 1.0, 2e-3) << "guided " << guided;
    }
    // With guide 1 the density is the bilinear chord of sin θ over sin θ: near-uniform.
    const EnvSampler uniform(basis);
    EXPECT_NEAR(uniform.pdf(normalize(Vec3f(0.3f, 0.2f, -0.9f))) * 4 * kPi, 1.0, 0.05);
}

TEST(EnvSampler, SamplesCarryTheirDensityAndEstimateEachTexelsBasisUnbiased) {
    const EnvMapBasis basis(50, 25);
    const std::vector<float> g = randomGuide(basis.texelCount(), 9);
    const EnvSampler es(basis, g);
    // Texels in the interior, next to a pole, on the pole row and across the u wrap.
    const std::vector<uint32_t> texels{12 * 50 + 7, 1 * 50 + 30, 0 * 50 + 3, 8 * 50 + 49,
                                       23 * 50 + 0};
    const int n = 400000;
    std::vector<double> sum(texels.size()), sum2(texels.size());
    Pcg32 rng(42, 7);
    for (int i = 0; i < n; ++i) {
        const EnvSampler::Sample s = es.sample(rng.nextFloat(), rng.nextFloat());
        ASSERT_GT(s.pdf, 0.0f);
        ASSERT_NEAR(std::sqrt(dot(s.direction, s.direction)), 1.0f, 1e-5f);
        if (i < 2000) {
            EXPECT_FLOAT_EQ(s.pdf, es.pdf(s.direction));
        }
        const TexelWeights tw = basis.weights(s.direction);
        for (size_t t = 0; t < texels.size(); ++t) {
            double b = 0;
            for (int k = 0; k < 4; ++k)
                if (tw.index[k] == texels[t]) b += tw.weight[k];
            const double v = b / s.pdf;
            sum[t] += v;
            sum2[t] += v * v;
        }
    }
    for (size_t t = 0; t < texels.size(); ++t) {
        const double exact = sphereIntegral([&](const Vec3f& d) {
            const TexelWeights tw = basis.weights(d);
            double b = 0;
            for (int k = 0; k < 4; ++k)
                if (tw.index[k] == texels[t]) b += tw.weight[k];
            return b;
        });
        const double mean = sum[t] / n, se = std::sqrt((sum2[t] / n - mean * mean) / n);
        std::printf("[ measured ] texel %u: estimate %.6f ± %.6f, quadrature %.6f\n", texels[t],
                    mean, se, exact);
        EXPECT_GT(exact, 0.0);
        EXPECT_NEAR(mean, exact, 4 * se + 1e-3 * exact) << "texel " << texels[t];
    }
}

TEST(EnvSampler, RefusesBadGuides) {
    const EnvMapBasis basis(50, 25);
    EXPECT_THROW(EnvSampler(basis, std::vector<float>(10, 1.0f)), std::invalid_argument);
    std::vector<float> g(1250, 1.0f);
    g[5] = -1.0f;
    EXPECT_THROW(EnvSampler(basis, g), std::invalid_argument);
    EXPECT_THROW(EnvSampler(basis, std::vector<float>(1250, 0.0f)), std::invalid_argument);
}

TEST(Sobol, FirstTwoDimensionsAreANetAndEachDimensionIsStratified) {
    for (int m = 0; m <= 10; ++m) {
        const uint32_t n = 1u << m;
        for (int dim = 0; dim < kSobolDimensions; ++dim) {
            std::set<uint32_t> cells;
            for (uint32_t i = 0; i < n; ++i) cells.insert(m ? sobol(i, dim) >> (32 - m) : 0);
            EXPECT_EQ(cells.size(), n) << "dim " << dim << ", 2^" << m << " points";
        }
        // (0, m, 2)-net: every elementary interval of area 2^-m holds exactly one point.
        for (int a = 0; a <= m; ++a) {
            std::set<std::pair<uint32_t, uint32_t>> cells;
            for (uint32_t i = 0; i < n; ++i) {
                const uint32_t x = a ? sobol(i, 0) >> (32 - a) : 0;
                const uint32_t y = m - a ? sobol(i, 1) >> (32 - (m - a)) : 0;
                cells.insert({x, y});
            }
            EXPECT_EQ(cells.size(), n) << "2^" << m << " points, intervals 2^-" << a;
        }
    }
}

TEST(Sampling, SceneFileNamesTheSamplerAndRefusesOthers) {
    for (const SamplingRow& r : samplingTable()) {
        const SceneDesc d = parseScene(
            std::string(R"({"heightmap": {"path": "part.exr"}, "render": {"sampling": ")") +
                r.name + "\"}}",
            ".", "t");
        EXPECT_EQ(d.render.sampling, r.value);
    }
    EXPECT_THROW(parseScene(R"({"heightmap": {"path": "part.exr"}, "render": {"sampling": "nee"}})",
                            ".", "t"),
                 InputError);
    EXPECT_EQ(renderOptionsFor(*bumpyScene(0.1f, 0.1f, true)).sampling, RenderDesc{}.sampling);
}

TEST(Sampling, FurnaceHoldsForEverySampler) {
    // White env, F == 1: a smooth mirror gives exactly 1 with every sampler (no emitter
    // sampling on a Dirac lobe); a rough one its albedo, the same mean for every sampler.
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.ior = ComplexIor{Rgb{0.0f}, Rgb{1.0f}};
    d.camera.width = d.camera.height = 32;
    const EnvMap white = EnvMap::constant(50, 25, 1.0f);
    for (const SamplingRow& row : samplingTable()) {
        SceneDesc smooth = d;
        smooth.material.params.smooth = true;
        Scene s(smooth, 64, 64, std::vector<float>(64 * 64, 0.0f));
        const RenderResult r = render(s, white, opts(row.value, 4, 2));
        for (size_t p = 0; p < r.image.pixelCount(); ++p) {
            if (r.summary.objectMask[p]) {
                EXPECT_NEAR(r.image.data[3 * p], 1.0f, 1e-6f) << row.name;
            }
        }
        EXPECT_EQ(r.summary.shadowRays, 0u);
    }
    SceneDesc rough = d;
    rough.material.params.alphaU = rough.material.params.alphaV = 0.05f;
    Scene s(rough, 64, 64, std::vector<float>(64 * 64, 0.0f));
    const MeanAndError ref = meanOverSeeds(s, white, Sampling::Bsdf, 8, 6);
    for (Sampling sm : {Sampling::Stratified, Sampling::Mis}) {
        const MeanAndError m = meanOverSeeds(s, white, sm, 8, 6);
        std::printf("[ measured ] furnace alpha 0.05: %s %.5f ± %.5f, bsdf %.5f ± %.5f\n", name(sm),
                    m.mean, m.se, ref.mean, ref.se);
        EXPECT_NEAR(m.mean, ref.mean, 4 * std::hypot(m.se, ref.se) + 1e-6) << name(sm);
        EXPECT_LE(m.mean, 1.0 + 4 * m.se);
        EXPECT_GT(m.mean, 0.95);
    }
    // Stratified keeps each sample's weight F·G1 <= 1, so no pixel exceeds 1.
    const RenderResult st = render(s, white, opts(Sampling::Stratified, 16, 2));
    for (size_t p = 0; p < st.image.pixelCount(); ++p)
        EXPECT_LE(st.image.data[3 * p], 1.0f + 1e-6f);
}

TEST(Sampling, TransportTimesEEqualsRenderForEverySampler) {
    auto s = bumpyScene(0.15f, 0.05f, false);
    Pcg32 rng(5, 3);
    EnvMap env = EnvMap::constant(50, 25, 0.0f);
    for (float& t : env.texels) t = rng.nextFloat();
    std::vector<double> e(env.texels.begin(), env.texels.end());
    for (const SamplingRow& row : samplingTable()) {
        for (int guided = 0; guided < (row.value == Sampling::Mis ? 2 : 1); ++guided) {
            for (int sets : {1, 2}) {
                RenderOptions o = opts(row.value, 8);
                o.sampleSets = sets;
                if (guided) o.guide = env.texels;
                const TransportMatrix t = precomputeTransport(*s, o, 1).matrix;
                std::vector<double> y(t.rows());
                t.applyLuminance(e, y);
                const RenderResult r = render(*s, env, o);
                double scale = 0, diff = 0;
                for (size_t i = 0; i < y.size(); ++i) {
                    const double ref = luminance<double>(
                        r.image.data[3 * i], r.image.data[3 * i + 1], r.image.data[3 * i + 2]);
                    scale = std::max(scale, std::abs(ref));
                    diff = std::max(diff, std::abs(y[i] - ref));
                }
                EXPECT_GT(scale, 0.0);
                EXPECT_LE(diff / scale, 1e-5)
                    << row.name << " guided " << guided << " sets " << sets;
                if (row.value == Sampling::Mis) {
                    EXPECT_GT(r.summary.shadowRays, 0u);
                } else {
                    EXPECT_EQ(r.summary.shadowRays, 0u);
                }
            }
        }
    }
}

TEST(Sampling, EverySamplerHasTheBsdfSamplersMean) {
    // Under the studio light, on a rough anisotropic part and on a mirror-like one (α 0.02):
    // image means over independent seeds agree within their standard errors.
    const EnvMap studio = studioEnvMap(50, 25);
    for (float alpha : {0.15f, 0.02f}) {
        auto s = bumpyScene(alpha, alpha == 0.15f ? 0.05f : alpha, false, 20);
        const MeanAndError ref = meanOverSeeds(*s, studio, Sampling::Bsdf, 16, 6);
        for (Sampling sm : {Sampling::Stratified, Sampling::Mis}) {
            const MeanAndError m = meanOverSeeds(*s, studio, sm, 16, 6);
            std::printf("[ measured ] alpha %.2f: %s %.5f ± %.5f, bsdf %.5f ± %.5f\n", alpha,
                        name(sm), m.mean, m.se, ref.mean, ref.se);
            EXPECT_NEAR(m.mean, ref.mean, 4 * std::hypot(m.se, ref.se)) << name(sm);
        }
    }
}

TEST(Sampling, GuidedMisHasTheSameMean) {
    // A guide changes only the variance: MIS guided by the light itself keeps the mean.
    const EnvMap studio = studioEnvMap(50, 25);
    auto s = bumpyScene(0.3f, 0.3f, false, 20);
    std::vector<double> a, b;
    for (int k = 0; k < 6; ++k) {
        RenderOptions o = opts(Sampling::Mis, 16, 4, 200 + k);
        a.push_back(maskedMean(render(*s, studio, o)));
        o.guide = studio.texels;
        b.push_back(maskedMean(render(*s, studio, o)));
    }
    auto stats = [](const std::vector<double>& v) {
        double m = 0, q = 0;
        for (double x : v) m += x;
        m /= static_cast<double>(v.size());
        for (double x : v) q += (x - m) * (x - m);
        return MeanAndError{
            m, std::sqrt(q / static_cast<double>(v.size() - 1) / static_cast<double>(v.size()))};
    };
    const MeanAndError ma = stats(a), mb = stats(b);
    EXPECT_NEAR(ma.mean, mb.mean, 4 * std::hypot(ma.se, mb.se));
}

TEST(SamplingBench, RelativeErrorIsExactOnKnownImages) {
    std::vector<float> ref{1, 1, 1, 2, 2, 2, 9, 9, 9}, a{1, 1, 1, 3, 3, 3, 0, 0, 0};
    const std::vector<uint8_t> mask{1, 1, 0};
    const RelativeError e = relativeError(a, ref, mask);
    EXPECT_NEAR(e.refMean, 1.5, 1e-12);
    EXPECT_NEAR(e.rmse, std::sqrt(0.5) / 1.5, 1e-12);
    EXPECT_NEAR(e.meanDiff, (4.0 - 3.0) / 3.0, 1e-12);
    EXPECT_EQ(relativeError(ref, ref, mask).rmse, 0.0);
}

TEST(SamplingBench, RunsOnTheBundledSceneAndItsMirrorLikeVariant) {
    SamplingBenchOptions o;
    o.resolution = 16;
    o.spps = {4};
    o.referenceSpp = 32;
    const SamplingBenchResult r = runSamplingBench(o);
    ASSERT_EQ(r.parts.size(), 2u);
    EXPECT_NEAR(r.parts[1].alpha, 0.02, 1e-6);
    EXPECT_EQ(r.rows.size(), 2u * 3u);
    for (const SamplingBenchRow& row : r.rows) {
        EXPECT_GT(row.relRmse, 0.0) << row.part;
        EXPECT_TRUE(std::isfinite(row.relMeanDiff));
        EXPECT_EQ(row.shadowRays > 0, row.sampling == Sampling::Mis);
    }
    EXPECT_NE(r.find("scene", Sampling::Stratified, 4), nullptr);
    o.referenceSpp = 3;
    EXPECT_THROW(runSamplingBench(o), InputError);
}
