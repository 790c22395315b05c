// Answers that hold: the noise-aware training rule (app/pipeline/TrainingNoise.h), the self-checked
// answer (app/pipeline/Answer.h) and what optimize's summary says its losses are.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "TestUtil.h"
#include "app/pipeline/Answer.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/Search.h"
#include "app/pipeline/TrainingNoise.h"
#include "core/Rng.h"
#include "objective/DefectVisibility.h"
#include "scene/Scene.h"

using namespace sl;
using json = nlohmann::json;

namespace {

std::vector<double> randomLight(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 7);
    std::vector<double> v(n);
    for (double& x : v) x = 0.2 + 0.6 * rng.nextDouble();
    return v;
}

std::vector<double> scaled(std::vector<double> e, double c) {
    for (double& x : e) x *= c;
    return e;
}

json readJson(const std::filesystem::path& p) {
    return json::parse(test::readFile(p));
}

/// A small bumpy part with one labelled scratch (a 3×12 stripe) and a 32-spp judge of it: the
/// validation estimate the Answer tests score lights on. `judge` has no viewing model (the
/// ratio); `jndJudge` is the same estimate seen on the default display (JND); `plainJudge`
/// knows no regions (U).
struct ScratchedPartJudge {
    std::unique_ptr<Scene> scene;
    TransportSource estimate;
    std::unique_ptr<Judge> judge, jndJudge, plainJudge;
    static std::unique_ptr<ScratchedPartJudge> make() {
        auto r = std::make_unique<ScratchedPartJudge>();
        r->scene =
            std::make_unique<Scene>(test::bumpyPartDesc(32, 32), 40, 40, test::bumpyHeightMap(40));
        JudgeOptions jo;
        jo.spp = 32;
        std::vector<uint8_t> labels(32 * 32, 0);
        for (int y = 10; y < 22; ++y)
            for (int x = 14; x < 17; ++x) labels[size_t(y) * 32 + x] = 1;
        r->estimate = judgeEstimate(*r->scene, jo);
        r->judge = std::make_unique<Judge>(r->estimate, jo, labels,
                                           std::vector{RegionLabel{1, "scratch"}});
        r->plainJudge = std::make_unique<Judge>(r->estimate, jo);
        jo.viewing = defaultViewing();
        r->jndJudge = std::make_unique<Judge>(r->estimate, jo, labels,
                                              std::vector{RegionLabel{1, "scratch"}});
        return r;
    }
};

}  // namespace

// The gap is how much better E* looks on its training estimate than on the validation one,
// relative to the validation figure, in the direction of each objective's figure.
TEST(TrainingNoise, GapFollowsEachObjectivesDirection) {
    // Losses (lower is better): training 20.3, validation 32.7 -> (32.7 - 20.3) / 32.7.
    EXPECT_NEAR(trainingGap(ObjectiveKind::Unbiased, 20.3, 32.7), 12.4 / 32.7, 1e-15);
    EXPECT_NEAR(trainingGap(ObjectiveKind::Paper, 10, 9), -1.0 / 9, 1e-15);
    // Visibility (higher is better): training 3, validation 2 -> 0.5.
    EXPECT_DOUBLE_EQ(trainingGap(ObjectiveKind::Defects, 3, 2), 0.5);
    EXPECT_LT(trainingGap(ObjectiveKind::Defects, 2, 3), 0);
    EXPECT_EQ(trainingGap(ObjectiveKind::Defects, 1, 0), std::numeric_limits<double>::infinity());
    // The defects figure is exp(−L_vis/2): sqrt(g(D)/g(R)) above the objective's floors.
    LossParts p;
    p.lGrad = -2 * std::log(1.5);  // g(D)/g(R) = 9/4
    EXPECT_NEAR(trainingFigure(ObjectiveKind::Defects, p), 1.5, 1e-15);
    p.total = 7;
    EXPECT_DOUBLE_EQ(trainingFigure(ObjectiveKind::Unbiased, p), 7.0);
}

// The next spp: at least twice the last, the smallest power-of-two multiple whose predicted gap
// (∝ 1/spp) is within half the tolerance, at most 4× the last and never above the cap; none at
// the cap.
TEST(TrainingNoise, NextSppAimsAtHalfTheToleranceUnderTheCap) {
    TrainingNoiseOptions o;
    o.maxGap = 0.05;
    o.maxSpp = 1024;
    EXPECT_EQ(nextTrainingSpp(16, 0.06, o), 64);    // 16·0.06/0.025 = 38.4 -> 64
    EXPECT_EQ(nextTrainingSpp(16, 0.051, o), 64);   // 32.6 -> 64
    EXPECT_EQ(nextTrainingSpp(16, 0.04, o), 32);    // 25.6 -> 32 (and at least 2·16)
    EXPECT_EQ(nextTrainingSpp(16, 0.4, o), 128);    // 256 wanted, at most 8× a round
    EXPECT_EQ(nextTrainingSpp(64, 0.1, o), 256);    // 256 exactly
    EXPECT_EQ(nextTrainingSpp(512, 0.2, o), 1024);  // capped
    EXPECT_EQ(nextTrainingSpp(1024, 0.2, o), std::nullopt);
    EXPECT_EQ(nextTrainingSpp(16, std::numeric_limits<double>::infinity(), o), 128);
    EXPECT_EQ(nextTrainingSpp(64, 2.5, o), 512);  // 6 400 wanted: 8× a round
    EXPECT_EQ(kMaxSppGrowth, 8);
}

// On any estimate G_u(cE) = c²·G_u(E) (the image is linear in E), so with λ = 0
// U(cE) = U(E)/c exactly: the brighter copy of the lamp wins, the dimmer loses to the lamp.
// The defect pixels' multiplier: the most (kDefectSppScale) while the extra samples stay
// within kDefectSppBudget of the part's, halving otherwise; 1 when nothing is affordable.
// Step 5's grids: √2 fewer nodes per side a step, from the env map's own, down to
// kCoarsestLightNodes.
TEST(TrainingNoise, CoarserLightsStepBySqrtTwoDownToTheCoarsest) {
    std::vector<std::string> ladder;
    for (auto g = nextLightGrid(LightGrid{}, 50, 25); g; g = nextLightGrid(*g, 50, 25))
        ladder.push_back(g->name());
    const std::vector<std::string> expected{"35x18 nodes", "25x13 nodes", "18x9 nodes",
                                            "13x6 nodes", "9x4 nodes"};
    EXPECT_EQ(ladder, expected);  // 6x3 = 18 nodes would be below 32
    EXPECT_FALSE(nextLightGrid(LightGrid{9, 4}, 50, 25));
    // The height never goes below 2 nodes (the poles), the width below 1.
    EXPECT_EQ(nextLightGrid(LightGrid{}, 200, 2)->name(), "141x2 nodes");
}

// A given grid (or the gap met) ends the rule; describe says which grid E* was searched on.
TEST(TrainingNoise, TheDescriptionNamesTheGridOfEachRound) {
    TrainingNoiseSummary s;
    s.adapted = true;
    s.maxGap = 0.05;
    auto round = [](int spp, LightGrid grid, double training, double gap, double se,
                    int validationSpp = 0) {
        TrainingNoiseRound r;
        r.spp = spp;
        r.grid = grid;
        r.training = training;
        r.validation = 1.0;
        r.gap = gap;
        r.gapError = se;
        r.validationSpp = validationSpp == 0 ? spp : validationSpp;
        return r;
    };
    s.rounds = {round(64, LightGrid{}, 3.0, 2.0, 0.1), round(512, LightGrid{}, 2.0, 1.0, 0.1),
                round(512, LightGrid{25, 13}, 1.04, 0.04, 0.02)};
    s.met = true;
    std::string d = describeTrainingNoise(s);
    EXPECT_NE(d.find("512 spp, 25x13 nodes: train/validation gap 4 % ± 2 %"), std::string::npos)
        << d;
    EXPECT_NE(d.find("-> 512 spp on 25x13 nodes (within 5 %)"), std::string::npos) << d;
    // V traced at more spp than T is named; a gap V cannot resolve at its most spp is said so.
    s.rounds.push_back(round(512, LightGrid{25, 13}, 1.2, 0.2, 0.3, 1024));
    s.met = false;
    s.unresolved = true;
    d = describeTrainingNoise(s);
    EXPECT_NE(d.find("512 spp, 25x13 nodes, V 1024 spp: train/validation gap 20 % ± 30 %"),
              std::string::npos)
        << d;
    EXPECT_NE(d.find("V at 1024 spp cannot resolve 5 %"), std::string::npos) << d;
    EXPECT_EQ(d.find("no light is trusted"), std::string::npos) << d;
    // A gap above the tolerance by less than V's noise, at the rule's limits, says ABOVE.
    s.rounds.back() = round(512, LightGrid{9, 4}, 1.07, 0.07, 0.02, 1024);
    s.rounds.back().verdict = GapVerdict::Above;
    d = describeTrainingNoise(s);
    EXPECT_NE(d.find("-> 512 spp on 9x4 nodes: ABOVE 5 % by less than V at 1024 spp's noise"),
              std::string::npos)
        << d;
}

