// The judge's standard errors and rounds (app/pipeline/Judge.h scoreWithErrors, judgeInRounds): the
// wild-bootstrap SE matches the spread of the scores over independent judge seeds and falls as
// 1/sqrt(spp), JND figures included; the rounds stop earlier for an easy light than for a hard
// one, trace more when the least visible kind's JND is noisy, hold the cap, and give the same
// numbers for the same seed; judge.json records the spp, the rounds and the SEs (JND's too).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "SyntheticDefects.h"
#include "TestUtil.h"
#include "app/pipeline/Judge.h"
#include "app/pipeline/TrainingNoise.h"
#include "core/Rng.h"
#include "core/WildBootstrap.h"
#include "objective/DefectVisibility.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

std::unique_ptr<Scene> wavyScene(int res, int n = 48) {
    return std::make_unique<Scene>(test::bumpyPartDesc(res, res), n, n, test::bumpyHeightMap(n));
}

std::vector<double> randomLight(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 3);
    std::vector<double> v(n);
    for (double& x : v) x = rng.nextDouble();
    return v;
}

/// Labels: a (2r)×(2r) block in the image's centre, the "defect" whose visibility is scored.
std::vector<uint8_t> blockLabels(int w, int h, int r = 3) {
    std::vector<uint8_t> l(size_t(w) * h, 0);
    for (int y = h / 2 - r; y < h / 2 + r; ++y)
        for (int x = w / 2 - r; x < w / 2 + r; ++x) l[size_t(y) * w + x] = 255;
    return l;
}

/// The wavy part (its bumps halved) with a V groove across it (SyntheticDefects.h), image-space
/// labels over where it shows (the part fills the view: height-map sample i is near pixel
/// i·res/n), and a light of narrow bands (5 texels in 50) under which the groove is ~1.8 JND: well
/// above 0, so its estimates are not held at the floor max(·, 0).
struct GroovedPart {
    std::unique_ptr<Scene> scene;
    std::vector<uint8_t> labels;
    std::vector<double> light;
};
GroovedPart groovedPart(int res = 32, int n = 48) {
    std::vector<float> h = test::bumpyHeightMap(n);
    for (float& v : h) v *= 0.5f;
    std::vector<uint8_t> truth(h.size(), 0);
    test::paintGroove(h, truth, n, n / 2, n / 6, n / 2, 5 * n / 6, 3.0, 0.1);
    GroovedPart g;
    g.scene = std::make_unique<Scene>(test::bumpyPartDesc(res, res), n, n, h);
    g.labels.assign(size_t(res) * res, 0);
    for (int y = res / 6 + 1; y < 5 * res / 6; ++y)
        for (int x = res / 2 - 2; x <= res / 2 + 1; ++x) g.labels[size_t(y) * res + x] = 255;
    g.light.resize(1250);
    for (size_t i = 0; i < g.light.size(); ++i) g.light[i] = i % 50 < 5 ? 1.0 : 0.0;
    return g;
}

double mean(const std::vector<double>& v) {
    return test::sampleMean(v);
}
double sd(const std::vector<double>& v) {
    return test::sampleSd(v);
}

// The scores, with their errors, of one light on 16 independent judge estimates at `spp`
// (seeds kJudgeSeed + seedOffset + k).
std::vector<JudgeScore> scoresOverSeeds(const Scene& scene, const std::vector<double>& e, int spp,
                                        uint64_t seedOffset) {
    std::vector<JudgeScore> scores;
    for (uint64_t k = 0; k < 16; ++k) {
        JudgeOptions o;
        o.spp = spp;
        o.seed = kJudgeSeed + seedOffset + k;
        scores.push_back(Judge(scene, o).scoreWithErrors(e, "random"));
    }
    return scores;
}

// U's, eq. 2's and the brightness's spread over the estimates is their mean SE, within ±45 %.
void expectSpreadMatchesErrors(const std::vector<JudgeScore>& scores) {
    std::vector<double> u, eq2, bright, seU, seEq2, seBright;
    for (const JudgeScore& s : scores) {
        u.push_back(s.unbiased.total);
        eq2.push_back(s.eq2.total);
        bright.push_back(s.brightness);
        seU.push_back(s.se->unbiased);
        seEq2.push_back(s.se->eq2);
        seBright.push_back(s.se->brightness);
    }
    EXPECT_NEAR(sd(u) / mean(seU), 1.0, 0.45) << sd(u) << " vs " << mean(seU);
    EXPECT_NEAR(sd(eq2) / mean(seEq2), 1.0, 0.45) << sd(eq2) << " vs " << mean(seEq2);
    EXPECT_NEAR(sd(bright) / mean(seBright), 1.0, 0.45) << sd(bright) << " vs " << mean(seBright);
}

}  // namespace

// The SE of one estimate predicts how much the score moves between independent estimates:
// over 16 judge seeds at 256 spp, the scores' standard deviation against the mean SE (the
// spread of 16 values is itself known to about ±18 %).
TEST(JudgeRounds, StandardErrorMatchesTheSpreadOverIndependentSeeds) {
    auto scene = wavyScene(32);
    const std::vector<double> e = randomLight(1250, 11);
    const std::vector<JudgeScore> scores = scoresOverSeeds(*scene, e, 256, 100);
    for (const JudgeScore& s : scores) {
        ASSERT_TRUE(s.se);
        EXPECT_EQ(s.spp, 256);
        EXPECT_EQ(s.se->replicates, kJudgeReplicates);
    }
    expectSpreadMatchesErrors(scores);
}

// Sixteen times the samples: the standard error falls as 1/sqrt(spp) where the noise is small
// (a quarter), faster where the noise's square still counts (U's and the visibility's
// denominators are products of two noisy halves: that part falls as 1/spp, and the bootstrap,
// whose replicates add noise to noise, over-states it there: a conservative SE). So: between a
// quarter and a sixteenth, for every score (128 replicates; a 10×10 block). Measured on this
// scene: U 7.1×, visibility 8.0×, eq. 2 and brightness about 4×.
TEST(JudgeRounds, StandardErrorFallsAsOneOverSqrtSpp) {
    auto scene = wavyScene(32);
    const std::vector<double> e = randomLight(1250, 12);
    const std::vector<uint8_t> labels = blockLabels(32, 32, 5);
    JudgeScore::Errors lo, hi;
    for (int spp : {512, 8192}) {
        JudgeOptions o;
        o.spp = spp;
        const TransportSource est = judgeEstimate(*scene, o);
        const Judge judge(est, o, labels, {{255, "block"}});
        const JudgeScore s = judge.scoreWithErrors(e, "", 128);
        ASSERT_TRUE(s.se);
        (spp == 512 ? lo : hi) = *s.se;
    }
    auto between = [](double ratio, const char* what) {
        EXPECT_GE(ratio, 3.2) << what;   // 1/sqrt(spp), less 20 % for the SEs' own spread
        EXPECT_LE(ratio, 16.0) << what;  // 1/spp
    };
    between(lo.unbiased / hi.unbiased, "U");
    EXPECT_NEAR(lo.eq2 / hi.eq2, 4.0, 1.2);
    EXPECT_NEAR(lo.brightness / hi.brightness, 4.0, 1.2);
    ASSERT_EQ(lo.visibility.size(), 1u);
    between(lo.visibility[0] / hi.visibility[0], "visibility");
}

