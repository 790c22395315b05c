// The transport matrix: T·E == render(E) by construction, the adjoint identity, storage
// equivalence, determinism, and the file's refusal of damaged or stale data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "TestUtil.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Rng.h"
#include "io/TransportFile.h"
#include "objective/TransportLoss.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

using namespace sl;
using test::maxRelDiff;

namespace {

std::unique_ptr<Scene> smallScene(int res = 24) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.alphaU = 0.15f;
    d.material.params.alphaV = 0.05f;
    d.material.params.ior = ComplexIor{Rgb{1.6f, 0.9f, 0.5f}, Rgb{9.0f, 6.3f, 4.8f}};
    d.camera.width = res;
    d.camera.height = res;
    const int n = 48;
    return std::make_unique<Scene>(d, n, n, test::bumpyHeightMap(n));
}

RenderOptions opts(int spp = 8) {
    RenderOptions o;
    o.spp = spp;
    o.maxDepth = 4;
    o.seed = 17;
    return o;
}

std::vector<double> randomVec(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 3);
    std::vector<double> v(n);
    for (double& x : v) x = rng.nextDouble();
    return v;
}

EnvMap asEnvMap(const std::vector<double>& e, int w, int h, int ch) {
    EnvMap m = EnvMap::constant(w, h, 0.0f, ch);
    for (size_t i = 0; i < e.size(); ++i) m.texels[i] = static_cast<float>(e[i]);
    return m;
}

}  // namespace

TEST(Transport, GrayTTimesEEqualsRenderLuminance) {
    auto s = smallScene();
    PrecomputeResult p = precomputeTransport(*s, opts(), 1);
    for (uint64_t seed : {1, 2, 3}) {
        std::vector<double> e = randomVec(s->basis.texelCount(), seed);
        std::vector<double> y(p.matrix.rows());
        p.matrix.applyLuminance(e, y);
        Image img = render(*s, asEnvMap(e, 50, 25, 1), opts()).image;
        std::vector<double> ref(p.matrix.rows());
        for (size_t i = 0; i < ref.size(); ++i)
            ref[i] = luminance<double>(img.data[3 * i], img.data[3 * i + 1], img.data[3 * i + 2]);
        double d = maxRelDiff(y, ref);
        std::printf("[ measured ] gray T·E vs render, max relative difference %.3g\n", d);
        EXPECT_LE(d, 1e-5);
    }
    EXPECT_EQ(p.matrix.objectMask, p.summary.objectMask);
}

TEST(Transport, RgbTTimesEEqualsRenderForGrayAndRgbMaps) {
    auto s = smallScene();
    PrecomputeResult p = precomputeTransport(*s, opts(), 3);
    for (int ch : {1, 3}) {
        std::vector<double> e = randomVec(s->basis.texelCount() * ch, 7 + ch);
        std::vector<double> rgb(3 * p.matrix.rows());
        p.matrix.applyRgb(e, rgb);
        Image img = render(*s, asEnvMap(e, 50, 25, ch), opts()).image;
        std::vector<double> ref(img.data.begin(), img.data.end());
        EXPECT_LE(maxRelDiff(rgb, ref), 1e-5) << ch << " channel(s)";
        // Luminance of the RGB product equals applyLuminance.
        std::vector<double> y(p.matrix.rows());
        p.matrix.applyLuminance(e, y);
        for (size_t i = 0; i < y.size(); ++i)
            EXPECT_NEAR(y[i], luminance<double>(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]),
                        1e-12 + 1e-12 * std::abs(y[i]));
    }
}

TEST(Transport, TransposeIsTheAdjoint) {
    auto s = smallScene();
    for (int channels : {1, 3}) {
        PrecomputeResult p = precomputeTransport(*s, opts(4), channels);
        for (int ech : channels == 3 ? std::vector<int>{1, 3} : std::vector<int>{1}) {
            std::vector<double> e = randomVec(p.matrix.cols() * ech, 5);
            std::vector<double> g = randomVec(p.matrix.rows(), 6);
            for (double& x : g) x -= 0.5;
            std::vector<double> y(p.matrix.rows()), tg(e.size());
            p.matrix.applyLuminance(e, y);
            p.matrix.applyTransposeLuminance(g, tg);
            double lhs = 0, rhs = 0;
            for (size_t i = 0; i < y.size(); ++i) lhs += y[i] * g[i];
            for (size_t i = 0; i < e.size(); ++i) rhs += e[i] * tg[i];
            EXPECT_NEAR(lhs, rhs, 1e-12 * std::abs(lhs)) << channels << "/" << ech;
        }
    }
}