// Step 3's verdict: over-fit only beyond kGapSigmas standard errors above the tolerance;
// otherwise V's noise when its SE is above the tolerance (or unknown); else above when the gap
// is above the tolerance; else within.
TEST(TrainingNoise, TheVerdictWeighsTheGapAgainstItsError) {
    EXPECT_EQ(kGapSigmas, 2.0);
    EXPECT_EQ(gapVerdict(0.03, 0.01, 0.05, false), GapVerdict::Within);
    EXPECT_EQ(gapVerdict(0.05, 0.05, 0.05, false), GapVerdict::Within);  // both at the tolerance
    EXPECT_EQ(gapVerdict(0.08, 0.02, 0.05, false), GapVerdict::Above);   // 0.08 − 0.04 ≤ 0.05
    EXPECT_EQ(gapVerdict(0.0501, 0.0001, 0.05, true), GapVerdict::Above);
    EXPECT_EQ(gapVerdict(0.10, 0.02, 0.05, false), GapVerdict::OverFit);  // 0.10 − 0.04 > 0.05
    EXPECT_EQ(gapVerdict(0.50, 0.30, 0.05, false), GapVerdict::ValidationNoise);   // −0.10
    EXPECT_EQ(gapVerdict(0.30, 0.10, 0.05, false), GapVerdict::OverFit);           // 0.10 > 0.05
    EXPECT_EQ(gapVerdict(0.20, 0.10, 0.05, false), GapVerdict::ValidationNoise);   // 0, SE > 5 %
    EXPECT_EQ(gapVerdict(-0.14, 0.30, 0.05, false), GapVerdict::ValidationNoise);  // noisy
    // At V's most spp the verdict on a known SE is the same.
    EXPECT_EQ(gapVerdict(0.20, 0.10, 0.05, true), GapVerdict::ValidationNoise);
    // An unknown SE (V's figure on the floor): V's noise while V can grow, over-fit after.
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(gapVerdict(0.01, std::nan(""), 0.05, false), GapVerdict::ValidationNoise);
    EXPECT_EQ(gapVerdict(inf, std::nan(""), 0.05, false), GapVerdict::ValidationNoise);
    EXPECT_EQ(gapVerdict(inf, std::nan(""), 0.05, true), GapVerdict::OverFit);
    // V's next spp: SE ∝ 1/sqrt(spp), spp·(SE/maxGap)² to a power of two, at least 2×, at most
    // the cap; none at the cap.
    TrainingNoiseOptions o;
    EXPECT_EQ(o.maxValidationSpp, kJudgeDefaultSpp);
    EXPECT_EQ(nextValidationSpp(64, 0.08, o), 256);   // 64·2.56 = 164 -> 256
    EXPECT_EQ(nextValidationSpp(64, 0.06, o), 128);   // 92 -> 128
    EXPECT_EQ(nextValidationSpp(512, 0.5, o), 1024);  // capped
    EXPECT_EQ(nextValidationSpp(1024, 0.5, o), std::nullopt);
    EXPECT_EQ(nextValidationSpp(16, std::nan(""), o), 1024);
    EXPECT_TRUE(validationSppFree(ObjectiveKind::Defects));
    EXPECT_TRUE(validationSppFree(ObjectiveKind::Unbiased));
    EXPECT_FALSE(validationSppFree(ObjectiveKind::Paper));  // eq. 2 is biased by the noise
}

// Step 4's decisions, one per verdict: within keeps; V's noise raises V (T for eq. 2); above
// raises V while its SE could hide twice the tolerance, else T like over-fit, then a coarser
// light; at the limits the light is kept, unresolved when V's noise could explain the gap.
TEST(TrainingNoise, EachVerdictLeadsToItsRemedy) {
    TrainingNoiseOptions o;  // 5 %, T to 512 spp, V to 1024
    auto round = [](int spp, int vSpp, double gap, double se, LightGrid grid = {}) {
        TrainingNoiseRound r;
        r.spp = spp;
        r.validationSpp = vSpp;
        r.gap = gap;
        r.gapError = se;
        r.grid = grid;
        return r;
    };
    auto decide = [&](const TrainingNoiseRound& r, ObjectiveKind kind = ObjectiveKind::Defects) {
        return decideAfterRound(r, kind, o, 50, 25);
    };
    GapDecision d = decide(round(64, 16, 0.04, 0.01));
    EXPECT_EQ(d.verdict, GapVerdict::Within);
    EXPECT_EQ(d.describe(), "kept");
    EXPECT_FALSE(d.unresolved);
    // Above, V's SE 4 % > 2.5 %: V to SE ≤ 2.5 %: 16·(0.04/0.025)² = 41 -> 64.
    d = decide(round(64, 16, 0.08, 0.04));
    EXPECT_EQ(d.verdict, GapVerdict::Above);
    EXPECT_EQ(d.describe(), "V at 64 spp");
    // Above with V's SE ≤ 2.5 %: T's spp as for over-fit, 64·0.08/0.025 = 205 -> 256.
    d = decide(round(64, 64, 0.08, 0.02));
    EXPECT_EQ(d.verdict, GapVerdict::Above);
    EXPECT_EQ(d.describe(), "T at 256 spp");
    // The same where V is at its most spp already.
    EXPECT_EQ(decide(round(64, 1024, 0.08, 0.04)).describe(), "T at 256 spp");
    // Over-fit: T first; at T's most spp a coarser light; at the coarsest, kept as over-fit.
    EXPECT_EQ(decide(round(64, 16, 0.3, 0.02)).verdict, GapVerdict::OverFit);
    EXPECT_EQ(decide(round(64, 16, 0.3, 0.02)).describe(), "T at 512 spp");  // at most 8×
    EXPECT_EQ(decide(round(512, 128, 0.3, 0.02)).describe(), "a coarser light, 35x18 nodes");
    d = decide(round(512, 128, 0.3, 0.02, LightGrid{9, 4}));
    EXPECT_EQ(d.describe(), "kept: over-fit at the limits");
    EXPECT_FALSE(d.unresolved);
    // Above at the same limits: the light is kept, the gap not resolved.
    d = decide(round(512, 128, 0.07, 0.02, LightGrid{9, 4}));
    EXPECT_EQ(d.verdict, GapVerdict::Above);
    EXPECT_EQ(d.describe(), "kept: not resolved at this cost");
    EXPECT_TRUE(d.unresolved);
    // V's noise: V rises; at V's most, kept unresolved; eq. 2 raises T's spp instead (its V
    // keeps T's spp).
    EXPECT_EQ(decide(round(64, 16, 0.2, 0.1)).describe(), "V at 64 spp");  // 16·(0.1/0.05)² = 64
    EXPECT_TRUE(decide(round(64, 1024, 0.2, 0.1)).unresolved);
    EXPECT_EQ(decide(round(64, 64, 0.2, 0.1), ObjectiveKind::Paper).describe(), "T at 256 spp");
    // A given spp: nothing is traced again; over-fit still coarsens the light, above does not.
    o.adapt = false;
    EXPECT_EQ(decide(round(16, 16, 0.3, 0.02)).describe(), "a coarser light, 35x18 nodes");
    d = decide(round(16, 16, 0.07, 0.02));
    EXPECT_EQ(d.verdict, GapVerdict::Above);
    EXPECT_EQ(d.describe(), "kept: not resolved at this cost");
}

