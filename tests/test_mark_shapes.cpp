// The defect map's marks told apart by shape (detect/MarkShapes.h), and the labels the judge
// scores a defect region by (app/pipeline/Truth.h judgedDefectLabels).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "app/pipeline/Truth.h"
#include "detect/Extent.h"
#include "detect/MarkShapes.h"

namespace {

using namespace sl;

TEST(MarkShapes, ALineIsALineWhateverItsDirectionASpotIsASpot) {
    const int W = 64, H = 48;
    std::vector<uint8_t> map(static_cast<size_t>(W) * H, 0);
    auto set = [&](int x, int y) { map[static_cast<size_t>(y) * W + x] = 255; };
    // a scratch 30 long and 2 wide along x: an axis-aligned bar's elongation is its length over
    // its width (each sample a unit square), 15
    for (int x = 2; x < 32; ++x)
        for (int y = 3; y < 5; ++y) set(x, y);
    // a diagonal one-sample line of 12 (8-connected)
    for (int k = 0; k < 12; ++k) set(40 + k, 10 + k);
    // a disc of radius 5: a spot
    for (int y = 20; y <= 30; ++y)
        for (int x = 10; x <= 20; ++x)
            if ((x - 15) * (x - 15) + (y - 25) * (y - 25) <= 25) set(x, y);
    // a 5 x 2 bar: elongation 2.5, under 3: a spot
    for (int x = 40; x < 45; ++x)
        for (int y = 40; y < 42; ++y) set(x, y);
    // a 7 x 2 bar: 3.5, a line
    for (int x = 50; x < 57; ++x)
        for (int y = 40; y < 42; ++y) set(x, y);
    const std::vector<uint8_t> labels = labelMarksByShape(map, W, H);
    ASSERT_EQ(labels.size(), map.size());
    auto at = [&](int x, int y) { return labels[static_cast<size_t>(y) * W + x]; };
    EXPECT_EQ(at(2, 3), kMarkLine);
    EXPECT_EQ(at(31, 4), kMarkLine);
    EXPECT_EQ(at(40, 10), kMarkLine);
    EXPECT_EQ(at(51, 21), kMarkLine);
    EXPECT_EQ(at(15, 25), kMarkSpot);
    EXPECT_EQ(at(10, 25), kMarkSpot);
    EXPECT_EQ(at(42, 41), kMarkSpot);
    EXPECT_EQ(at(53, 40), kMarkLine);
    // every marked sample is labelled, nothing else
    for (size_t k = 0; k < map.size(); ++k) EXPECT_EQ(labels[k] != 0, map[k] != 0) << k;
    // the bars' elongations as Extent gives them (a sample a unit square)
    std::vector<size_t> bar;
    for (int x = 40; x < 45; ++x)
        for (int y = 40; y < 42; ++y) bar.push_back(static_cast<size_t>(y) * W + x);
    EXPECT_NEAR(extentOf(bar, W).elongation, 2.5, 1e-12);
    // the same marks turned a quarter: the same labels, turned
    std::vector<uint8_t> turned(map.size(), 0);
    const int W2 = H, H2 = W;  // (x, y) -> (H-1-y, x)
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            turned[static_cast<size_t>(x) * W2 + (H - 1 - y)] = map[static_cast<size_t>(y) * W + x];
    const std::vector<uint8_t> labels2 = labelMarksByShape(turned, W2, H2);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            EXPECT_EQ(labels2[static_cast<size_t>(x) * W2 + (H - 1 - y)], at(x, y));
    EXPECT_THROW(labelMarksByShape(map, W + 1, H), std::invalid_argument);
}

TEST(MarkShapes, TheJudgeScoresTheMapsMarksByShapeAndAnyOtherRegionAsOne) {
    const std::vector<uint8_t> defects = {0, kMarkLine, kMarkLine, 0, kMarkSpot};
    const JudgedDefectLabels byShape = judgedDefectLabels(defects, true);
    EXPECT_EQ(byShape.labels, defects);
    ASSERT_EQ(byShape.legend.size(), 2u);
    EXPECT_EQ(byShape.legend[0].value, kMarkLine);
    EXPECT_EQ(byShape.legend[0].name, "lines");
    EXPECT_EQ(byShape.legend[1].value, kMarkSpot);
    EXPECT_EQ(byShape.legend[1].name, "spots");
    // only the shapes present are named
    const JudgedDefectLabels linesOnly =
        judgedDefectLabels(std::vector<uint8_t>{0, kMarkLine}, true);
    ASSERT_EQ(linesOnly.legend.size(), 1u);
    EXPECT_EQ(linesOnly.legend[0].name, "lines");
    // a mask (or a truth's labels picked as one region): one region "defects"
    const JudgedDefectLabels one = judgedDefectLabels(std::vector<uint8_t>{0, 250, 7, 0}, false);
    EXPECT_EQ(one.labels, (std::vector<uint8_t>{0, 255, 255, 0}));
    ASSERT_EQ(one.legend.size(), 1u);
    EXPECT_EQ(one.legend[0].name, "defects");
}

}  // namespace