// The rule: on an easy scene (no region: U, eq. 2 and the brightness are sums over the whole
// part) the rounds stop in the first; on a hard one (a 6×6 block's visibility: a ratio of
// gradients over 36 pixels) they ask for more; a target no estimate meets stops at the cap,
// not met; the same seed gives the same rounds and numbers.
TEST(JudgeRounds, StopsEarlierOnAnEasySceneThanOnAHardOneAndHoldsTheCap) {
    auto scene = wavyScene(32);
    std::vector<std::unique_ptr<TransportSource>> kept;
    std::unique_ptr<Judge> judge;
    std::vector<uint8_t> labels;
    auto judgeAt = [&](int spp) -> const Judge& {
        JudgeOptions o;
        o.spp = spp;
        judge.reset();
        kept.push_back(std::make_unique<TransportSource>(judgeEstimate(*scene, o)));
        judge = std::make_unique<Judge>(
            *kept.back(), o, labels,
            labels.empty() ? std::vector<RegionLabel>{} : std::vector<RegionLabel>{{255, "block"}});
        return *judge;
    };
    const std::vector<double> e = randomLight(1250, 13);
    const double target = 0.05;
    const JudgedRounds a = judgeInRounds(judgeAt, {{"easy", e}}, 64, 1024, target);
    labels = blockLabels(32, 32);
    const JudgedRounds b = judgeInRounds(judgeAt, {{"hard", e}}, 64, 1024, target);
    ASSERT_EQ(a.scores.size(), 1u);
    EXPECT_TRUE(a.met) << a.describe(target);
    EXPECT_EQ(a.spp(), 64);
    EXPECT_EQ(a.rounds.size(), 1u);
    EXPECT_LE(a.rounds.back().worst.relative, target);
    EXPECT_GT(b.spp(), a.spp()) << b.describe(target);
    EXPECT_GT(b.rounds.size(), 1u);
    EXPECT_GT(b.rounds.front().worst.relative, target);
    EXPECT_EQ(b.rounds.front().worst.score.rfind("hard: ", 0), 0u) << b.rounds.front().worst.score;
    EXPECT_NE(b.rounds.front().worst.score.find("block"), std::string::npos)
        << b.rounds.front().worst.score;
    for (size_t k = 1; k < b.rounds.size(); ++k)
        EXPECT_GE(b.rounds[k].spp, 2 * b.rounds[k - 1].spp);  // at least twice a round
    EXPECT_EQ(b.scores.front().spp, b.spp());

    const JudgedRounds c = judgeInRounds(judgeAt, {{"hard", e}}, 16, 64, 1e-6);
    EXPECT_EQ(c.spp(), 64);
    EXPECT_FALSE(c.met);
    EXPECT_NE(c.describe(1e-6).find("at the most 64 spp"), std::string::npos) << c.describe();
    // A given spp is one round (spp == cap).
    EXPECT_EQ(judgeInRounds(judgeAt, {{"hard", e}}, 32, 32, target).rounds.size(), 1u);

    // Reproducible: the same seed, the same rounds and numbers, errors included.
    const JudgedRounds b2 = judgeInRounds(judgeAt, {{"hard", e}}, 64, 1024, target);
    ASSERT_EQ(b2.rounds.size(), b.rounds.size());
    EXPECT_EQ(b2.spp(), b.spp());
    EXPECT_EQ(b2.scores[0].unbiased.total, b.scores[0].unbiased.total);
    EXPECT_EQ(b2.scores[0].visibility[0].visibility, b.scores[0].visibility[0].visibility);
    EXPECT_EQ(b2.scores[0].se->visibility[0], b.scores[0].se->visibility[0]);
}

TEST(JudgeRounds, NextSppFollowsTheSquareOfTheErrorRatio) {
    EXPECT_EQ(nextJudgeSpp(128, 0.009, 1024), 0);        // met
    EXPECT_EQ(nextJudgeSpp(128, 0.012, 1024), 256);      // at least twice
    EXPECT_EQ(nextJudgeSpp(128, 0.025, 1024), 1024);     // 128 · 6.25 = 800 → 1024
    EXPECT_EQ(nextJudgeSpp(128, 0.017, 1024), 512);      // 128 · 2.89 = 370 → 512
    EXPECT_EQ(nextJudgeSpp(1024, 0.5, 1024), 0);         // at the cap
    EXPECT_EQ(nextJudgeSpp(128, INFINITY, 1024), 1024);  // an SE that could not be formed
    JudgeScore s;
    s.name = "x";
    s.unbiased.total = 10;
    s.brightness = 0.001;  // near zero: held to 0.05 · 1 %, not to 1 % of itself
    s.se = JudgeScore::Errors{};
    s.se->unbiased = 0.05;
    s.se->brightness = 0.0002;
    const WorstError w = worstRelativeError(s);
    EXPECT_NEAR(w.relative, 0.005, 1e-12);  // U's 0.05/10; brightness 0.0002/0.05 = 0.004
    EXPECT_EQ(w.score, "x: U");
}