// The rule's caps are a budget of samples: an image with k times fewer pixels than 256² takes up
// to k times the spp (a power of two, at most 4×), a larger one keeps the caps; a given --max-spp
// is kept, V's cap still scales; and the scaled caps lead the remedies on.
TEST(TrainingNoise, TheSppCapsAreABudgetOfSamples) {
    EXPECT_EQ(sppCapForImage(512, 256 * 256), 512);
    EXPECT_EQ(sppCapForImage(512, 512 * 512), 512);
    EXPECT_EQ(sppCapForImage(512, 200 * 200), 512);  // 1.6× fewer pixels: no power of two
    EXPECT_EQ(sppCapForImage(512, 181 * 181), 1024);
    EXPECT_EQ(sppCapForImage(512, 128 * 128), 2048);
    EXPECT_EQ(sppCapForImage(1024, 128 * 128), 4096);
    EXPECT_EQ(sppCapForImage(512, 64 * 64), 2048);  // at most kMaxSppCapScale
    for (size_t pixels : {size_t{48 * 48}, size_t{128 * 128}, size_t{300 * 300}}) {
        const int cap = sppCapForImage(512, pixels);
        // The samples of a trace at the cap never exceed a 256² trace at 512 spp.
        EXPECT_LE(static_cast<double>(cap) * static_cast<double>(pixels),
                  512.0 * static_cast<double>(std::max(pixels, kSppCapPixels)));
    }
    const TrainingNoiseOptions base;
    const TrainingNoiseOptions small = base.forImage(128 * 128, false);
    EXPECT_EQ(small.maxSpp, 4 * base.maxSpp);
    EXPECT_EQ(small.maxValidationSpp, 4 * base.maxValidationSpp);
    EXPECT_EQ(small.maxGap, base.maxGap);
    TrainingNoiseOptions given = base;
    given.maxSpp = 64;
    EXPECT_EQ(given.forImage(128 * 128, true).maxSpp, 64);
    EXPECT_EQ(given.forImage(128 * 128, true).maxValidationSpp, 4 * base.maxValidationSpp);
    EXPECT_EQ(base.forImage(256 * 256, false).maxSpp, base.maxSpp);
    // Over-fit at 512 spp on a 128² image: more T, not yet a coarser light; V's noise at 1024
    // spp: more V, not yet "not resolved".
    TrainingNoiseRound r;
    r.spp = 512;
    r.validationSpp = 1024;
    r.gap = 0.3;
    r.gapError = 0.02;
    EXPECT_EQ(decideAfterRound(r, ObjectiveKind::Defects, small, 50, 25).describe(),
              "T at 2048 spp");
    EXPECT_EQ(decideAfterRound(r, ObjectiveKind::Defects, base, 50, 25).describe(),
              "a coarser light, 35x18 nodes");
    r.gap = 0.2;
    r.gapError = 0.1;
    EXPECT_EQ(decideAfterRound(r, ObjectiveKind::Defects, small, 50, 25).describe(),
              "V at 4096 spp");
    EXPECT_TRUE(decideAfterRound(r, ObjectiveKind::Defects, base, 50, 25).unresolved);
}

// V's first round (step 1): a quarter of T's spp, even, at least 16, at most T's.
TEST(TrainingNoise, TheValidationEstimateStartsAtAQuarterOfTsSpp) {
    EXPECT_EQ(validationPilotSpp(64), 16);
    EXPECT_EQ(validationPilotSpp(512), 128);
    EXPECT_EQ(validationPilotSpp(32), 16);
    EXPECT_EQ(validationPilotSpp(8), 8);
    EXPECT_EQ(validationPilotSpp(4), 4);
    EXPECT_EQ(validationPilotSpp(200), 50);
}

// The answer chosen on V's first round stands only when it wins by more than
// kAnswerMarginSigmas standard errors of the difference against the other side (the references
// when an optimized light won, the optimized lights when a reference did); a candidate of its
// own side, or one not eligible, is no rival; an unknown SE decides nothing.
TEST(TrainingNoise, AnAnswerWithinVsNoiseIsNotDecided) {
    auto candidate = [](const char* name, CandidateKind kind, double u, bool eligible = true) {
        ScoredCandidate c;
        c.candidate.name = name;
        c.candidate.kind = kind;
        c.merit.value = u;
        c.merit.what = "U";  // lower is better
        c.eligible = eligible;
        return c;
    };
    AnswerChoice c;
    c.scored = {candidate("optimized", CandidateKind::Optimized, 9.0),
                candidate("start specular", CandidateKind::Start, 9.01),
                candidate("lamp", CandidateKind::Reference, 10.0),
                candidate("dark", CandidateKind::Reference, 9.05, false)};
    c.chosen = 0;
    // 1.0 apart of 10: decided up to an SE of 1/(3·√2·10) = 2.36 %.
    EXPECT_TRUE(answerDecided(c, 0.02));
    EXPECT_FALSE(answerDecided(c, 0.03));
    EXPECT_FALSE(answerDecided(c, std::nan("")));
    // A reference that won: its rival is the best optimized light.
    c.chosen = 2;
    c.scored[2].merit.value = 8.9;
    EXPECT_FALSE(answerDecided(c, 0.003));  // 0.1 apart of 9.0
    EXPECT_TRUE(answerDecided(c, 0.002));
    // No rival: decided.
    c.scored = {candidate("optimized", CandidateKind::Optimized, 9.0)};
    c.chosen = 0;
    EXPECT_TRUE(answerDecided(c, 0.5));
}

namespace {

/// The defects objective (its ratio measure) through independent estimates of the bumpy part (the
/// validation estimate's trace, seeds `seed0` + k), with an 8×8 block of labels in the image's
/// centre: E's figure and the gap's SE against `training` on each.
struct GapOnEstimates {
    std::vector<double> figures, gaps, errors;
};
GapOnEstimates gapsOnEstimates(int spp, uint64_t seed0, int count, std::span<const double> e,
                               double training) {
    const Scene scene(test::bumpyPartDesc(32, 32), 48, 48, test::bumpyHeightMap(48));
    std::vector<uint8_t> block(32 * 32, 0);
    for (int y = 10; y < 22; ++y)
        for (int x = 10; x < 22; ++x) block[size_t(y) * 32 + x] = 1;
    GapOnEstimates out;
    for (int k = 0; k < count; ++k) {
        PrecomputeOptions o;
        o.spp = spp;
        const TransportSource v = validationEstimate(scene, o, seed0 + uint64_t(k), {});
        SearchInputs si;
        si.mask = v.file.matrix.objectMask;
        si.defects = block;
        // The ratio measure: a random light shows the block far above its floors there (on
        // JND most of these lights are below its 0.1-JND floor, V's figure then has no SE).
        ObjectiveOptions ratio;
        ratio.defectMeasure = DefectMeasure::Ratio;
        const ObjectiveOnT onV = objectiveOnT(ObjectiveKind::Defects, v.file.matrix, si, ratio);
        const LossParts parts = onV.loss->evaluate(e, {});
        // The bootstrap's images are the loss's own: the loss at them is the loss at E.
        EXPECT_NEAR(onV.loss->evaluateImages(onV.loss->halfImages(e), e).total, parts.total,
                    1e-12 * std::abs(parts.total));
        const double figure = trainingFigure(ObjectiveKind::Defects, parts);
        out.figures.push_back(figure);
        out.gaps.push_back(trainingGap(ObjectiveKind::Defects, training, figure));
        out.errors.push_back(
            trainingGapError(ObjectiveKind::Defects, *onV.loss, e, v.file.provenance.seed));
    }
    return out;
}

}  // namespace

