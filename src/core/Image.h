// Image value type: row-major, top row first (row 0 is the image's top), channels interleaved.
#pragma once

#include <cstddef>
#include <vector>

namespace sl {

struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> data;  // width * height * channels

    Image() = default;
    Image(int w, int h, int c, float fill = 0.0f)
        : width(w), height(h), channels(c), data(static_cast<size_t>(w) * h * c, fill) {}

    size_t pixelCount() const { return static_cast<size_t>(width) * height; }
    float& at(int x, int y, int c = 0) {
        return data[(static_cast<size_t>(y) * width + x) * channels + c];
    }
    float at(int x, int y, int c = 0) const {
        return data[(static_cast<size_t>(y) * width + x) * channels + c];
    }
};

}  // namespace sl