// A reference (optimize's lamp and paper's light) is read only against the answer: its score's
// SE may be up to a tenth of its gap to the answer's (at most 20 % of itself), the answer's is
// held to 1 % (worstError; exact on scores whose SEs are given).
TEST(JudgeRounds, AReferenceIsHeldToItsGapToTheAnswer) {
    auto scored = [](const std::string& name, double u, double se) {
        JudgeScore s;
        s.name = name;
        s.unbiased.total = u;
        s.se = JudgeScore::Errors{};
        s.se->unbiased = se;
        return s;
    };
    const JudgeScore answer = scored("answer", 5.0, 0.04);  // 0.8 %
    const JudgeScore paper = scored("paper", 12.0, 0.6);    // 5 %, 7 from the answer
    const JudgeScore far = scored("answer", 400.0, 1.0);
    EXPECT_NEAR(worstError(answer).excess, 0.8, 1e-12);
    EXPECT_NEAR(worstError(paper).excess, 5.0, 1e-12);  // alone: 5 % against 1 %
    WorstError w = worstError(paper, kJudgeMaxError, &answer);
    EXPECT_NEAR(w.excess, 0.6 / 0.7, 1e-12);  // a tenth of the gap: 0.7
    EXPECT_TRUE(w.byGap);
    EXPECT_NEAR(w.relative, 0.05, 1e-12);
    EXPECT_EQ(w.score, "paper: U");
    // Near the answer (gap 0.5): a tenth of the gap (0.05) is below 1 % of itself (0.055).
    w = worstError(scored("near", 5.5, 0.275), kJudgeMaxError, &answer);
    EXPECT_NEAR(w.excess, 5.0, 1e-12);
    EXPECT_FALSE(w.byGap);
    // The cap: a tenth of a gap of 300 is 30, but at most 20 % of itself (20).
    w = worstError(scored("far", 100.0, 30.0), kJudgeMaxError, &far);
    EXPECT_NEAR(w.excess, 30.0 / 20.0, 1e-12);
    EXPECT_EQ(nextJudgeSpp(64, w.excess, 1024, 1.0), 256);  // 64 · 2.25 = 144 -> 256
}

// judge.json records the estimate's spp, the rounds that chose it, and every score's SE.
// The JND figures (perception/JndVisibility.h) have standard errors by the same bootstrap: over
// 16 judge seeds at 256 spp, the region's JND moves by what one estimate's SE says (±45 %, as
// above); with one region the least visible kind's JND is that region's, SE included.
TEST(JudgeRounds, JndStandardErrorMatchesTheSpreadOverIndependentSeeds) {
    const GroovedPart part = groovedPart();
    const Scene* scene = part.scene.get();
    const std::vector<uint8_t>& labels = part.labels;
    const std::vector<double>& e = part.light;
    std::vector<double> jnd, seJnd;
    for (uint64_t k = 0; k < 16; ++k) {
        JudgeOptions o;
        o.spp = 256;
        o.seed = kJudgeSeed + 200 + k;
        o.viewing = viewingFor(*scene);
        const TransportSource est = judgeEstimate(*scene, o);
        const Judge judge(est, o, labels, {{255, "groove"}});
        const JudgeScore s = judge.scoreWithErrors(e, "random");
        ASSERT_TRUE(s.se);
        ASSERT_EQ(s.se->jnd.size(), 1u);
        ASSERT_TRUE(std::isfinite(s.visibility[0].jnd));
        jnd.push_back(s.visibility[0].jnd);
        seJnd.push_back(s.se->jnd[0]);
        EXPECT_EQ(s.se->leastVisibleJnd, s.se->jnd[0]);
    }
    EXPECT_GT(mean(jnd), 3.0 * sd(jnd)) << "the JND should be well away from its floor at 0";
    EXPECT_NEAR(sd(jnd) / mean(seJnd), 1.0, 0.45) << sd(jnd) << " vs " << mean(seJnd);
}

// The stop rule counts the figure the answer is chosen on: a least visible kind's JND whose SE
// is the largest relative error decides the rounds (its floor is one JND, the threshold).
TEST(JudgeRounds, TheLeastVisibleJndDecidesTheRoundsWhenItIsTheNoisiest) {
    JudgeScore s;
    s.name = "lamp";
    s.eq2.total = 1.0;
    s.unbiased.total = 1.0;
    s.brightness = 0.5;
    RegionVisibility scratch, pit;
    scratch.label = {1, "scratch"};
    pit.label = {2, "pit"};
    scratch.pixels = pit.pixels = 100;
    scratch.visibility = pit.visibility = 2.0;
    scratch.contrast = pit.contrast = 0.1;
    scratch.jnd = 5.0;
    pit.jnd = 2.0;  // the least visible kind
    s.visibility = {scratch, pit};
    JudgeScore::Errors e;
    e.replicates = kJudgeReplicates;
    e.eq2 = e.unbiased = 0.001;
    e.brightness = 0.0005;
    e.combinedVisibility = 0.002;
    e.visibility = {0.002, 0.002};
    e.contrast = {0.0001, 0.0001};
    e.jnd = {0.5, 0.002};
    e.leastVisibleJnd = 0.002;
    s.se = e;
    // The table prints each JND's error beside it: scratch 5 JND ± 0.5.
    EXPECT_NE(formatJudgeTable({s}).find("5.00 ±10.0%"), std::string::npos)
        << formatJudgeTable({s});
    // Quiet: within 1 %, whatever the most visible kind's JND does (it is not the answer's).
    EXPECT_LE(worstRelativeError(s).relative, kJudgeMaxError) << worstRelativeError(s).score;
    EXPECT_EQ(nextJudgeSpp(128, worstRelativeError(s).relative, 1024), 0);
    // Noisy: 0.1 JND on 2 is 5 %: it is the worst score, and the next round has 25 times the
    // samples (to the cap).
    s.se->leastVisibleJnd = 0.1;
    const WorstError w = worstRelativeError(s);
    EXPECT_DOUBLE_EQ(w.relative, 0.05);
    EXPECT_EQ(w.score, "lamp: JND pit");
    EXPECT_EQ(nextJudgeSpp(128, w.relative, 4096), 4096);
    // Below threshold the floor is one JND: 0.005 JND of error on 0.2 JND is 0.5 %, within 1 %.
    s.visibility[1].jnd = 0.2;
    s.se->leastVisibleJnd = 0.005;
    EXPECT_LE(worstRelativeError(s).relative, kJudgeMaxError);
    // Without a JND (no viewing model) the rule is as before.
    s.visibility[0].jnd = s.visibility[1].jnd = std::nan("");
    s.se->leastVisibleJnd = std::nan("");
    EXPECT_LE(worstRelativeError(s).relative, kJudgeMaxError);
}