// The gap's SE is V's own noise: over 16 independent validation estimates of one light with no
// over-fit (its training figure the mean of its figures: the hypothesis the verdict tests), the
// gaps' standard deviation against the mean SE (the spread of 16 values is itself known to
// about ±18 %, as the judge's test of the same bootstrap).
TEST(TrainingNoise, TheGapsErrorMatchesItsSpreadOverValidationSeeds) {
    const std::vector<double> e = randomLight(1250, 5);
    const GapOnEstimates g = gapsOnEstimates(256, 9000, 16, e, /*training=*/1.0);
    for (double se : g.errors) ASSERT_TRUE(std::isfinite(se) && se > 0) << se;
    const double training = test::sampleMean(g.figures);
    std::vector<double> gaps;
    for (double f : g.figures) gaps.push_back(trainingGap(ObjectiveKind::Defects, training, f));
    EXPECT_NEAR(test::sampleSd(gaps) / test::sampleMean(g.errors), 1.0, 0.45)
        << test::sampleSd(gaps) << " vs " << test::sampleMean(g.errors);
    // ... and it falls as V's spp rises: V at 4× the spp, about half where the noise is small,
    // faster where its square counts (the ratio's denominator; the judge's SE does the same):
    // measured 0.25, required between an eighth and three quarters.
    const GapOnEstimates f = gapsOnEstimates(1024, 9000, 4, e, 1.0);
    const double ratio = test::sampleMean(f.errors) /
                         test::sampleMean(std::vector(g.errors.begin(), g.errors.begin() + 4));
    EXPECT_GT(ratio, 0.125);
    EXPECT_LT(ratio, 0.75);
}

// A light fitted to no estimate at all, scored on two independent ones: its gap is all
// validation noise. At 64 spp some of 16 such gaps pass the tolerance (the rule before its SE
// would have traced again), and weighed against their SE none is called over-fit. (At 32 spp
// one of 8 is: the visibility ratio of a light that barely shows the block is heavy-tailed.)
TEST(TrainingNoise, AGapThatIsAllValidationNoiseDoesNotRaiseTheSpp) {
    const std::vector<double> e = randomLight(1250, 6);
    // "Training" figures: the same light on other independent estimates.
    const GapOnEstimates t = gapsOnEstimates(64, 7000, 16, e, 1.0);
    int aboveTolerance = 0, measured = 0;
    for (size_t k = 0; k < t.gaps.size(); ++k) {
        const double training = 1.0 / (1.0 + t.gaps[k]);  // the figure on estimate 7000 + k
        const GapOnEstimates v = gapsOnEstimates(64, 8000 + k, 1, e, training);
        aboveTolerance += v.gaps[0] > 0.05;
        measured += std::isfinite(v.errors[0]);  // NaN: V's figure on the floor
        EXPECT_NE(gapVerdict(v.gaps[0], v.errors[0], 0.05, false), GapVerdict::OverFit)
            << "estimate " << k << ": gap " << v.gaps[0] << " ± " << v.errors[0];
    }
    EXPECT_GE(aboveTolerance, 4) << "the gaps are too small to test the rule";
    EXPECT_GE(measured, 6) << "too few gaps with a standard error to test it";
}

TEST(TrainingNoise, DefectPixelsTakeMoreSamplesWithinTheBudget) {
    EXPECT_EQ(defectSppFactor(0, 5000), 1);
    EXPECT_EQ(defectSppFactor(50, 5000), kDefectSppScale);  // 1 %: 31 × 50 ≤ 2500
    EXPECT_EQ(defectSppFactor(84, 5212), 32);
    EXPECT_EQ(defectSppFactor(200, 5000), 8);   // 31·200 > 2500, 15·200 > 2500, 7·200 ≤ 2500
    EXPECT_EQ(defectSppFactor(2501, 5000), 1);  // over half the part: not even 2×
    EXPECT_EQ(defectSppFactor(1250, 5000), 2);
    for (size_t d = 1; d < 5000; d += 97) {
        const int f = defectSppFactor(d, 5000);
        EXPECT_LE(static_cast<double>(d) * (f - 1), kDefectSppBudget * 5000 + 1e-9) << d;
        EXPECT_LE(f, kDefectSppScale);
        EXPECT_GE(f, 1);
        EXPECT_GE(f, defectSppFactor(d + 97, 5000)) << "more defect pixels, more samples? " << d;
    }
    const std::vector<uint8_t> defects = {0, 1, 0, 255};
    EXPECT_TRUE(defectSppScale(defects, 1).empty());
    EXPECT_EQ(defectSppScale(defects, 8), (std::vector<uint8_t>{1, 8, 1, 8}));
}

// Per label: the smallest labels (the soft-min's noisiest sums) take the budget first; one label
// is the single-factor rule exactly; the budget holds; a smaller label never takes fewer samples.
TEST(TrainingNoise, SmallLabelsTakeTheBudgetFirst) {
    std::array<size_t, 256> n{};
    for (size_t d = 1; d < 5000; d += 97) {
        n.fill(0);
        n[255] = d;
        const std::array<int, 256> f = defectSppFactors(n, 5000);
        EXPECT_EQ(f[255], defectSppFactor(d, 5000)) << d;
        for (size_t v = 0; v < 255; ++v) EXPECT_EQ(f[v], 1) << v;
    }
    // A face-milled part at 128 px (the race's facemill-deep): a 15-pixel scratch and a 38-pixel
    // burr beside 911- and 1634-pixel chatter bands, of 5110 part pixels. One factor for all
    // (2597 marked) was 1; per label the two small ones take 32x and a band 2x, within the budget.
    n.fill(0);
    n[255] = 15;
    n[160] = 38;
    n[144] = 911;
    n[128] = 1634;
    EXPECT_EQ(defectSppFactor(15 + 38 + 911 + 1634, 5110), 1);
    const std::array<int, 256> f = defectSppFactors(n, 5110);
    EXPECT_EQ(f[255], 32);
    EXPECT_EQ(f[160], 32);
    EXPECT_EQ(f[144], 2);
    EXPECT_EQ(f[128], 1);
    EXPECT_EQ(f[0], 1);
    // Random label sizes: the budget holds and the order is kept.
    Pcg32 rng(29, 1);
    for (int trial = 0; trial < 200; ++trial) {
        n.fill(0);
        const int labels = 1 + static_cast<int>(rng.nextDouble() * 6);
        for (int k = 0; k < labels; ++k)
            n[static_cast<size_t>(1 + rng.nextDouble() * 254)] +=
                1 + static_cast<size_t>(rng.nextDouble() * 3000);
        const std::array<int, 256> g = defectSppFactors(n, 8000);
        double extra = 0;
        for (size_t v = 1; v < 256; ++v) {
            extra += static_cast<double>(n[v]) * (g[v] - 1);
            EXPECT_GE(g[v], 1);
            EXPECT_LE(g[v], kDefectSppScale);
            for (size_t u = 1; u < 256; ++u)
                if (n[u] > 0 && n[v] > 0 && n[u] < n[v]) {
                    EXPECT_GE(g[u], g[v]) << trial;
                }
        }
        EXPECT_LE(extra, kDefectSppBudget * 8000 + 1e-9) << trial;
    }
    std::array<int, 256> h;
    h.fill(1);
    const std::vector<uint8_t> defects = {0, 160, 0, 255, 144};
    EXPECT_TRUE(defectSppScale(defects, h).empty());
    h[255] = 32;
    h[160] = 8;
    EXPECT_EQ(defectSppScale(defects, h), (std::vector<uint8_t>{1, 8, 1, 32, 1}));
}

