// perception/: Barten's contrast sensitivity against its published values, Legge & Foley's
// masking slope, the viewing model's geometry, and the orderings JND must keep.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "perception/ContrastMasking.h"
#include "perception/ContrastSensitivity.h"
#include "perception/JndVisibility.h"
#include "perception/ViewingModel.h"

using namespace sl;

namespace {

/// Barten's reference condition: pupil 2.1 mm, 20 cd/m², a 60° × 60° field.
BartenCondition referenceCondition() {
    BartenCondition c;
    c.sigmaDeg = std::hypot(0.5 / 60, 0.08 / 60 * 2.1);
    c.illuminance = bartenRetinalIlluminance(20, 2.1);
    c.x0Deg = c.y0Deg = 60;
    return c;
}

}  // namespace

TEST(ContrastSensitivity, BartenModelReproducesItsReferenceValues) {
    // The model's functions at the values published with an independent implementation of
    // Barten (1999) (colour-science, colour.contrast.barten1999's documented examples).
    EXPECT_NEAR(bartenPupilDiameter(100, 60, 60), 2.7931307, 1e-6);
    EXPECT_NEAR(bartenRetinalIlluminance(100, 2.1), 330.4115803, 1e-6);
    EXPECT_NEAR(bartenSensitivity(4, referenceCondition()), 360.8691122, 1e-6);
}

TEST(ContrastSensitivity, MinimumDetectableContrastFollowsItuBt2246Figure31) {
    // ITU-R Report BT.2246-4 (2015), Figure 31: the minimum detectable contrast of Barten's
    // model for UHDTV, MDC = 2/(1.27·S) at the peak frequency, a 60° field, pupil by Barten's
    // formula, 10 luminances from 0.01 to 100 cd/m² (values as the figure is reproduced by
    // colour-science). The figure's accuracy: 0.5 %.
    const double mdc[10] = {0.0218764, 0.0141848, 0.0095244, 0.0066805, 0.0049246,
                            0.0038228, 0.0031188, 0.0026627, 0.0023674, 0.0021814};
    for (int i = 0; i < 10; ++i) {
        const double L = std::pow(10.0, -2.0 + 4.0 * i / 9.0);
        const SensitivityPeak peak = bartenPeak(bartenCondition(L, 60, 60));
        const double got = 2.0 / (1.27 * peak.sensitivity);
        EXPECT_NEAR(got / mdc[i], 1.0, 0.005) << "L = " << L << " cd/m²";
        // The CSF peaks between 1 and 10 c/deg in daylight, lower in the dark.
        EXPECT_GT(peak.frequency, L >= 1 ? 1.0 : 0.2);
        EXPECT_LT(peak.frequency, 10.0);
    }
}

TEST(ContrastSensitivity, OrderingsOfTheModel) {
    // More light: more sensitive, approaching Weber's law (the gain per decade shrinks).
    const double s1 = bartenPeak(bartenCondition(1, 10, 10)).sensitivity;
    const double s10 = bartenPeak(bartenCondition(10, 10, 10)).sensitivity;
    const double s100 = bartenPeak(bartenCondition(100, 10, 10)).sensitivity;
    const double s1000 = bartenPeak(bartenCondition(1000, 10, 10)).sensitivity;
    EXPECT_LT(s1, s10);
    EXPECT_LT(s10, s100);
    EXPECT_LT(s100, s1000);
    EXPECT_LT(s1000 / s100, s10 / s1);
    // A smaller field: less sensitive (less spatial integration).
    EXPECT_LT(bartenSensitivity(4, 100, 0.5, 0.5), bartenSensitivity(4, 100, 10, 10));
    // Band-pass: below and above the peak the sensitivity falls; nothing at u = 0 or L = 0.
    const BartenCondition c = bartenCondition(100, 10, 10);
    const SensitivityPeak p = bartenPeak(c);
    EXPECT_LT(bartenSensitivity(p.frequency / 8, c), p.sensitivity);
    EXPECT_LT(bartenSensitivity(p.frequency * 8, c), p.sensitivity / 10);
    EXPECT_EQ(bartenSensitivity(0, c), 0.0);
    EXPECT_EQ(bartenSensitivity(4, 0, 10, 10), 0.0);
}

TEST(ContrastMasking, LeggeFoleySlopeAboveThresholdAndNoneBelow) {
    EXPECT_EQ(thresholdElevation(0), 1.0);
    EXPECT_NEAR(thresholdElevation(1e-3), 1.0, 1e-6);
    // log-log slope 0.6 for maskers far above their threshold (Legge & Foley 1980).
    for (double m : {1e2, 1e3}) {
        const double slope =
            std::log(thresholdElevation(1.01 * m) / thresholdElevation(m)) / std::log(1.01);
        EXPECT_NEAR(slope, kMaskingExponent, 1e-3) << m;
    }
    for (double m = 0.01; m < 100; m *= 1.5)
        EXPECT_GT(thresholdElevation(1.5 * m), thresholdElevation(m));
}