// On a traced estimate: the same light and region, judged with a viewing model (its JND in the
// rule) and without. On this part the groove's JND (1.8) is the noisiest figure (4.7 % at 128 spp,
// measured; the visibility ratio and contrast 1.4 %): with a target of 3 % the rounds stop at
// once without it and trace more with it, until it is met.
TEST(JudgeRounds, TracesMoreWhenTheJndFigureIsNoisy) {
    const GroovedPart part = groovedPart();
    const Scene* scene = part.scene.get();
    std::vector<std::unique_ptr<TransportSource>> kept;
    std::unique_ptr<Judge> judge;
    bool withJnd = false;
    auto judgeAt = [&](int spp) -> const Judge& {
        JudgeOptions o;
        o.spp = spp;
        if (withJnd) o.viewing = viewingFor(*scene);
        judge.reset();
        kept.push_back(std::make_unique<TransportSource>(judgeEstimate(*scene, o)));
        judge = std::make_unique<Judge>(*kept.back(), o, part.labels,
                                        std::vector<RegionLabel>{{255, "groove"}});
        return *judge;
    };
    const double target = 0.03;
    const JudgedRounds without = judgeInRounds(judgeAt, {{"bands", part.light}}, 128, 4096, target);
    withJnd = true;
    const JudgedRounds with = judgeInRounds(judgeAt, {{"bands", part.light}}, 128, 4096, target);
    EXPECT_EQ(without.spp(), 128) << without.describe(target);
    EXPECT_TRUE(without.met);
    EXPECT_GT(with.spp(), 128) << with.describe(target);
    EXPECT_EQ(with.rounds.front().worst.score, "bands: JND groove") << with.describe(target);
    EXPECT_TRUE(with.met) << with.describe(target);
    ASSERT_TRUE(with.scores.at(0).se);
    EXPECT_LE(with.scores[0].se->leastVisibleJnd, target * with.scores[0].visibility[0].jnd);
}

TEST(JudgeRounds, JudgeJsonRecordsSppRoundsAndErrors) {
    test::TempDir dir("judge-rounds");
    const std::string part = (dir / "part.exr").string(), scene = (dir / "scene.json").string();
    ASSERT_EQ(test::runCli("gen-surface -o " + part + " --width 96 --height 96 --scene " + scene +
                           " --image-size 24 --spp 8 --max-depth 3")
                  .exitCode,
              0);
    const auto r =
        test::runCli("judge " + scene + " --truth " + (dir / "part-truth.png").string() +
                     " --cache " + (dir / "cache").string() + " -o " + (dir / "j").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("±"), std::string::npos) << r.output;  // the SE beside each score
    const nlohmann::json j = nlohmann::json::parse(test::readFile(dir / "j" / "judge.json"));
    const nlohmann::json& est = j.at("estimate");
    EXPECT_EQ(est.value("spp_rule", ""), "rounds");
    ASSERT_GE(est.at("rounds").size(), 1u);
    EXPECT_EQ(est.at("rounds").at(0).value("spp", 0), kJudgePilotSpp);
    EXPECT_EQ(est.value("spp", 0), est.at("rounds").back().value("spp", -1));
    EXPECT_LE(est.value("spp", 0), kJudgeDefaultSpp);
    for (const auto& l : j.at("lights")) {
        EXPECT_EQ(l.value("spp", 0), est.value("spp", -1));
        ASSERT_TRUE(l.contains("se")) << l.dump();
        EXPECT_TRUE(l["se"]["unbiased"].is_number());
        EXPECT_GT(l["se"]["unbiased"].get<double>(), 0.0);
        EXPECT_TRUE(l["se"]["brightness"].is_number());
        EXPECT_EQ(l["se"].value("replicates", 0), kJudgeReplicates);
        EXPECT_EQ(l["se"]["regions"].size(), l["visibility"].size());
        // The JND figures' errors (the scene's default viewing model gives every region a JND).
        EXPECT_TRUE(l["se"]["least_visible_jnd"].is_number()) << l["se"].dump();
        for (size_t k = 0; k < l["visibility"].size(); ++k)
            if (l["visibility"][k]["jnd"].is_number()) {
                EXPECT_TRUE(l["se"]["regions"][k]["jnd"].is_number()) << l["se"].dump();
            }
    }
    // Met, or at the cap: never stopped early with an error above the target.
    const double worst = est.at("rounds").back().value("worst_relative_se", 1.0);
    EXPECT_TRUE(worst <= kJudgeMaxError || est.value("spp", 0) == kJudgeDefaultSpp) << worst;
}

// The bootstrap's replicates run in parallel (core/WildBootstrap.h): replicate r's signs depend
// on (seed, r) only, so the errors are the same, bit for bit, on 1, 2 or 5 threads (a nonlinear
// score: a ratio of sums of squares); another seed gives other errors.
TEST(JudgeRounds, BootstrapErrorsAreTheSameOnAnyNumberOfThreads) {
    Pcg32 rng(5, 1);
    std::vector<HalfImages> images(2,
                                   HalfImages{std::vector<double>(300), std::vector<double>(300)});
    for (HalfImages& h : images)
        for (size_t p = 0; p < 300; ++p) {
            h.a[p] = 1.0 + rng.nextDouble();
            h.b[p] = 1.0 + rng.nextDouble();
        }
    const ReplicateScores scores = [](std::span<const HalfImages> r) {
        double ab = 0, w = 0, sum = 0;
        for (size_t p = 0; p < r[0].a.size(); ++p) {
            ab += r[0].a[p] * r[0].b[p];
            w += r[1].a[p] * r[1].a[p];
            sum += r[0].a[p] - r[1].b[p];
        }
        return std::vector<double>{ab / w, sum};
    };
    const std::vector<double> one = wildBootstrapErrors(images, 42, 33, scores, 1);
    ASSERT_EQ(one.size(), 2u);
    EXPECT_GT(one[0], 0.0);
    EXPECT_GT(one[1], 0.0);
    for (int threads : {2, 5}) {
        const std::vector<double> many = wildBootstrapErrors(images, 42, 33, scores, threads);
        EXPECT_EQ(many, one) << threads << " threads";
    }
    EXPECT_NE(wildBootstrapErrors(images, 43, 33, scores, 2), one);
    // A replicate that throws: the error reaches the caller.
    EXPECT_THROW(wildBootstrapErrors(
                     images, 42, 8,
                     [](std::span<const HalfImages>) -> std::vector<double> {
                         throw std::runtime_error("x");
                     },
                     2),
                 std::runtime_error);
}