TEST(Answer, TheBestOnValidationIsTheAnswerAndALampCanBeIt) {
    auto scene =
        std::make_unique<Scene>(test::bumpyPartDesc(32, 32), 40, 40, test::bumpyHeightMap(40));
    JudgeOptions jo;
    jo.spp = 32;
    jo.objective.lambda = 0;
    const Judge validation(*scene, jo);
    const std::vector<double> lamp = randomLight(1250, 3);
    const double uLamp = validation.score(lamp).unbiased.total;
    {
        const AnswerChoice c =
            chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, scaled(lamp, 0.5)},
                                      {"lamp", CandidateKind::Reference, lamp}});
        ASSERT_EQ(c.scored.size(), 2u);
        EXPECT_NEAR(c.scored[0].merit.value, 2 * uLamp, 1e-9 * uLamp);
        EXPECT_EQ(c.scored[0].merit.what, "U");
        EXPECT_TRUE(c.referenceWon());
        EXPECT_EQ(c.answer().candidate.name, "lamp");
        EXPECT_EQ(c.optimized, 0u);
        EXPECT_NE(c.reason.find("reference light lamp"), std::string::npos) << c.reason;
    }
    {
        const AnswerChoice c =
            chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, scaled(lamp, 1.25)},
                                      {"lamp", CandidateKind::Reference, lamp}});
        EXPECT_FALSE(c.referenceWon());
        EXPECT_EQ(c.chosen, 0u);
        EXPECT_NEAR(c.answer().merit.value, uLamp / 1.25, 1e-9 * uLamp);
    }
    // Without an optimized candidate there is nothing to check.
    EXPECT_THROW(chooseAnswer(validation, {{"lamp", CandidateKind::Reference, lamp}}),
                 std::invalid_argument);
}

// Defect visibility is invariant to the light's scale, so a light 100× dimmer shows the
// defects exactly as well by the ratio — and is still not the answer: its image is darker than
// 0.05 of white. When every light is that dark, the best of them is, said so.
TEST(Answer, ALightThatLeavesThePartBlackIsNotTheAnswer) {
    const auto part = ScratchedPartJudge::make();
    const Judge& validation = *part->judge;
    // Of two random lights, the one with the higher visibility is dimmed to 1 %.
    std::vector<double> a = randomLight(1250, 11), b = randomLight(1250, 12);
    const double va = combinedVisibility(validation.score(a).visibility),
                 vb = combinedVisibility(validation.score(b).visibility);
    ASSERT_TRUE(std::isfinite(va) && std::isfinite(vb));
    if (vb > va) std::swap(a, b);
    const std::vector<double> dark = scaled(a, 0.01);
    const AnswerChoice c = chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, dark},
                                                     {"lamp", CandidateKind::Reference, b}});
    EXPECT_EQ(c.scored[0].merit.what, "defect visibility");
    EXPECT_NEAR(c.scored[0].merit.value, std::max(va, vb), 1e-9 * std::max(va, vb));
    EXPECT_GT(c.scored[0].merit.value, c.scored[1].merit.value);
    EXPECT_FALSE(c.scored[0].eligible);
    EXPECT_NE(c.scored[0].why.find("too dark"), std::string::npos);
    EXPECT_TRUE(c.referenceWon());
    // The reason says the optimized light failed a check, not that the lamp showed more.
    EXPECT_NE(c.reason.find("the optimized light does not pass the checks"), std::string::npos)
        << c.reason;
    EXPECT_EQ(c.reason.find("shows the defects better"), std::string::npos) << c.reason;
    // Both dark: the better one is still the answer, and the reason says why.
    const AnswerChoice d =
        chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, dark},
                                  {"lamp", CandidateKind::Reference, scaled(b, 0.01)}});
    EXPECT_EQ(d.chosen, 0u);
    EXPECT_NE(d.reason.find("no light passes the checks"), std::string::npos) << d.reason;
}

// The answer is chosen on what the judge reports first. Of two lights that pass the checks,
// one shows the scratch better by the visibility ratio (the defects' gradient over the
// texture's) and worse in JND (a person sees it less: less contrast, a dimmer image, more
// masking): with a viewing model the other is the answer, and when it is the lamp, the lamp is
// returned; without a viewing model the ratio decides as before, and without regions U does.
TEST(Answer, WithAViewingModelTheAnswerIsChosenInJnd) {
    const auto part = ScratchedPartJudge::make();
    const Judge &jnd = *part->jndJudge, &ratio = *part->judge;
    // Lights of different character: random skies, bright bands over a dim sky, each also at
    // 30 % (the same ratio, a dimmer image).
    std::vector<std::vector<double>> lights;
    for (uint64_t k = 1; k <= 6; ++k) lights.push_back(randomLight(1250, 40 + k));
    for (size_t b = 0; b < 1250; b += 125) {
        std::vector<double> band(1250, 0.05);
        for (size_t i = b; i < b + 60; ++i) band[i] = 1.0;
        lights.push_back(band);
    }
    for (size_t k = 0, n = lights.size(); k < n; ++k) lights.push_back(scaled(lights[k], 0.3));
    struct Figures {
        double visibility, jnd;
    };
    std::vector<Figures> f;
    std::vector<size_t> eligible;
    for (size_t k = 0; k < lights.size(); ++k) {
        const JudgeScore s = jnd.score(lights[k]);
        f.push_back({combinedVisibility(s.visibility), combinedJnd(s.visibility)});
        if (s.brightness >= kMinVisibleBrightness &&
            combinedContrast(s.visibility) >= kMinDefectContrast && f.back().jnd > 0)
            eligible.push_back(k);
    }
    // The pair where the ratio and the JND disagree the most (by the JND's factor).
    size_t opt = 0, lamp = 0;
    double most = 1;
    for (size_t a : eligible)
        for (size_t b : eligible)
            if (f[a].visibility > 1.05 * f[b].visibility && f[b].jnd / f[a].jnd > most) {
                most = f[b].jnd / f[a].jnd;
                opt = a;
                lamp = b;
            }
    ASSERT_GT(most, 1.1) << "no two lights disagree: the test part cannot tell the rules apart";
    const std::vector<AnswerCandidate> candidates = {
        {"optimized", CandidateKind::Optimized, lights[opt]},
        {"lamp", CandidateKind::Reference, lights[lamp]}};

    const AnswerChoice c = chooseAnswer(jnd, candidates);
    ASSERT_TRUE(c.scored[0].eligible && c.scored[1].eligible) << c.reason;
    EXPECT_EQ(c.scored[0].merit.what, "JND");
    EXPECT_NEAR(c.scored[0].merit.value, f[opt].jnd, 1e-9 * f[opt].jnd);
    EXPECT_NEAR(c.scored[1].merit.value, f[lamp].jnd, 1e-9 * f[lamp].jnd);
    // The ratio stays beside the JND.
    EXPECT_NEAR(c.scored[0].merit.visibility, f[opt].visibility, 1e-9 * f[opt].visibility);
    EXPECT_TRUE(c.referenceWon()) << c.reason;
    EXPECT_EQ(c.answer().candidate.name, "lamp");
    EXPECT_EQ(c.optimized, 0u);
    EXPECT_NE(c.reason.find("reference light lamp shows the defects better"), std::string::npos)
        << c.reason;
    EXPECT_NE(c.reason.find("(JND "), std::string::npos) << c.reason;
    EXPECT_NE(c.reason.find("visibility ratio"), std::string::npos) << c.reason;
    const nlohmann::ordered_json j = answerJson(c);
    EXPECT_EQ(j["merit"], "JND");
    EXPECT_EQ(j["light"], "lamp");
    EXPECT_DOUBLE_EQ(j["candidates"][0]["visibility"].get<double>(), c.scored[0].merit.visibility);
    EXPECT_GE(j["seconds"].get<double>(), 0.0);

    // No viewing model: the ratio, and the optimized light is the answer.
    const AnswerChoice r = chooseAnswer(ratio, candidates);
    EXPECT_EQ(r.scored[0].merit.what, "defect visibility");
    EXPECT_NEAR(r.scored[0].merit.value, f[opt].visibility, 1e-9 * f[opt].visibility);
    EXPECT_EQ(r.chosen, 0u) << r.reason;
    EXPECT_EQ(r.reason.find("visibility ratio"), std::string::npos) << r.reason;
    // No regions: U, viewing model or not.
    const AnswerChoice u = chooseAnswer(*part->plainJudge, candidates);
    EXPECT_EQ(u.scored[0].merit.what, "U");
    EXPECT_DOUBLE_EQ(u.scored[0].merit.value, part->plainJudge->score(lights[opt]).unbiased.total);
    EXPECT_TRUE(std::isnan(u.scored[0].merit.visibility));
}

