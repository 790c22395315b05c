// EnvMap → E (scene/EnvMapToE.h): the one rule every caller that renders, scores or fits a light
// uses, checked against what each former copy computed: a gray map as it is (and on all three
// channels of an RGB T, as optimize's lamp did), a colour map on a gray T by its luminance in
// double (the judge's and optimize's lamp; the viewer's copy rounded it through float), and the
// same Y a file loaded as one channel stores (io/EnvMapIO.h loadEnvMap). A start keeps the
// paper's L*/100 for colour photos (app/pipeline/InitialState.h).
#include <gtest/gtest.h>

#include <algorithm>

#include "TestUtil.h"
#include "app/pipeline/InitialState.h"
#include "core/Color.h"
#include "io/EnvMapIO.h"
#include "scene/EnvMapToE.h"

namespace sl {
namespace {

EnvMap colourMap() {
    EnvMap m = EnvMap::constant(4, 3, 0.0f, 3);
    for (size_t i = 0; i < m.texels.size(); ++i)
        m.texels[i] = 0.05f + 0.37f * static_cast<float>((i * 7) % 11);  // some above 1
    return m;
}

TEST(EnvMapToE, AGrayMapIsEOnAGrayTAndDrivesRGBAlikeOnAnRgbT) {
    EnvMap g = EnvMap::constant(4, 3, 0.0f, 1);
    for (size_t i = 0; i < g.texels.size(); ++i) g.texels[i] = 0.1f * static_cast<float>(i);
    const std::vector<double> e1 = envMapToE(g, 1), e3 = envMapToE(g, 3);
    ASSERT_EQ(e1.size(), 12u);
    ASSERT_EQ(e3.size(), 36u);
    for (size_t t = 0; t < 12; ++t) {
        EXPECT_EQ(e1[t], double(g.texels[t]));
        for (int c = 0; c < 3; ++c) EXPECT_EQ(e3[3 * t + c], double(g.texels[t]));
    }
}

TEST(EnvMapToE, AColourMapIsItsLuminanceOnAGrayTAndItselfOnAnRgbT) {
    const EnvMap m = colourMap();
    const std::vector<double> e1 = envMapToE(m, 1), e3 = envMapToE(m, 3);
    for (size_t t = 0; t < m.texelCount(); ++t) {
        const float* c = &m.texels[3 * t];
        EXPECT_EQ(e1[t], luminance(double(c[0]), double(c[1]), double(c[2])));  // not clamped
        for (int k = 0; k < 3; ++k) EXPECT_EQ(e3[3 * t + k], double(c[k]));
    }
    EXPECT_GT(*std::max_element(e1.begin(), e1.end()), 1.0);
    EXPECT_THROW(envMapToE(m, 2), std::invalid_argument);
}

TEST(EnvMapToE, IsTheLuminanceAFileLoadedAsOneChannelStores) {
    test::TempDir dir("envmap-to-e");
    const EnvMap m = colourMap();
    writeEnvMap(dir / "c.exr", m);
    const EnvMap asStored = loadEnvMap(dir / "c.exr", 4, 3, 0),
                 gray = loadEnvMap(dir / "c.exr", 4, 3, 1);
    ASSERT_EQ(asStored.channels, 3);
    const std::vector<double> e = envMapToE(asStored, 1);
    for (size_t t = 0; t < e.size(); ++t) EXPECT_EQ(static_cast<float>(e[t]), gray.texels[t]) << t;
}

TEST(EnvMapToE, AStartIsTheLightClampedButAColourPhotoTurnsGrayByLStar) {
    const EnvMap m = colourMap();
    const std::vector<double> gray = initialEnvMapFrom(m, false), rgb = initialEnvMapFrom(m, true);
    const std::vector<double> light = envMapToE(m, 3);
    for (size_t t = 0; t < m.texelCount(); ++t) {
        const float* c = &m.texels[3 * t];
        EXPECT_EQ(gray[t], std::clamp(lightnessLStar01(c[0], c[1], c[2]), 0.0, 1.0));
        for (int k = 0; k < 3; ++k)
            EXPECT_EQ(rgb[3 * t + k], std::clamp(light[3 * t + k], 0.0, 1.0));
    }
    EnvMap g = EnvMap::constant(4, 3, 1.5f, 1);
    for (double v : initialEnvMapFrom(g, true)) EXPECT_EQ(v, 1.0);
}

}  // namespace
}  // namespace sl