TEST(Transport, DenseAndSparseAgreeAndProductsIgnoreThreadCount) {
    auto s = smallScene();
    PrecomputeResult p = precomputeTransport(*s, opts(4), 1);
    TransportMatrix sparse = p.matrix;
    sparse.toSparse();
    TransportMatrix dense = sparse;
    dense.toDense();
    EXPECT_EQ(dense.storage, TransportStorage::Dense);
    EXPECT_NEAR(dense.density(), sparse.density(), 1e-12);
    std::vector<double> e = randomVec(sparse.cols(), 9), g = randomVec(sparse.rows(), 10);
    std::vector<double> y1(sparse.rows()), y2(sparse.rows()), t1(sparse.cols()), t2(sparse.cols());
    sparse.applyLuminance(e, y1);
    dense.applyLuminance(e, y2);
    EXPECT_LE(maxRelDiff(y1, y2), 1e-14);
    sparse.applyTransposeLuminance(g, t1);
    dense.applyTransposeLuminance(g, t2);
    EXPECT_LE(maxRelDiff(t1, t2), 1e-13);
    // Round trip dense -> sparse restores the same arrays.
    TransportMatrix back = dense;
    back.toSparse();
    EXPECT_EQ(back.colIdx, sparse.colIdx);
    EXPECT_EQ(back.values, sparse.values);
    // The transpose product is bit-identical for 1 and 2 threads.
    sparse.threads = 1;
    sparse.applyTransposeLuminance(g, t1);
    sparse.threads = 2;
    sparse.applyTransposeLuminance(g, t2);
    EXPECT_EQ(0, std::memcmp(t1.data(), t2.data(), t1.size() * sizeof(double)));
}

TEST(Transport, PrecomputeIsBitIdenticalForAnyThreadCount) {
    auto s = smallScene();
    RenderOptions a = opts(4), b = opts(4);
    a.threads = 1;
    b.threads = 2;
    TransportMatrix ta = precomputeTransport(*s, a, 1).matrix;
    TransportMatrix tb = precomputeTransport(*s, b, 1).matrix;
    EXPECT_EQ(ta.rowPtr, tb.rowPtr);
    EXPECT_EQ(ta.colIdx, tb.colIdx);
    EXPECT_EQ(ta.values, tb.values);
}

TEST(Transport, RowsHoldEachTexelOnceInColumnOrderAndHalvesAverageToT) {
    // The sink sums a texel's paths in a per-thread dense accumulator: every row lists each
    // texel once, ascending, for gray and RGB T, one plane and halves; and the halves' mean
    // renders as T does (the same paths, split by sample set).
    auto s = smallScene();
    for (int channels : {1, 3})
        for (int sets : {1, 2}) {
            RenderOptions o = opts(4);
            o.sampleSets = sets;
            const TransportMatrix t = precomputeTransport(*s, o, channels).matrix;
            ASSERT_EQ(t.storage, TransportStorage::Sparse);
            for (size_t r = 0; r < t.rows(); ++r)
                for (uint64_t k = t.rowPtr[r] + 1; k < t.rowPtr[r + 1]; ++k)
                    ASSERT_LT(t.colIdx[k - 1], t.colIdx[k]) << "row " << r;
            if (sets == 1) continue;
            const std::vector<double> e = randomVec(t.cols(), 5);
            std::vector<double> y(t.rows());
            t.applyLuminance(e, y);
            Image img = render(*s, asEnvMap(e, 50, 25, 1), o).image;
            std::vector<double> ref(t.rows());
            for (size_t i = 0; i < ref.size(); ++i)
                ref[i] =
                    luminance<double>(img.data[3 * i], img.data[3 * i + 1], img.data[3 * i + 2]);
            EXPECT_LE(maxRelDiff(y, ref), 1e-5) << channels;
        }
}