// With the `both` measure the merit is a gain over the lamp: the smaller of the least visible
// kind's JND over the lamp's and the visibility ratio over the lamp's. A light that shows the
// defects more in JND but less out of the texture than the lamp loses to it; one above it by
// both wins, with the smaller gain as its merit.
TEST(Answer, TheGainOverTheLampNeedsBothMeasures) {
    const auto part = ScratchedPartJudge::make();
    const Judge& jnd = *part->jndJudge;
    std::vector<std::vector<double>> lights;
    for (uint64_t k = 1; k <= 8; ++k) lights.push_back(randomLight(1250, 60 + k));
    for (size_t b = 0; b < 1250; b += 125) {
        std::vector<double> band(1250, 0.05);
        for (size_t i = b; i < b + 60; ++i) band[i] = 1.0;
        lights.push_back(band);
    }
    struct Figures {
        double jnd, visibility;
    };
    std::vector<Figures> f;
    for (const auto& e : lights) {
        const AnswerMerit m = answerMerit(jnd.score(e), true);
        const bool ok = jnd.score(e).brightness >= kMinVisibleBrightness;
        f.push_back({ok ? m.value : std::nan(""), m.visibility});
    }
    // A pair that disagrees (a: more JND, less ratio than b) and one that agrees (a above b by
    // both by at least 5 %).
    std::optional<std::pair<size_t, size_t>> disagree, agree;
    for (size_t a = 0; a < f.size(); ++a)
        for (size_t b = 0; b < f.size(); ++b) {
            if (!(f[a].jnd > 0) || !(f[b].jnd > 0)) continue;
            if (f[a].jnd > 1.05 * f[b].jnd && f[a].visibility < f[b].visibility / 1.05)
                disagree = {a, b};
            if (f[a].jnd > 1.05 * f[b].jnd && f[a].visibility > 1.05 * f[b].visibility)
                agree = {a, b};
        }
    ASSERT_TRUE(disagree && agree) << "the test part's lights cannot tell the rules apart";
    AnswerOptions o;
    o.gainOver = "lamp";
    // The test part shows its scratch below 1 JND under every light; the gains here are over the
    // lamp's own JND (no floor: the next test has the default floor of 1 JND).
    o.gainFloorJnd = 0;
    {
        const auto [a, b] = *disagree;
        const std::vector<AnswerCandidate> candidates = {
            {"optimized", CandidateKind::Optimized, lights[a]},
            {"lamp", CandidateKind::Reference, lights[b]}};
        EXPECT_EQ(chooseAnswer(jnd, candidates).chosen, 0u);  // by JND alone
        const AnswerChoice c = chooseAnswer(jnd, candidates, o);
        EXPECT_EQ(c.scored[0].merit.what, "gain over lamp");
        EXPECT_NEAR(c.scored[0].merit.value, f[a].visibility / f[b].visibility, 1e-9);
        EXPECT_NEAR(c.scored[0].merit.jnd, f[a].jnd, 1e-9 * f[a].jnd);
        EXPECT_NEAR(c.scored[1].merit.value, 1.0, 1e-12);
        EXPECT_TRUE(c.referenceWon()) << c.reason;
        EXPECT_NE(c.reason.find("gains over lamp"), std::string::npos) << c.reason;
    }
    {
        const auto [a, b] = *agree;
        const std::vector<AnswerCandidate> candidates = {
            {"optimized", CandidateKind::Optimized, lights[a]},
            {"lamp", CandidateKind::Reference, lights[b]}};
        const AnswerChoice c = chooseAnswer(jnd, candidates, o);
        EXPECT_EQ(c.chosen, 0u) << c.reason;
        EXPECT_NEAR(c.scored[0].merit.value,
                    std::min(f[a].jnd / f[b].jnd, f[a].visibility / f[b].visibility), 1e-9);
    }
}

// The contrast floor guards the visibility ratio (a ratio of two tiny gradients is noise); in
// JND a light that barely shows the defects scores near 0 by itself, so a uniform dome stays
// eligible there and competes on its JND.
TEST(Answer, TheContrastFloorGuardsOnlyTheRatio) {
    const auto part = ScratchedPartJudge::make();
    const std::vector<double> uniform(1250, 0.5), lamp = randomLight(1250, 21);
    const std::vector<AnswerCandidate> candidates = {
        {"optimized", CandidateKind::Optimized, lamp},
        {"uniform-0.5", CandidateKind::Reference, uniform}};
    // A floor above the dome's contrast and below the other light's.
    const double cu = combinedContrast(part->judge->score(uniform).visibility),
                 cl = combinedContrast(part->judge->score(lamp).visibility);
    ASSERT_LT(cu, cl);
    AnswerOptions options;
    options.minContrast = std::sqrt(cu * cl);
    const AnswerChoice r = chooseAnswer(*part->judge, candidates, options);
    EXPECT_FALSE(r.scored[1].eligible) << r.reason;
    EXPECT_NE(r.scored[1].why.find("barely show"), std::string::npos) << r.scored[1].why;
    const AnswerChoice j = chooseAnswer(*part->jndJudge, candidates, options);
    EXPECT_EQ(j.scored[1].merit.what, "JND");
    EXPECT_TRUE(j.scored[1].eligible) << j.scored[1].why;
    EXPECT_TRUE(std::isfinite(j.scored[1].merit.value));
    EXPECT_EQ(j.chosen, j.scored[1].merit.value > j.scored[0].merit.value ? 1u : 0u) << j.reason;
}

// With several defect kinds the answer is chosen on the least visible kind's JND (what the
// defects objective maximizes), not the pooled JND, which follows the best-shown kind: a light
// showing one kind at 10 JND and another at 0.9 (below threshold) loses to one showing both at
// 2.5 or more. Regions without pixels do not count; equal values fall to the pooled JND.
TEST(Answer, TheJndMeritIsTheLeastVisibleKinds) {
    auto region = [](const char* name, size_t pixels, double jnd) {
        RegionVisibility r;
        r.label.name = name;
        r.pixels = pixels;
        r.jnd = jnd;
        r.visibility = 1.5;
        return r;
    };
    JudgeScore lamp, optimized;
    lamp.visibility = {region("scratch", 400, 10.0), region("pit-chain", 60, 0.9),
                       region("defect", 0, std::numeric_limits<double>::quiet_NaN())};
    optimized.visibility = {region("scratch", 400, 3.0), region("pit-chain", 60, 2.5),
                            region("defect", 0, std::numeric_limits<double>::quiet_NaN())};
    size_t least = 9;
    EXPECT_DOUBLE_EQ(leastVisibleJnd(lamp.visibility, &least), 0.9);
    EXPECT_EQ(least, 1u);
    const AnswerMerit ml = answerMerit(lamp, true), mo = answerMerit(optimized, true);
    EXPECT_EQ(ml.what, "JND");
    EXPECT_DOUBLE_EQ(ml.value, 0.9);
    EXPECT_EQ(ml.leastVisible, "pit-chain");
    EXPECT_NEAR(ml.pooled, std::pow(std::pow(10.0, 4) + std::pow(0.9, 4), 0.25), 1e-12);
    EXPECT_GT(ml.pooled, mo.pooled);  // pooled, the lamp would win
    EXPECT_TRUE(betterMerit(mo, ml));
    EXPECT_FALSE(betterMerit(ml, mo));
    // A tie on the least visible kind: the pooled JND decides.
    optimized.visibility[1].jnd = 0.9;
    EXPECT_TRUE(betterMerit(answerMerit(lamp, true), answerMerit(optimized, true)));
    // Without a viewing model: the ratio; a light whose JND cannot be formed is never better.
    EXPECT_EQ(answerMerit(lamp, false).what, "defect visibility");
    for (RegionVisibility& r : lamp.visibility) r.jnd = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(std::isnan(leastVisibleJnd(lamp.visibility)));
    EXPECT_EQ(answerMerit(lamp, true).what, "JND");
    EXPECT_FALSE(betterMerit(answerMerit(lamp, true), answerMerit(optimized, true)));
    EXPECT_TRUE(betterMerit(answerMerit(optimized, true), answerMerit(lamp, true)));
    // No region in view: U.
    for (RegionVisibility& r : lamp.visibility) r.pixels = 0;
    EXPECT_EQ(answerMerit(lamp, true).what, "U");
}

