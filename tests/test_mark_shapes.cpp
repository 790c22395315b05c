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
    // the disc (81 samples) is more than 8x the shape's lower median, the 5x2 bar's 10: a large
    // spot (next test)
    EXPECT_EQ(at(15, 25), kMarkLargeSpot);
    EXPECT_EQ(at(10, 25), kMarkLargeSpot);
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

TEST(MarkShapes, AMarkManyTimesItsShapesMedianIsLabelledApart) {
    const int W = 120, H = 60;
    std::vector<uint8_t> map(static_cast<size_t>(W) * H, 0);
    auto box = [&](int x0, int y0, int w, int h) {
        for (int y = y0; y < y0 + h; ++y)
            for (int x = x0; x < x0 + w; ++x) map[static_cast<size_t>(y) * W + x] = 255;
    };
    // spots: four of 3x3 (9 samples), one of 8x9 (72 = 8 x 9, not more: a spot), one of 9x9
    // (81 > 72: a large spot); the lower median is 9
    for (int k = 0; k < 4; ++k) box(2 + 5 * k, 2, 3, 3);
    box(30, 2, 8, 9);
    box(45, 2, 9, 9);
    // lines: three of 8x1 (8 samples), one of 60x2 (120 > 8 x 8: a large line)
    for (int k = 0; k < 3; ++k) box(2 + 12 * k, 20, 8, 1);
    box(2, 30, 60, 2);
    const std::vector<uint8_t> labels = labelMarksByShape(map, W, H);
    auto at = [&](int x, int y) { return labels[static_cast<size_t>(y) * W + x]; };
    for (int k = 0; k < 4; ++k) EXPECT_EQ(at(3 + 5 * k, 3), kMarkSpot) << k;
    EXPECT_EQ(at(31, 3), kMarkSpot);
    EXPECT_EQ(at(46, 3), kMarkLargeSpot);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(at(3 + 12 * k, 20), kMarkLine) << k;
    EXPECT_EQ(at(30, 31), kMarkLargeLine);
    for (size_t k = 0; k < map.size(); ++k) EXPECT_EQ(labels[k] != 0, map[k] != 0) << k;
    // of two marks of a shape, the smaller is the median: the larger, 8x as large or more, apart
    std::vector<uint8_t> two(static_cast<size_t>(W) * H, 0);
    for (int y = 2; y < 5; ++y)
        for (int x = 2; x < 5; ++x) two[static_cast<size_t>(y) * W + x] = 1;  // 9
    for (int y = 20; y < 30; ++y)
        for (int x = 20; x < 30; ++x) two[static_cast<size_t>(y) * W + x] = 1;  // 100
    const std::vector<uint8_t> twoLabels = labelMarksByShape(two, W, H);
    EXPECT_EQ(twoLabels[static_cast<size_t>(3) * W + 3], kMarkSpot);
    EXPECT_EQ(twoLabels[static_cast<size_t>(25) * W + 25], kMarkLargeSpot);
    // marks all alike: none apart
    std::vector<uint8_t> alike(static_cast<size_t>(W) * H, 0);
    for (int k = 0; k < 6; ++k)
        for (int y = 2; y < 6; ++y)
            for (int x = 2 + 8 * k; x < 6 + 8 * k; ++x) alike[static_cast<size_t>(y) * W + x] = 1;
    for (const uint8_t v : labelMarksByShape(alike, W, H)) EXPECT_TRUE(v == 0 || v == kMarkSpot);
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
    // the large marks' labels are named too, in the legend's order
    const JudgedDefectLabels large =
        judgedDefectLabels(std::vector<uint8_t>{kMarkLargeSpot, kMarkSpot, kMarkLargeLine}, true);
    ASSERT_EQ(large.legend.size(), 3u);
    EXPECT_EQ(large.legend[0].name, "spots");
    EXPECT_EQ(large.legend[1].name, "large lines");
    EXPECT_EQ(large.legend[2].name, "large spots");
    for (const RegionLabel& l : markShapeLegend()) EXPECT_TRUE(isMarkShapeLabel(l.value));
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