TEST(TransportFile, RoundTripsAndRefusesDamagedOrStaleFiles) {
    test::TempDir dir("tm");
    auto s = smallScene();
    RenderOptions o = opts(4);
    PrecomputeResult p = precomputeTransport(*s, o, 3);
    TransportProvenance prov = transportProvenance(*s, o, 3);
    const auto file = dir / "part.tm";
    writeTransportFile(file, p.matrix, prov);
    TransportFile f = readTransportFile(file, prov.fingerprint);
    EXPECT_EQ(f.matrix.rowPtr, p.matrix.rowPtr);
    EXPECT_EQ(f.matrix.colIdx, p.matrix.colIdx);
    EXPECT_EQ(f.matrix.values, p.matrix.values);
    EXPECT_EQ(f.matrix.objectMask, p.matrix.objectMask);
    EXPECT_EQ(f.matrix.channels, 3);
    EXPECT_EQ(f.provenance.fingerprint, prov.fingerprint);

    // Another seed, spp or material is another fingerprint: refused as stale.
    RenderOptions o2 = o;
    o2.seed = 18;
    auto stale = transportProvenance(*s, o2, 3);
    EXPECT_NE(stale.fingerprint, prov.fingerprint);
    try {
        readTransportFile(file, stale.fingerprint);
        FAIL() << "stale file accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("stale"), std::string::npos) << e.what();
    }
    EXPECT_NE(transportProvenance(*s, o, 1).fingerprint, prov.fingerprint);

    // Flip one byte anywhere in the payload or header: refused as damaged.
    std::string bytes;
    {
        std::ifstream in(file, std::ios::binary);
        bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    for (size_t pos : {size_t(20), bytes.size() / 2, bytes.size() - 3}) {
        std::string bad = bytes;
        bad[pos] = static_cast<char>(bad[pos] ^ 0x5a);
        test::writeText(dir / "bad.tm", bad);
        try {
            readTransportFile(dir / "bad.tm");
            FAIL() << "damaged file accepted (byte " << pos << ")";
        } catch (const InputError& e) {
            std::string m = e.what();
            EXPECT_TRUE(m.find("damaged") != std::string::npos ||
                        m.find("not a scratchlight") != std::string::npos)
                << m;
            EXPECT_NE(m.find("bad.tm"), std::string::npos);
        }
    }
    // Truncated, wrong magic, empty.
    test::writeText(dir / "short.tm", bytes.substr(0, bytes.size() - 10));
    EXPECT_THROW(readTransportFile(dir / "short.tm"), InputError);
    test::writeText(dir / "junk.tm", "hello");
    EXPECT_THROW(readTransportFile(dir / "junk.tm"), InputError);
    EXPECT_THROW(readTransportFile(dir / "absent.tm"), InputError);
}

TEST(TransportLoss, GradientMatchesCentralDifferences) {
    auto s = smallScene(20);
    PrecomputeResult p = precomputeTransport(*s, opts(8), 3);
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool rgb : {false, true}) {
            ObjectiveOptions oo;
            oo.reg = reg;
            oo.lambda = 3.0;
            ImageObjective obj(p.matrix.width, p.matrix.height, p.matrix.objectMask, oo);
            TransportLoss loss(p.matrix, obj, rgb);
            std::vector<double> e = randomVec(loss.dimension(), 21), g(loss.dimension());
            for (double& x : e) x = 0.2 + 0.6 * x;
            loss.evaluate(e, g);
            double maxErr = 0, maxG = 0;
            for (size_t i = 0; i < e.size(); i += 7) {
                const double h = 1e-6;
                std::vector<double> a = e, b = e;
                a[i] += h;
                b[i] -= h;
                double fd = (loss.evaluate(a, {}).total - loss.evaluate(b, {}).total) / (2 * h);
                maxErr = std::max(maxErr, std::abs(fd - g[i]));
                maxG = std::max(maxG, std::abs(g[i]));
            }
            EXPECT_LE(maxErr, 1e-6 * maxG) << "reg " << int(reg) << " rgb " << rgb;
        }
    }
}

TEST(TransportLoss, FusedPassEqualsTwoPassesForAnyThreadCount) {
    auto s = smallScene(37);  // odd size: chunks and bands do not divide it
    PrecomputeResult p = precomputeTransport(*s, opts(4), 3);
    for (RegTarget reg : {RegTarget::EnvMap, RegTarget::Image}) {
        for (bool smooth : {false, true}) {
            for (bool rgb : {false, true}) {
                ObjectiveOptions oo;
                oo.reg = reg;
                oo.smoothAbs = smooth;
                oo.smoothEps = 1e-3;
                ImageObjective obj(p.matrix.width, p.matrix.height, p.matrix.objectMask, oo);
                TransportMatrix t = p.matrix;
                TransportLoss loss(t, obj, rgb);
                std::vector<double> e = randomVec(loss.dimension(), 4);
                std::vector<double> g1(e.size()), g2(e.size()), g3(e.size());
                LossParts a = loss.evaluate(e, g1);
                t.threads = 1;
                LossParts b = loss.evaluateFused(e, g2);
                t.threads = 2;
                loss.evaluateFused(e, g3);
                EXPECT_NEAR(a.total, b.total, 1e-12 * std::abs(a.total));
                EXPECT_NEAR(a.G, b.G, 1e-12 * a.G);
                EXPECT_LE(maxRelDiff(g2, g1), 1e-11)
                    << "reg " << int(reg) << " smooth " << smooth << " rgb " << rgb;
                EXPECT_EQ(0, std::memcmp(g2.data(), g3.data(), g2.size() * sizeof(double)));
            }
        }
    }
}

TEST(TransportFile, FingerprintCoversTheTracerRevision) {
    auto s = smallScene();
    TransportProvenance p = transportProvenance(*s, opts(4), 1);
    EXPECT_NE(p.inputs.find("\"tracer_revision\":" + std::to_string(kTracerRevision)),
              std::string::npos)
        << p.inputs;
}