// A finer light (searched before E* on a finer grid, its training figure over-fit) is the answer
// only when no trusted optimized light passes the checks, and then only if it beats the
// references on the validation estimate.
TEST(Answer, AFinerLightStandsInOnlyWhenTheTrustedOnesFailTheChecks) {
    const auto part = ScratchedPartJudge::make();
    const Judge& validation = *part->judge;
    // Three random lights by visibility: best, middle, worst.
    std::vector<std::vector<double>> l{randomLight(1250, 21), randomLight(1250, 22),
                                       randomLight(1250, 23)};
    std::sort(l.begin(), l.end(), [&](const auto& a, const auto& b) {
        return combinedVisibility(validation.score(a).visibility) >
               combinedVisibility(validation.score(b).visibility);
    });
    // E* passes the checks: the better finer light is not the answer, and says why.
    const AnswerChoice trusted =
        chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, l[1]},
                                  {"optimized on texels", CandidateKind::Finer, l[0]},
                                  {"lamp", CandidateKind::Reference, l[2]}});
    EXPECT_EQ(trusted.chosen, 0u) << trusted.reason;
    EXPECT_FALSE(trusted.scored[1].eligible);
    EXPECT_NE(trusted.scored[1].why.find("fits the estimate's noise"), std::string::npos);
    // E* too dark: the finer light beats the lamp and is the answer, said so.
    const AnswerChoice fallback =
        chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, scaled(l[1], 0.01)},
                                  {"optimized on texels", CandidateKind::Finer, l[0]},
                                  {"lamp", CandidateKind::Reference, l[2]}});
    EXPECT_EQ(fallback.chosen, 1u) << fallback.reason;
    EXPECT_FALSE(fallback.referenceWon());
    EXPECT_NE(fallback.reason.find("searched before it on a finer grid"), std::string::npos)
        << fallback.reason;
    EXPECT_EQ(answerJson(fallback)["kind"], "finer");
    // ... but a lamp better than the finer light still wins.
    const AnswerChoice lamp =
        chooseAnswer(validation, {{"optimized", CandidateKind::Optimized, scaled(l[1], 0.01)},
                                  {"optimized on texels", CandidateKind::Finer, l[2]},
                                  {"lamp", CandidateKind::Reference, l[0]}});
    EXPECT_EQ(lamp.chosen, 2u) << lamp.reason;
    EXPECT_TRUE(lamp.referenceWon());
}