TEST(ViewingModel, PixelsPerDegreeFromTheGeometry) {
    // 0.27 mm at 600 mm: 2·atan(0.135/600) = 0.025783° per pixel.
    const ViewingModel v = defaultViewing();
    EXPECT_NEAR(v.pixelsPerDegree, 1.0 / (2 * std::atan(0.135 / 600) * 180 / std::numbers::pi),
                1e-9);
    EXPECT_NEAR(v.pixelsPerDegree, 38.785, 0.01);
    EXPECT_EQ(v.whiteLuminance, kDisplayWhiteCdM2);
    // The part through a 4× loupe at 250 mm, 0.01 mm per pixel: as a 0.04 mm pixel at 250 mm.
    const ViewingModel p = ViewingModel::part(250, 4, 0.01, 300);
    EXPECT_NEAR(p.pixelsPerDegree, ViewingModel::display(250, 0.04, 300).pixelsPerDegree, 1e-9);
    EXPECT_THROW(ViewingModel::display(0, 0.27, 200), std::invalid_argument);
    EXPECT_THROW(ViewingModel::display(600, 0.27, -1), std::invalid_argument);
}

namespace {

constexpr int kSide = 192;

struct Picture {
    std::vector<double> y = std::vector<double>(kSide * kSide, 0.5);
    std::vector<uint8_t> part = std::vector<uint8_t>(kSide * kSide, 1);
};

/// A scratch-like defect: a bright and a dark flank, 3 px each, 24 px long, at the centre.
std::vector<uint8_t> addScratch(Picture& pic, double contrast) {
    std::vector<uint8_t> region(pic.y.size(), 0);
    for (int yy = kSide / 2 - 12; yy < kSide / 2 + 12; ++yy)
        for (int xx = kSide / 2 - 3; xx < kSide / 2 + 3; ++xx) {
            const size_t p = static_cast<size_t>(yy) * kSide + xx;
            pic.y[p] *= 1.0 + (xx < kSide / 2 ? contrast : -contrast);
            region[p] = 1;
        }
    return region;
}

/// Pixels farther than 40 px (Chebyshev) from the centre: the defect-free surface.
std::vector<uint8_t> farFromCentre() {
    std::vector<uint8_t> clean(kSide * kSide, 0);
    for (int yy = 0; yy < kSide; ++yy)
        for (int xx = 0; xx < kSide; ++xx)
            clean[static_cast<size_t>(yy) * kSide + xx] =
                std::max(std::abs(xx - kSide / 2), std::abs(yy - kSide / 2)) > 40;
    return clean;
}

double jndOf(const Picture& a, const Picture& b, const std::vector<uint8_t>& region,
             const std::vector<uint8_t>& clean) {
    const BandContrast bands(kSide, kSide, a.y, b.y, a.part, 1.0, defaultViewing());
    return bands.score(region, clean).jnd;
}

/// A horizontal grating of RMS contrast c·0.5/√2... multiplied into the picture: y *= 1 + c·sin.
void addGrating(Picture& pic, double c, double periodPx) {
    for (int yy = 0; yy < kSide; ++yy)
        for (int xx = 0; xx < kSide; ++xx)
            pic.y[static_cast<size_t>(yy) * kSide + xx] *=
                1.0 + c * std::sin(2 * std::numbers::pi * yy / periodPx);
}

/// Vertical stripes y *= 1 + c·sin over the central 48×48 pixels; returns that patch.
std::vector<uint8_t> addStripes(Picture& pic, double c, double periodPx) {
    std::vector<uint8_t> region(pic.y.size(), 0);
    for (int yy = kSide / 2 - 24; yy < kSide / 2 + 24; ++yy)
        for (int xx = kSide / 2 - 24; xx < kSide / 2 + 24; ++xx) {
            const size_t p = static_cast<size_t>(yy) * kSide + xx;
            pic.y[p] *= 1.0 + c * std::sin(2 * std::numbers::pi * xx / periodPx);
            region[p] = 1;
        }
    return region;
}

}  // namespace

TEST(JndVisibility, NothingToSeeIsZeroJnd) {
    Picture flat;
    std::vector<uint8_t> region(flat.y.size(), 0);
    for (int i = 0; i < 100; ++i) region[static_cast<size_t>(kSide / 2) * kSide + i] = 1;
    EXPECT_EQ(jndOf(flat, flat, region, farFromCentre()), 0.0);
    // A pattern under a light that shows nothing (a black image) is not seen either.
    Picture dark;
    const std::vector<uint8_t> r = addScratch(dark, 0.5);
    for (double& v : dark.y) v = 0;
    EXPECT_EQ(jndOf(dark, dark, r, farFromCentre()), 0.0);
}

