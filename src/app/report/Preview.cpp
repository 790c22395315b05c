#include "app/report/Preview.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "detect/DefectMap.h"
#include "io/ImageIO.h"

namespace sl {

void writeRender(const std::filesystem::path& exr, const std::vector<double>& image, int width,
                 int height, int channels) {
    Image img(width, height, channels);
    for (size_t i = 0; i < image.size(); ++i) img.data[i] = static_cast<float>(image[i]);
    writeExr(exr, img);
    auto png = exr;
    png.replace_extension(".png");
    writePng(png, img);
}

double exposureScale(const std::vector<double>& y, const std::vector<uint8_t>& part) {
    std::vector<double> in;
    for (size_t p = 0; p < y.size(); ++p)
        if (part.empty() || part[p]) in.push_back(y[p]);
    if (in.empty()) return 1.0;
    auto q = in.begin() + static_cast<std::ptrdiff_t>(0.99 * static_cast<double>(in.size() - 1));
    std::nth_element(in.begin(), q, in.end());
    return *q > 0 ? 0.8 / *q : 1.0;
}

namespace {

constexpr OutlineColour kOutlines[] = {
    {255, 1.0f, 0.0f, 0.0f, "red"},     {224, 1.0f, 0.45f, 0.0f, "orange"},
    {192, 1.0f, 0.0f, 1.0f, "magenta"}, {160, 1.0f, 1.0f, 0.0f, "yellow"},
    {144, 0.0f, 1.0f, 1.0f, "cyan"},    {128, 0.1f, 0.3f, 1.0f, "blue"},
};

}  // namespace

std::span<const OutlineColour> outlineColours() {
    return kOutlines;
}

const OutlineColour& outlineOf(uint8_t v) {
    static constexpr OutlineColour white{0, 1.0f, 1.0f, 1.0f, "white"};
    for (const OutlineColour& c : kOutlines)
        if (c.value == v) return c;
    return white;
}

Image outlinedRender(const std::vector<double>& y, int w, int h, const std::vector<uint8_t>& part,
                     const std::vector<uint8_t>& labels) {
    const double scale = exposureScale(y, part);
    Image img(w, h, 3);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const size_t p = static_cast<size_t>(j) * w + i;
            const float v = static_cast<float>(y[p] * scale);
            float rgb[3] = {v, v, v};
            const uint8_t l = labels.empty() ? 0 : labels[p];
            if (l) {
                auto other = [&](int x, int z) {
                    return x < 0 || z < 0 || x >= w || z >= h ||
                           labels[static_cast<size_t>(z) * w + x] != l;
                };
                if (other(i - 1, j) || other(i + 1, j) || other(i, j - 1) || other(i, j + 1)) {
                    const OutlineColour& c = outlineOf(l);
                    rgb[0] = c.r;
                    rgb[1] = c.g;
                    rgb[2] = c.b;
                }
            }
            for (int c = 0; c < 3; ++c) img.at(i, j, c) = rgb[c];
        }
    return img;
}

std::vector<double> hillShade(std::span<const float> heights, int w, int h) {
    const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
    auto at = [&](int x, int z) {
        return static_cast<double>(
            heights[static_cast<size_t>(std::clamp(z, 0, h - 1)) * w + std::clamp(x, 0, w - 1)]);
    };
    // the central differences at sample i (x = column, z = row)
    auto slopes = [&](size_t i, double& gx, double& gz) {
        const int x = static_cast<int>(i % static_cast<size_t>(w)),
                  z = static_cast<int>(i / static_cast<size_t>(w));
        gx = 0.5 * (at(x + 1, z) - at(x - 1, z));
        gz = 0.5 * (at(x, z + 1) - at(x, z - 1));
    };
    // their spread over every sample, or every stride-th on a map of more than kSpreadSamples
    // (the median of a million is as good, and a 5000² map's would need 400 MB)
    constexpr size_t kSpreadSamples = 1'000'000;
    const size_t stride = std::max<size_t>(1, n / kSpreadSamples);
    std::vector<double> mags;
    mags.reserve(2 * (n / stride + 1));
    for (size_t i = 0; i < n; i += stride) {
        double gx = 0.0, gz = 0.0;
        slopes(i, gx, gz);
        mags.push_back(std::abs(gx));
        mags.push_back(std::abs(gz));
    }
    double spread = 0.0;
    if (!mags.empty()) {
        double mean = 0.0;
        for (const double m : mags) mean += m;
        mean /= static_cast<double>(mags.size());
        auto mid = mags.begin() + static_cast<std::ptrdiff_t>(mags.size() / 2);
        std::nth_element(mags.begin(), mid, mags.end());
        spread = *mid > 0.0 ? 1.4826 * *mid : mean;
    }
    // the light from the top left (−x, −z) at 45° elevation; a typical slope tilts the normal
    // by about 27° (half a spread per sample)
    const double l = 1.0 / std::sqrt(3.0), k = spread > 0.0 ? 0.5 / spread : 0.0;
    std::vector<double> y(n);
    for (size_t i = 0; i < n; ++i) {
        double gx = 0.0, gz = 0.0;
        slopes(i, gx, gz);
        const double nx = -k * gx, nz = -k * gz;
        const double dot = (-nx - nz + 1.0) * l / std::sqrt(nx * nx + nz * nz + 1.0);
        y[i] = std::clamp(dot, 0.0, 1.0);
    }
    return y;
}

Image defectMapPreview(std::span<const float> heights, int w, int h,
                       const std::vector<uint8_t>& map, const std::vector<uint8_t>& unjudged) {
    constexpr uint8_t kMarkColour = 255, kUnjudgedColour = 128;  // red, blue (kOutlines)
    std::vector<uint8_t> labels(map.size(), 0);
    for (size_t i = 0; i < labels.size(); ++i)
        labels[i] = map[i]                                                ? kMarkColour
                    : !unjudged.empty() && unjudged[i] == kUnjudgedRegion ? kUnjudgedColour
                                                                          : 0;
    Image img = outlinedRender(hillShade(heights, w, h), w, h, {}, labels);
    for (size_t i = 0; i < unjudged.size(); ++i)
        if (unjudged[i] == kUnjudgedBorder && !labels[i])
            for (int c = 0; c < 3; ++c) img.data[i * 3 + static_cast<size_t>(c)] *= 0.5f;
    return img;
}

}  // namespace sl