// A labelled part traced at 4 spp: the defects objective fits the estimate's noise, so the rule
// measures a gap above 5 % and traces again at more spp (or says, at its cap, that no light is
// trusted); summary.json records every round, the answer and its candidates, and the losses
// are the defects objective's on T.
TEST(OptimizeAnswers, DefectsBelowTheTrainingNoiseRaiseTheSpp) {
    test::TempDir dir("answers-noise");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const auto out = dir.path() / "out";
    const test::RunResult r =
        test::runCli("optimize " + (dir.path() / "scene.json").string() + " --truth " +
                     (dir.path() / "part-truth.png").string() +
                     " --heldout none --no-figures --max-spp 64 --cache " +
                     (dir.path() / "cache").string() + " -o " + out.string() + " 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json s = readJson(out / "summary.json");
    EXPECT_EQ(s["objective"], "defects");
    EXPECT_EQ(s["loss_through"], "T");
    const json& n = s["training_noise"];
    ASSERT_TRUE(n.is_object()) << s.dump(2);
    ASSERT_GE(n["rounds"].size(), 2u) << n.dump(2);
    EXPECT_EQ(n["rounds"][0]["spp"], 4);
    EXPECT_EQ(n["rounds"][0]["light_grid"], "texels");
    // A real over-fit: once V resolves it (V alone traced again while its noise hides the
    // gap), the gap is more than its two standard errors above the tolerance (or V's figure is
    // on the floor at V's most spp), and T's spp rises.
    size_t firstOverFit = 0;
    while (firstOverFit < n["rounds"].size() &&
           n["rounds"][firstOverFit]["verdict"] == "validation noise")
        ++firstOverFit;
    ASSERT_LT(firstOverFit, n["rounds"].size()) << n.dump(2);
    const json& over = n["rounds"][firstOverFit];
    EXPECT_EQ(over["verdict"], "over-fit") << n.dump(2);
    if (!over["gap_se"].is_null()) {
        EXPECT_GT(over["gap"].get<double>() - kGapSigmas * over["gap_se"].get<double>(), 0.05);
    } else {
        EXPECT_EQ(over["validation_spp"], kJudgeDefaultSpp) << n.dump(2);
    }
    EXPECT_EQ(over["decision"].get<std::string>().substr(0, 5), "T at ") << n.dump(2);
    // The spp rises first (each round a new trace); at the most spp the light's grid gets
    // coarser instead (step 5), on the same T; V alone gets more spp when its noise hides the
    // gap (step 4). Each round says what came next.
    for (size_t k = 1; k < n["rounds"].size(); ++k) {
        const json &a = n["rounds"][k - 1], &b = n["rounds"][k];
        EXPECT_GE(b["validation_spp"].get<int>(), validationPilotSpp(b["spp"].get<int>()));
        if (b["spp"] != a["spp"]) {
            EXPECT_EQ(a["verdict"], "over-fit");
            EXPECT_EQ(a["decision"], "T at " + std::to_string(b["spp"].get<int>()) + " spp");
            EXPECT_GT(b["spp"].get<int>(), a["spp"].get<int>());
            EXPECT_EQ(b["light_grid"], "texels") << n.dump(2);
        } else if (b["light_grid"] == a["light_grid"]) {
            EXPECT_EQ(a["verdict"], "validation noise") << n.dump(2);
            EXPECT_GT(b["validation_spp"].get<int>(), a["validation_spp"].get<int>());
            EXPECT_EQ(b["training"], a["training"]);  // the same T and E*, V again
        } else {
            EXPECT_EQ(a["verdict"], "over-fit");
            EXPECT_EQ(b["spp"], 64) << n.dump(2);
        }
    }
    EXPECT_EQ(n["light_grid"], n["rounds"].back()["light_grid"]);
    EXPECT_EQ(s["light_grid"], n["light_grid"]);
    EXPECT_EQ(s["transport"]["spp"], n["spp"]);
    // V's spp: its last round's, or T's when the answer was within V's noise there.
    EXPECT_EQ(s["validation"]["transport"]["spp"], s["answer"]["validation_spp"]);
    EXPECT_TRUE(s["answer"]["validation_spp"] == n["rounds"].back()["validation_spp"] ||
                s["answer"]["validation_spp"] == n["spp"])
        << s["answer"].dump(2);
    EXPECT_EQ(n["gap_se"], n["rounds"].back()["gap_se"]);
    // The truth marks chatter over half the part: too many pixels to supersample them; the
    // smaller labels take the budget (defectSppFactors).
    const json& scale = s["transport"]["spp_scale"];
    if (!scale.is_null()) {
        const double part = s["mask_pixels"].get<double>();
        EXPECT_LT(scale["scaled_pixels"].get<double>(), 0.5 * part) << s["transport"].dump(2);
    }
    EXPECT_NE(s["validation"]["transport"]["seed"], s["transport"]["seed"]);
    const bool met = n["met"].get<bool>();
    EXPECT_EQ(met, n["rounds"].back()["verdict"] == "within");
    EXPECT_EQ(n["unresolved"].get<bool>(), n["rounds"].back()["verdict"] == "validation noise");
    if (n["rounds"].back()["verdict"] == "over-fit") {
        EXPECT_EQ(n["spp"], 64);
        EXPECT_NE(r.output.find("no light is trusted"), std::string::npos) << r.output;
    }
    if (n["unresolved"].get<bool>()) {
        EXPECT_NE(r.output.find("not resolved at this cost"), std::string::npos) << r.output;
    }
    // The gap is the figures' relative difference.
    const json& last = n["rounds"].back();
    EXPECT_NEAR(last["gap"].get<double>(),
                (last["training"].get<double>() - last["validation"].get<double>()) /
                    last["validation"].get<double>(),
                1e-12);
    // Every candidate was scored on the validation estimate; the answer is one of them.
    const json& a = s["answer"];
    ASSERT_TRUE(a.is_object());
    EXPECT_GE(a["candidates"].size(), 4u);
    // The scene has the default viewing model and the default measure (both): the answer is
    // chosen on the smaller of its JND's and its visibility ratio's gains over the lamp.
    EXPECT_EQ(a["merit"], "gain over studio preset");
    EXPECT_TRUE(a["candidates"][0]["visibility"].is_number()) << a.dump(2);
    bool found = false;
    for (const json& c : a["candidates"]) found |= c["name"] == a["light"];
    EXPECT_TRUE(found);
    EXPECT_EQ(std::filesystem::exists(out / "envmap-optimized.exr"), a["light"] != "optimized");
    // --heldout none: the headline says its figures are training figures, first.
    EXPECT_NE(r.output.find("Training figures only"), std::string::npos) << r.output;
}

// A given spp is kept; its gap is measured and, above the tolerance, warned about.
TEST(OptimizeAnswers, AGivenSppIsKeptAndItsGapWarnedAbout) {
    test::TempDir dir("answers-given");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const auto out = dir.path() / "out";
    const test::RunResult r =
        test::runCli("optimize " + (dir.path() / "scene.json").string() + " --truth " +
                     (dir.path() / "part-truth.png").string() +
                     " --spp 4 --defect-spp-scale 4 --heldout none --no-figures --cache " +
                     (dir.path() / "cache").string() + " -o " + out.string() + " 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json s = readJson(out / "summary.json");
    // The defect pixels took 4× the spp, in T and in V alike, and the run said so.
    ASSERT_TRUE(s["transport"]["spp_scale"].is_object()) << s["transport"].dump(2);
    EXPECT_EQ(s["transport"]["spp_scale"]["max"], 4);
    EXPECT_EQ(s["validation"]["transport"]["spp_scale"], s["transport"]["spp_scale"]);
    EXPECT_NE(r.output.find("take 4x the training spp"), std::string::npos) << r.output;
    const json& n = s["training_noise"];
    ASSERT_GE(n["rounds"].size(), 1u);
    EXPECT_FALSE(n["adapted"].get<bool>());
    EXPECT_EQ(s["transport"]["spp"], 4);
    for (const json& round : n["rounds"]) EXPECT_EQ(round["spp"], 4);  // only the grid adapts
    if (!n["met"].get<bool>()) {
        const std::string reason = n["reason"].get<std::string>();
        EXPECT_NE(reason.find("(the given spp"), std::string::npos) << reason;
        EXPECT_NE(
            reason.find(n["unresolved"].get<bool>() ? "not resolved at this cost" : ": ABOVE 5 %"),
            std::string::npos)
            << reason;
        bool warned = false;
        for (const json& w : s["warnings"])
            warned |= w.get<std::string>().find("training noise") != std::string::npos;
        EXPECT_TRUE(warned) << s["warnings"].dump();
    }
    // The defects objective (both measures) chose its answer on its gains over the lamp; the
    // whole-image objective on the same part and truth chooses on the JND.
    EXPECT_EQ(s["answer"]["merit"], "gain over studio preset");
    const auto whole = dir.path() / "whole";
    const test::RunResult u =
        test::runCli("optimize " + (dir.path() / "scene.json").string() + " --truth " +
                     (dir.path() / "part-truth.png").string() +
                     " --objective unbiased --spp 4 --heldout none --no-figures --cache " +
                     (dir.path() / "cache").string() + " -o " + whole.string() + " 2>&1");
    ASSERT_EQ(u.exitCode, 0) << u.output;
    EXPECT_EQ(readJson(whole / "summary.json")["answer"]["merit"], "JND");
}

// A black box (SPSA through our renderer) minimizes eq. 2 through the renderer: the summary's
// objective, initial and final loss are that, and say so; another objective is refused.
TEST(OptimizeAnswers, TheBlackBoxSummaryReportsTheLossItMinimized) {
    test::TempDir dir("answers-blackbox");
    ASSERT_EQ(test::writeSmallLabelledPart(dir.path()), 0);
    const auto out = dir.path() / "out";
    const std::string common = "optimize " + (dir.path() / "scene.json").string() +
                               " --optimizer spsa --iterations 6 --heldout none --no-figures "
                               "--cache " +
                               (dir.path() / "cache").string() + " -o " + out.string();
    const test::RunResult r = test::runCli(common + " 2>&1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const json s = readJson(out / "summary.json");
    EXPECT_EQ(s["objective"], "paper");
    EXPECT_NE(s["loss_through"].get<std::string>().find("our renderer"), std::string::npos);
    // loss.csv's rows are the optimizer's own losses through the renderer: the first is the
    // summary's initial loss; the final one (SPSA re-evaluates its best estimate exactly) lies
    // within what the optimizer saw.
    const std::string csv = test::readFile(out / "loss.csv");
    std::istringstream lines(csv);
    std::string line;
    std::getline(lines, line);  // header
    double first = std::nan(""), lo = std::numeric_limits<double>::infinity(), hi = -lo;
    while (std::getline(lines, line)) {
        std::istringstream f(line);
        std::string it, ev, loss;
        std::getline(f, it, ',');
        std::getline(f, ev, ',');
        std::getline(f, loss, ',');
        const double v = std::stod(loss);
        if (std::isnan(first)) first = v;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    EXPECT_NEAR(s["initial_loss"].get<double>(), first, 1e-9 * std::abs(first));
    const double fin = s["final_loss"].get<double>();
    EXPECT_GE(fin, lo * (1 - 0.05));
    EXPECT_LE(fin, hi);
    EXPECT_EQ(s["improved"].get<bool>(), fin < s["initial_loss"].get<double>());
    const test::RunResult refused = test::runCli(common + " --objective unbiased 2>&1");
    EXPECT_NE(refused.exitCode, 0);
    EXPECT_NE(refused.output.find("eq. 2 through the renderer"), std::string::npos)
        << refused.output;
}

// Under a lamp that shows the defects less than just noticeably (the test part shows its scratch
// below 1 JND under every light; the lamp is the best of a few lights dimmed), the JND's gain is
// counted from 1 JND (kGainFloorJnd), as the both measure's anchor is: a finite merit, not a gain
// over nothing, and the answer line says so.
TEST(Answer, AGainOverALampThatShowsNothingCountsFromOneJnd) {
    const auto part = ScratchedPartJudge::make();
    const Judge& jnd = *part->jndJudge;
    // The light that shows the scratch best of a few, and that light dimmed below half of it.
    std::vector<double> bright;
    double best = -1;
    for (uint64_t k = 1; k <= 8; ++k) {
        std::vector<double> e = randomLight(1250, 60 + k);
        const double j = answerMerit(jnd.score(e), true).value;
        if (j > best) best = j, bright = std::move(e);
    }
    std::vector<double> dim = bright;
    double lampJnd = answerMerit(jnd.score(dim), true).value;
    for (int k = 0; k < 40 && !(lampJnd < 0.5 * best); ++k) {
        for (double& v : dim) v *= 0.25;
        lampJnd = answerMerit(jnd.score(dim), true).value;
    }
    ASSERT_LT(lampJnd, 0.5 * best) << "no dimming hides the test part's defects";
    const AnswerMerit lit = answerMerit(jnd.score(bright), true);
    const double lampVisibility = answerMerit(jnd.score(dim), true).visibility;
    ASSERT_LT(best, kGainFloorJnd);
    AnswerOptions o;
    o.gainOver = "lamp";
    const AnswerChoice c = chooseAnswer(
        jnd,
        {{"optimized", CandidateKind::Optimized, bright}, {"lamp", CandidateKind::Reference, dim}},
        o);
    EXPECT_NEAR(c.scored[0].merit.value,
                std::min(lit.value / kGainFloorJnd, lit.visibility / lampVisibility), 1e-9);
    EXPECT_NEAR(c.scored[1].merit.value, std::min(lampJnd / kGainFloorJnd, 1.0), 1e-12);
    EXPECT_TRUE(std::isfinite(c.scored[0].merit.value));
    EXPECT_NE(c.reason.find("counted from there"), std::string::npos) << c.reason;
}