// Each replicate is the wild bootstrap's perturbation exactly (core/WildBootstrap.h): pixel p of
// replicate r takes the signs of the p-th draw of Pcg32(mix64(seed ^ 0x5345), r), bit 0 for half
// a and bit 1 for half b, the same for every image, and adds sign · (a − b)/√2; the perturbed
// images equal, bit for bit, that rule applied pixel by pixel (on a size that is no multiple of
// the blocks the bootstrap draws its signs in).
TEST(JudgeRounds, BootstrapReplicatesAreTheRulesPerturbationBitForBit) {
    const size_t n = 2500;
    Pcg32 rng(9, 3);
    std::vector<HalfImages> images(3, HalfImages{std::vector<double>(n), std::vector<double>(n)});
    for (HalfImages& h : images)
        for (size_t p = 0; p < n; ++p) {
            h.a[p] = 0.3 + rng.nextDouble();
            h.b[p] = 0.3 + rng.nextDouble();
        }
    std::vector<std::vector<HalfImages>> seen;
    const int replicates = 5;
    const uint64_t seed = 77;
    wildBootstrapErrors(
        images, seed, replicates,
        [&](std::span<const HalfImages> r) {
            seen.emplace_back(r.begin(), r.end());
            return std::vector<double>{r[0].a[0]};
        },
        1);
    ASSERT_EQ(seen.size(), static_cast<size_t>(replicates));
    for (int rep = 0; rep < replicates; ++rep) {
        Pcg32 signs(mix64(seed ^ 0x5345ULL), static_cast<uint64_t>(rep));
        size_t differ = 0;
        for (size_t p = 0; p < n; ++p) {
            const uint32_t bits = signs.nextU32();
            const double sa = bits & 1u ? 1.0 : -1.0, sb = bits & 2u ? 1.0 : -1.0;
            for (size_t k = 0; k < images.size(); ++k) {
                const double d = (images[k].a[p] - images[k].b[p]) * std::sqrt(0.5);
                differ += seen[rep][k].a[p] != images[k].a[p] + sa * d;
                differ += seen[rep][k].b[p] != images[k].b[p] + sb * d;
            }
        }
        EXPECT_EQ(differ, 0u) << "replicate " << rep;
    }
}

// The JND figures' errors on one bank of band filters for every replicate, on every core: the
// same numbers as the serial bootstrap that built a bank per replicate (each region's JND and
// its error, bit for bit, on 1 and 3 threads), and the same seed gives the same numbers.
TEST(JudgeRounds, JndErrorsOnASharedBankAndThreadsAreTheSerialOnes) {
    const GroovedPart part = groovedPart();
    JudgeOptions o;
    o.spp = 64;
    o.viewing = viewingFor(*part.scene);
    const TransportSource est = judgeEstimate(*part.scene, o);
    std::vector<JudgeScore> scores;
    for (int threads : {1, 3}) {
        o.threads = threads;
        const Judge judge(est, o, part.labels, {{255, "groove"}});
        scores.push_back(judge.scoreWithErrors(part.light, "bands"));
    }
    ASSERT_TRUE(scores[0].se && scores[1].se);
    ASSERT_EQ(scores[0].se->jnd.size(), 1u);
    EXPECT_TRUE(std::isfinite(scores[0].se->jnd[0]));
    EXPECT_GT(scores[0].se->jnd[0], 0.0);
    EXPECT_EQ(scores[1].se->jnd, scores[0].se->jnd);
    EXPECT_EQ(scores[1].se->leastVisibleJnd, scores[0].se->leastVisibleJnd);
    EXPECT_EQ(scores[1].se->visibility, scores[0].se->visibility);
    EXPECT_EQ(scores[1].se->unbiased, scores[0].se->unbiased);
    // The serial bootstrap as it was: a bank built anew in every replicate's JND.
    const TransportMatrix& t = est.file.matrix;
    const size_t n = t.rows();
    std::vector<HalfImages> images(2, HalfImages{std::vector<double>(n), std::vector<double>(n)});
    t.applyLuminanceHalves(part.light, images[0].a, images[0].b);
    const std::vector<double> ones(part.light.size(), 1.0);
    t.applyLuminanceHalves(ones, images[1].a, images[1].b);
    const std::vector<uint8_t>& mask = t.objectMask;
    const auto partPixels =
        static_cast<double>(std::count_if(mask.begin(), mask.end(), [](uint8_t m) { return m; }));
    const std::vector<double> serial = wildBootstrapErrors(
        images, o.seed, kJudgeReplicates,
        [&](std::span<const HalfImages> r) {
            double white = 0;
            for (size_t p = 0; p < n; ++p)
                if (mask[p]) white += 0.5 * (r[1].a[p] + r[1].b[p]);
            const JndViewing viewing{*o.viewing, white / partPixels};
            const std::vector<RegionVisibility> v =
                defectVisibility(t.width, t.height, r[0].a, r[0].b, mask, part.labels,
                                 {{255, "groove"}}, {}, &viewing);
            return std::vector<double>{v.at(0).jnd};
        },
        1);
    EXPECT_EQ(serial.at(0), scores[0].se->jnd[0]);
}

// The rounds start at kJudgePilotSpp (32): the rule may stop there only if the SE still
// predicts how far an estimate at that spp moves. Over 16 judge seeds at the pilot's spp, the
// scores' spread against the mean SE (as at 256 spp above), for U, eq. 2 and the brightness.
// Measured on this scene with the bootstrap: within the bound at 64 and 128 spp; at 32 spp not
// (U's SE 2.1× its spread, now the delta method's, below; eq. 2's 0.55×, now doubled below
// 64 spp: Judge.h kJudgeLowSppInflation).
TEST(JudgeRounds, StandardErrorHoldsAtThePilotSpp) {
    auto scene = wavyScene(32);
    const std::vector<double> e = randomLight(1250, 13);
    const std::vector<JudgeScore> scores = scoresOverSeeds(*scene, e, kJudgePilotSpp, 300);
    for (const JudgeScore& s : scores) ASSERT_TRUE(s.se);
    expectSpreadMatchesErrors(scores);
}

// U's SE is the delta method's on the halves' product (objective/UnbiasedObjective.h
// lossStandardError), not the bootstrap's, which perturbs noisy differences and over-states it
// where the noise's square counts (at 32 spp on this scene: 2.1× the spread). Over 16 judge seeds
// at 16 and 32 spp, U's spread against its mean SE, within ±45 % (as above).
TEST(JudgeRounds, UStandardErrorHoldsAtAFewSpp) {
    auto scene = wavyScene(32);
    const std::vector<double> e = randomLight(1250, 13);
    for (int spp : {16, 32}) {
        std::vector<double> u, se;
        for (const JudgeScore& s : scoresOverSeeds(*scene, e, spp, 500)) {
            ASSERT_TRUE(s.se);
            u.push_back(s.unbiased.total);
            se.push_back(s.se->unbiased);
        }
        std::printf("[ measured ] %d spp: U's spread %.4g, its mean SE %.4g (%.2fx)\n", spp, sd(u),
                    mean(se), mean(se) / sd(u));
        EXPECT_NEAR(sd(u) / mean(se), 1.0, 0.45) << spp << " spp: " << sd(u) << " vs " << mean(se);
    }
}

