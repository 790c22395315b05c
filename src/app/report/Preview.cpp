#include "app/report/Preview.h"

#include <algorithm>
#include <cstddef>

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

}  // namespace sl