TEST(JndVisibility, DoublingContrastOnAFlatBackgroundDoublesJnd) {
    Picture a, b;
    const std::vector<uint8_t> region = addScratch(a, 0.002);
    addScratch(b, 0.004);
    const std::vector<uint8_t> clean = farFromCentre();
    const double j1 = jndOf(a, a, region, clean), j2 = jndOf(b, b, region, clean);
    EXPECT_GT(j1, 0.0);
    EXPECT_NEAR(j2 / j1, 2.0, 0.01);
}

TEST(JndVisibility, ATextureAsStrongAsTheDefectMasksIt) {
    // The same scratch (20 %) on a flat surface and on a grating as strong as it (period 8 px:
    // the scratch's band).
    Picture flat, textured;
    const std::vector<uint8_t> region = addScratch(flat, 0.2);
    addGrating(textured, 0.2, 8);
    addScratch(textured, 0.2);
    const std::vector<uint8_t> clean = farFromCentre();
    const double jFlat = jndOf(flat, flat, region, clean);
    const double jTextured = jndOf(textured, textured, region, clean);
    EXPECT_GT(jTextured, 0.0);
    EXPECT_LT(jTextured, 0.5 * jFlat);
    // Ten times the texture's contrast raises the threshold of a pattern in the same band by
    // up to 10^0.6 (Legge & Foley's slope, reached in bands where the texture is far above its
    // own threshold) and by more than 10^0.3 over the pattern's bands: a patch of vertical
    // stripes on horizontal ones, both of period 8 px.
    Picture weak, strong;
    addGrating(weak, 0.05, 8);
    addGrating(strong, 0.5, 8);
    std::vector<uint8_t> patch;
    for (Picture* p : {&weak, &strong}) patch = addStripes(*p, 0.05, 8);
    const double ratio = jndOf(weak, weak, patch, clean) / jndOf(strong, strong, patch, clean);
    EXPECT_GT(ratio, std::pow(10.0, kMaskingExponent / 2));
    EXPECT_LT(ratio, 1.1 * std::pow(10.0, kMaskingExponent));
}

TEST(JndVisibility, TwoIndependentEstimatesCancelTheNoise) {
    // Rendering noise of 2 % per pixel: the two-estimate JND stays near the noise-free one,
    // the same estimate used twice sees the noise as contrast.
    Picture clean;
    const std::vector<uint8_t> region = addScratch(clean, 0.05);
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.01);
    Picture a = clean, b = clean;
    for (size_t p = 0; p < a.y.size(); ++p) a.y[p] += noise(rng), b.y[p] += noise(rng);
    const std::vector<uint8_t> far = farFromCentre();
    auto scoreOf = [&](const Picture& x, const Picture& y) {
        return BandContrast(kSide, kSide, x.y, y.y, x.part, 1.0, defaultViewing())
            .score(region, far);
    };
    const JndScore truth = scoreOf(clean, clean), unbiased = scoreOf(a, b), biased = scoreOf(a, a);
    EXPECT_NEAR(unbiased.jnd / truth.jnd, 1.0, 0.1);
    // The texture's contrast (here none) is not inflated by the noise with two estimates; with
    // one, the noise is taken for a texture that masks the scratch.
    EXPECT_LT(unbiased.maskContrast, 0.2 * biased.maskContrast);
    EXPECT_LT(biased.jnd, unbiased.jnd);
}

TEST(JndVisibility, BandFrequencyIsTheDifferenceOfGaussiansPeak) {
    // The DoG of σ and 2σ peaks at f = sqrt(ln 4 / 6)/(πσ) cycles/pixel: check on its
    // spectrum exp(−2π²σ²f²) − exp(−8π²σ²f²) numerically for band 2 (σ = 2 px).
    const double sigma = 2.0, pi = std::numbers::pi;
    auto dog = [&](double f) {
        return std::exp(-2 * pi * pi * sigma * sigma * f * f) -
               std::exp(-8 * pi * pi * sigma * sigma * f * f);
    };
    double best = 0, bestF = 0;
    for (double f = 0.001; f < 0.5; f += 1e-5)
        if (dog(f) > best) best = dog(f), bestF = f;
    const Picture pic;
    const BandContrast bands(kSide, kSide, pic.y, pic.y, pic.part, 1.0, defaultViewing());
    EXPECT_NEAR(bands.bandFrequency(2) / defaultViewing().pixelsPerDegree, bestF, 2e-5);
}