namespace {

/// Y_a, Y_b of E through a two-plane estimate.
HalfImages halvesOf(const TransportMatrix& t, const std::vector<double>& e) {
    HalfImages h{std::vector<double>(t.rows()), std::vector<double>(t.rows())};
    t.applyLuminanceHalves(e, h.a, h.b);
    return h;
}

}  // namespace

// A round extends the estimate before it (app/pipeline/Transport.h transportInDoublings): at
// 4× the base spp the estimate is the base estimate, a chunk of base spp and a chunk of 2× base
// spp, each half the mean of the same half of its pieces (so half a never holds half b's
// samples), every chunk on a seed of its own (not the estimate's, not the other chunk's, not a
// training, validation or judge seed); a round at 2n after one at n traces n samples, not 2n
// (no fresh trace at 4× base appears in the cache); the same options give the same numbers,
// from the cache too.
TEST(JudgeRounds, ARoundExtendsTheEstimateBeforeIt) {
    test::TempDir dir("doublings");
    auto scene = wavyScene(16);
    PrecomputeOptions o;
    o.sampleSets = 2;
    o.seed = kJudgeSeed;
    auto at = [&](int spp, uint64_t seed) {
        PrecomputeOptions x = o;
        x.spp = spp;
        x.seed = seed;
        return x;
    };
    const TransportSource half = transportInDoublings(*scene, at(16, kJudgeSeed), 8, dir.path());
    const TransportSource whole = transportInDoublings(*scene, at(32, kJudgeSeed), 8, dir.path());
    EXPECT_EQ(whole.file.provenance.spp, 32);
    EXPECT_EQ(whole.file.provenance.seed, kJudgeSeed);
    const uint64_t s8 = doublingSeed(kJudgeSeed, 8), s16 = doublingSeed(kJudgeSeed, 16);
    for (uint64_t s : {s8, s16}) {
        EXPECT_NE(s, kJudgeSeed);
        EXPECT_GT(s, uint64_t{1} << 32);  // no training seed a user can reach
        EXPECT_NE(s, kJudgeSeed + kValidationSeedOffset);
    }
    EXPECT_NE(s8, s16);
    // The pieces, traced on their own (cache hits).
    const TransportSource base = transportForScene(*scene, at(8, kJudgeSeed), dir.path());
    const TransportSource c8 = transportForScene(*scene, at(8, s8), dir.path());
    const TransportSource c16 = transportForScene(*scene, at(16, s16), dir.path());
    EXPECT_TRUE(base.cacheHit && c8.cacheHit && c16.cacheHit);
    const std::vector<double> e = randomLight(1250, 21);
    const HalfImages w = halvesOf(whole.file.matrix, e), b = halvesOf(base.file.matrix, e),
                     x = halvesOf(c8.file.matrix, e), y = halvesOf(c16.file.matrix, e);
    double worst = 0, scale = 0;
    for (size_t p = 0; p < w.a.size(); ++p) {
        worst = std::max(worst, std::abs(w.a[p] - (0.25 * (b.a[p] + x.a[p]) + 0.5 * y.a[p])));
        worst = std::max(worst, std::abs(w.b[p] - (0.25 * (b.b[p] + x.b[p]) + 0.5 * y.b[p])));
        scale = std::max({scale, std::abs(w.a[p]), std::abs(w.b[p])});
    }
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(worst, 1e-5 * scale);
    // A pixel is on the part where every piece says so.
    for (size_t p = 0; p < w.a.size(); ++p)
        EXPECT_EQ(whole.file.matrix.objectMask[p], base.file.matrix.objectMask[p] &&
                                                       c8.file.matrix.objectMask[p] &&
                                                       c16.file.matrix.objectMask[p]);
    // No fresh trace at 32 spp: the cache holds the base, two chunks and the two means.
    const TransportProvenance fresh =
        transportProvenance(*scene, traceOptions(*scene, at(32, kJudgeSeed)), 1);
    EXPECT_FALSE(std::filesystem::exists(dir.path() / ("transport-" + fresh.fingerprint + ".tm")));
    size_t files = 0;
    for (const auto& f : std::filesystem::directory_iterator(dir.path()))
        files += f.path().extension() == ".tm";
    EXPECT_EQ(files, 5u);
    EXPECT_NE(half.file.provenance.fingerprint, whole.file.provenance.fingerprint);
    // The same options, the same numbers: from the cache, and traced anew without one.
    const TransportSource again = transportInDoublings(*scene, at(32, kJudgeSeed), 8, dir.path());
    EXPECT_TRUE(again.cacheHit);
    EXPECT_EQ(again.file.matrix.values, whole.file.matrix.values);
    const TransportSource uncached = transportInDoublings(*scene, at(32, kJudgeSeed), 8, {});
    EXPECT_EQ(uncached.file.matrix.values, whole.file.matrix.values);
    EXPECT_EQ(uncached.file.provenance.fingerprint, whole.file.provenance.fingerprint);
    // An spp of no form base·2^k is one trace.
    const TransportSource odd = transportInDoublings(*scene, at(24, kJudgeSeed), 8, {});
    EXPECT_EQ(odd.file.provenance.fingerprint,
              transportProvenance(*scene, traceOptions(*scene, at(24, kJudgeSeed)), 1).fingerprint);
}

// The mean of two estimates: each entry the mean of the two (a texel only one of them reached
// at half its value), dense or sparse alike; estimates of another shape are refused.
TEST(JudgeRounds, TheMeanOfTwoEstimatesIsTheirEntriesMean) {
    auto scene = wavyScene(12);
    PrecomputeOptions o;
    o.sampleSets = 2;
    o.spp = 8;
    o.seed = 3;
    const TransportSource a = transportForScene(*scene, o, {});
    o.seed = 4;
    const TransportSource b = transportForScene(*scene, o, {});
    TransportMatrix da = a.file.matrix, db = b.file.matrix;
    da.toDense();
    db.toDense();
    TransportMatrix m = meanOfEstimates(a.file.matrix, db);
    m.toDense();
    ASSERT_EQ(m.values.size(), da.values.size());
    for (size_t k = 0; k < m.values.size(); ++k)
        EXPECT_FLOAT_EQ(m.values[k], 0.5f * (da.values[k] + db.values[k])) << k;
    TransportMatrix other = a.file.matrix;
    other.planes = 1;
    EXPECT_THROW(meanOfEstimates(a.file.matrix, other), std::invalid_argument);
}

namespace {

double gauss(Pcg32& rng) {
    const double u1 = std::max(rng.nextDouble(), 1e-300), u2 = rng.nextDouble();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
}

/// A synthetic estimate of known noise (the judge's rounds without a tracer): a 16×16 image
/// fully in the part, three texels, texel c's column a checkerboard μ_c = 1 ± A_c, and at
/// spp n each half's entry μ + (σ_c·sqrt(2/n))·z with z standard normal (a half is the mean of
/// n/2 samples of standard deviation σ_c), fresh for every spp (seeded by it). The light e_c
/// (texel c alone) has half images μ_c + noise, so with λ 0 its U = sqrt(S/G_u) with G_u =
/// Y_aᵀ·M·Y_b (M: the grid's Laplacian) of known variance 2s²·|Mμ|² + s⁴·tr(M²) (s: a half's
/// standard deviation), and by the delta method SE(U) = U·SE(G_u)/(2·G). On a checkerboard
/// eq. 2 (S/Σ|ΔȲ|, no difference near 0 at these s) has the same first-order relative SE,
/// s·sqrt(Σ deg²/2)/(2A·pairs), and the brightness a far smaller one.
struct KnownNoise {
    static constexpr int kSide = 16;
    std::vector<double> amplitude, sigma;  // per texel
    std::vector<std::unique_ptr<TransportSource>> kept;
    std::unique_ptr<Judge> judge;
    JudgeOptions options;

    KnownNoise() { options.objective.lambda = 0; }
    static std::vector<double> mu(double a) {
        std::vector<double> m(size_t(kSide) * kSide);
        for (int y = 0; y < kSide; ++y)
            for (int x = 0; x < kSide; ++x) m[size_t(y) * kSide + x] = (x + y) % 2 ? 1 - a : 1 + a;
        return m;
    }
    /// Σ_pairs (Δμ)², |Mμ|², tr(M²) on the grid (right and down neighbours).
    struct Forms {
        double g = 0, mmu2 = 0, trace = 0;
    };
    static Forms forms(const std::vector<double>& m) {
        Forms f;
        for (int y = 0; y < kSide; ++y)
            for (int x = 0; x < kSide; ++x) {
                const size_t p = size_t(y) * kSide + x;
                double lap = 0;
                int deg = 0;
                auto nb = [&](int qx, int qy) {
                    if (qx < 0 || qy < 0 || qx >= kSide || qy >= kSide) return;
                    lap += m[p] - m[size_t(qy) * kSide + qx];
                    ++deg;
                };
                nb(x + 1, y), nb(x - 1, y), nb(x, y + 1), nb(x, y - 1);
                f.mmu2 += lap * lap;
                f.trace += double(deg) * deg + deg;
                if (x + 1 < kSide) f.g += std::pow(m[p + 1] - m[p], 2);
                if (y + 1 < kSide) f.g += std::pow(m[p + kSide] - m[p], 2);
            }
        return f;
    }
    /// U's relative standard error of light e_c at spp (the formula above).
    double relativeError(size_t c, int spp) const {
        const Forms f = forms(mu(amplitude[c]));
        const double s = sigma[c] * std::sqrt(2.0 / spp);
        return 0.5 * std::sqrt(2 * s * s * f.mmu2 + std::pow(s, 4) * f.trace) / f.g;
    }
    /// The per-sample σ that gives U of e_c a relative SE of r at spp (the quadratic in s²).
    void setError(size_t c, double r, int spp) {
        const Forms f = forms(mu(amplitude[c]));
        const double rhs = std::pow(2 * r * f.g, 2);
        const double s2 =
            (-2 * f.mmu2 + std::sqrt(4 * f.mmu2 * f.mmu2 + 4 * f.trace * rhs)) / (2 * f.trace);
        sigma[c] = std::sqrt(s2) / std::sqrt(2.0 / spp);
    }
    std::vector<double> light(size_t c) const {
        std::vector<double> e(amplitude.size(), 0.0);
        e[c] = 1;
        return e;
    }
    const Judge& at(int spp) {
        Pcg32 rng(0x5eed + uint64_t(spp), 7);
        auto src = std::make_unique<TransportSource>();
        TransportMatrix& t = src->file.matrix;
        t.width = t.height = kSide;
        t.envWidth = static_cast<int>(amplitude.size());
        t.envHeight = 1;
        t.planes = 2;
        t.storage = TransportStorage::Dense;
        t.objectMask.assign(t.rows(), 1);
        t.values.resize(t.rows() * t.cols() * 2);
        for (size_t c = 0; c < t.cols(); ++c) {
            const std::vector<double> m = mu(amplitude[c]);
            const double s = sigma[c] * std::sqrt(2.0 / spp);
            for (size_t p = 0; p < t.rows(); ++p)
                for (int h = 0; h < 2; ++h)
                    t.values[(p * t.cols() + c) * 2 + h] =
                        static_cast<float>(m[p] + s * gauss(rng));
        }
        src->file.provenance.spp = spp;
        judge.reset();
        kept.push_back(std::move(src));
        judge = std::make_unique<Judge>(*kept.back(), options);
        return *judge;
    }
};

}  // namespace

// The rounds on an estimate whose variance is known (KnownNoise), optimize's rule (the answer
// first, the others references): U's SE is known at every spp, so where the rounds stop is too.
// - It stops early: the answer's U has a 0.5 % SE at the 64-spp pilot, the lamp's 3 %, but the
//   lamp's U is 3× the answer's, so a tenth of the gap (6.7 % of it) decides it: one round.
//   Every score held to 1 % (the rule before references) must trace to 1024 for the lamp
//   (64·3² = 576, the next power of two), where its SE is 0.75 %.
// - It must go further: the answer's U has a 2.4 % SE at 64 spp, so 64·2.4² = 369 -> 512 spp in
//   one step (256 would leave 1.2 %: that round is skipped), where it is 0.85 %: met.
// - A reference 3.4 % from the answer with a 3 % SE: a tenth of the gap is below 1 % of itself,
//   so 1 % it is, and the rounds go to the references' most (128 spp: 2.1 %) and no further; the
//   comparison is said not decided.
// Each round's SE of the deciding score is the known one within ±20 % (U's by the delta method,
// eq. 2's by the bootstrap, from one estimate's halves).
TEST(JudgeRounds, RoundsOnAnEstimateOfKnownNoiseStopWhereItsVarianceSays) {
    KnownNoise k;
    k.amplitude = {0.3, 0.1, 0.29};  // answer, lamp (U 3× the answer's), a near reference
    k.sigma.assign(3, 0);
    k.setError(0, 0.005, 64);
    k.setError(1, 0.03, 64);
    k.setError(2, 0.03, 64);
    EXPECT_NEAR(k.relativeError(1, 1024), 0.0075, 0.0005);  // ~1/sqrt(16) of 3 %
    auto judgeAt = [&](int spp) -> const Judge& { return k.at(spp); };
    JudgeStopRule rule;
    rule.againstFirst = true;
    auto seOf = [](const JudgedRounds& r, size_t light) {
        return r.scores[light].se->unbiased / r.scores[light].unbiased.total;
    };

    // Stops early: one round.
    const JudgedRounds early =
        judgeInRounds(judgeAt, {{"answer", k.light(0)}, {"lamp", k.light(1)}}, 64, 1024, rule);
    ASSERT_EQ(early.scores.size(), 2u);
    EXPECT_NEAR(early.scores[1].unbiased.total / early.scores[0].unbiased.total, 3.0, 0.1);
    EXPECT_TRUE(early.met) << early.describe();
    EXPECT_EQ(early.spp(), 64) << early.describe();
    EXPECT_NEAR(seOf(early, 0) / k.relativeError(0, 64), 1.0, 0.2);
    EXPECT_NEAR(seOf(early, 1) / k.relativeError(1, 64), 1.0, 0.2);
    EXPECT_TRUE(early.rounds[0].references.byGap);
    EXPECT_EQ(early.rounds[0].references.score.rfind("lamp: ", 0), 0u);
    // The same lights, every score held to 1 %: to the cap, met there.
    const JudgedRounds all =
        judgeInRounds(judgeAt, {{"answer", k.light(0)}, {"lamp", k.light(1)}}, 64, 1024);
    ASSERT_EQ(all.rounds.size(), 2u) << all.describe();
    EXPECT_EQ(all.spp(), 1024);
    EXPECT_EQ(all.rounds[0].worst.score.rfind("lamp: ", 0), 0u);
    EXPECT_TRUE(all.met) << all.describe();
    EXPECT_NEAR(seOf(all, 1) / k.relativeError(1, 1024), 1.0, 0.2);

    // Must go further: 64 -> 512.
    k.setError(0, 0.024, 64);
    EXPECT_GT(k.relativeError(0, 256), 0.01);
    EXPECT_LT(k.relativeError(0, 512), 0.0085);
    const JudgedRounds further =
        judgeInRounds(judgeAt, {{"answer", k.light(0)}, {"lamp", k.light(1)}}, 64, 1024, rule);
    ASSERT_EQ(further.rounds.size(), 2u) << further.describe();
    EXPECT_EQ(further.rounds[0].spp, 64);
    EXPECT_EQ(further.rounds[0].answer.score.rfind("answer: ", 0), 0u);  // U or eq. 2
    EXPECT_NEAR(further.rounds[0].answer.relative / k.relativeError(0, 64), 1.0, 0.2);
    EXPECT_EQ(further.spp(), 512);
    EXPECT_TRUE(further.met) << further.describe();
    EXPECT_NEAR(seOf(further, 0) / k.relativeError(0, 512), 1.0, 0.2);

    // A near reference: to the references' most, not decided, said.
    k.setError(0, 0.005, 64);
    const JudgedRounds near =
        judgeInRounds(judgeAt, {{"answer", k.light(0)}, {"paper", k.light(2)}}, 64, 1024, rule);
    EXPECT_EQ(near.spp(), kJudgeReferenceMaxSpp) << near.describe();
    EXPECT_FALSE(near.met);
    EXPECT_FALSE(near.rounds.back().references.byGap);
    EXPECT_NEAR(seOf(near, 1) / k.relativeError(2, kJudgeReferenceMaxSpp), 1.0, 0.2);
    EXPECT_NE(near.describe().find("not decided"), std::string::npos) << near.describe();
}

// The 32-spp pilot (Judge.h kJudgePilotSpp, kJudgeBootstrapFullSpp): below 64 spp eq. 2's
// bootstrap SE is doubled, U's delta-method SE and the brightness's are not. Exactly: the same
// estimate read as 32 spp and as 64 spp gives eq. 2's SE in the ratio 2, the others equal. On
// an estimate of known noise (KnownNoise: eq. 2's first-order relative SE is U's; the bootstrap
// reads it ~0.66× at 32 spp here) a 32-spp round thus stops only where eq. 2's bootstrap SE is
// within half the target: U at 0.9 % (eq. 2 read ~1.2 %) goes on to 64 spp (a trace at the
// doubling base, not an extension of the pilot), where U is ~0.64 %: met; U at 0.3 % stops at 32.
TEST(JudgeRounds, AThirtyTwoSppPilotHoldsTheBootstrapsErrorsToHalfTheTarget) {
    static_assert(kJudgePilotSpp == 32 && kJudgeBootstrapFullSpp == 64 && kJudgeDoublingBase == 64);
    KnownNoise k;
    k.amplitude = {0.3};
    k.sigma.assign(1, 0);
    k.setError(0, 0.009, 32);
    const Judge& at32 = k.at(32);
    const JudgeScore s32 = at32.scoreWithErrors(k.light(0), "answer");
    TransportSource as64 = *k.kept.back();
    as64.file.provenance.spp = 64;
    const JudgeScore s64 = Judge(as64, k.options).scoreWithErrors(k.light(0), "answer");
    ASSERT_TRUE(s32.se && s64.se);
    EXPECT_EQ(s32.spp, 32);
    EXPECT_EQ(s64.spp, 64);
    EXPECT_EQ(s32.eq2.total, s64.eq2.total);
    EXPECT_EQ(s32.se->eq2, kJudgeLowSppInflation * s64.se->eq2);
    EXPECT_EQ(s32.se->brightness, s64.se->brightness);
    EXPECT_EQ(s32.se->unbiased, s64.se->unbiased);
    EXPECT_NEAR(s32.se->unbiased / s32.unbiased.total / k.relativeError(0, 32), 1.0, 0.2);

    auto judgeAt = [&](int spp) -> const Judge& { return k.at(spp); };
    const JudgedRounds further = judgeInRounds(judgeAt, {{"answer", k.light(0)}}, 32, 1024);
    ASSERT_EQ(further.rounds.size(), 2u) << further.describe();
    EXPECT_EQ(further.rounds[0].worst.score, "answer: eq2");
    EXPECT_GT(further.rounds[0].worst.relative, kJudgeMaxError);
    EXPECT_LT(further.rounds[0].worst.relative / kJudgeLowSppInflation, kJudgeMaxError);
    EXPECT_EQ(further.spp(), 64);
    EXPECT_TRUE(further.met) << further.describe();

    k.setError(0, 0.003, 32);
    const JudgedRounds early = judgeInRounds(judgeAt, {{"answer", k.light(0)}}, 32, 1024);
    EXPECT_EQ(early.spp(), 32) << early.describe();
    EXPECT_TRUE(early.met) << early.describe();
}
