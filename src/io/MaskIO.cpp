#include "io/MaskIO.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/Error.h"
#include "io/ImageFile.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"

namespace sl {

namespace {

std::string sizeText(int w, int h) {
    return std::to_string(w) + "x" + std::to_string(h);
}

std::vector<RegionLabel> readLegend(const std::filesystem::path& file) {
    const std::string where = file.string();
    nlohmann::json j = readJsonInput(
        file, "a truth legend", "write {\"labels\": [{\"value\": 255, \"name\": \"defect\"}]}");
    if (!j.is_object() || !j.contains("labels") || !j["labels"].is_array())
        throw inputError(where, "has no \"labels\" array",
                         "write {\"labels\": [{\"value\": 255, \"name\": \"defect\"}]}");
    std::vector<RegionLabel> legend;
    for (const auto& e : j["labels"]) {
        if (!e.is_object() || !e.contains("value") || !e["value"].is_number_integer() ||
            !e.contains("name") || !e["name"].is_string())
            throw inputError(where + ": labels[" + std::to_string(legend.size()) + "]",
                             "needs an integer \"value\" and a string \"name\"");
        const long long v = e["value"].get<long long>();
        if (v < 1 || v > 255)
            throw inputError(
                where + ": labels[" + std::to_string(legend.size()) + "].value",
                "must be 1..255 (0 is the unlabelled surface), got " + std::to_string(v));
        legend.push_back({static_cast<uint8_t>(v), e["name"].get<std::string>()});
    }
    return legend;
}

}  // namespace

LabelMask readLabelMask(const std::filesystem::path& file, int mapWidth, int mapHeight) {
    const std::string where = file.string();
    if (!std::filesystem::is_regular_file(file))
        throw inputError(where, "no such file", "give the truth mask gen-surface wrote");
    // Read as bytes: OpenImageIO's conversions, so an EXR mask goes through it too.
    auto in = detail::openImageFile(file, "Give the truth mask gen-surface wrote", false);
    const detail::ImageHeader& spec = in->header();
    detail::checkImageSize(file, spec);
    if (spec.width != mapWidth || spec.height != mapHeight)
        throw inputError(where,
                         "mask is " + std::to_string(spec.width) + "x" +
                             std::to_string(spec.height) + " pixels, the height map is " +
                             std::to_string(mapWidth) + "x" + std::to_string(mapHeight),
                         "A height-map-space mask (as gen-surface's <stem>-truth.png) has one "
                         "pixel per height sample");
    LabelMask m;
    m.width = spec.width;
    m.height = spec.height;
    const size_t n = static_cast<size_t>(spec.width) * spec.height;
    m.labels.resize(n);
    // UINT8 reads integer files raw (16-bit scaled to 8 bits); no colour decoding. Channel 0.
    const size_t nch = static_cast<size_t>(spec.nchannels), w = static_cast<size_t>(spec.width);
    detail::readBands(*in, file, detail::PixelType::UInt8, "Give the truth mask gen-surface wrote",
                      [&](int y0, int y1, const void* values) {
                          const auto* v = static_cast<const uint8_t*>(values);
                          const size_t off = static_cast<size_t>(y0) * w;
                          for (size_t p = 0; p < static_cast<size_t>(y1 - y0) * w; ++p)
                              m.labels[off + p] = v[p * nch];
                      });
    in->close();

    std::filesystem::path legend = file;
    legend.replace_extension(".json");
    if (std::filesystem::exists(legend)) {
        m.legend = readLegend(legend);
    } else {
        bool present[256] = {};
        for (uint8_t v : m.labels) present[v] = true;
        for (int v = 255; v >= 1; --v)
            if (present[v])
                m.legend.push_back(
                    {static_cast<uint8_t>(v), v == 255 ? "defect" : "label-" + std::to_string(v)});
    }
    return m;
}

std::vector<uint8_t> loadImageMask(const std::filesystem::path& file, int width, int height) {
    const Image img = readImage(file);
    if (img.width != width || img.height != height) {
        throw inputError(file.string(),
                         "mask is " + sizeText(img.width, img.height) + " pixels, the image is " +
                             sizeText(width, height),
                         "Use a mask drawn on (or resized to) the rendered image's size");
    }
    if (img.channels < 1) throw inputError(file.string(), "mask image has no channels");
    std::vector<uint8_t> mask(img.pixelCount());
    size_t inside = 0;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const bool in = img.at(x, y, 0) > 0.5f;
            mask[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)] =
                in ? 255 : 0;
            inside += in;
        }
    }
    if (inside == 0) {
        throw inputError(file.string(),
                         "mask is empty (no pixel with first channel > 0.5 after decoding)",
                         "Paint the region of interest white (inside) on black (outside)");
    }
    return mask;
}

std::vector<uint8_t> loadHeightMapMask(const std::filesystem::path& file, int mapWidth,
                                       int mapHeight) {
    const Image img = readImage(file);
    if (img.width != mapWidth || img.height != mapHeight)
        throw inputError(file.string(),
                         "mask is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                             " pixels, the height map is " + std::to_string(mapWidth) + "x" +
                             std::to_string(mapHeight),
                         "A height-map-space mask (as gen-surface's <stem>-truth.png) has one "
                         "pixel per height sample");
    if (img.channels < 1) throw inputError(file.string(), "mask image has no channels");
    std::vector<uint8_t> mask(img.pixelCount());
    for (size_t k = 0; k < mask.size(); ++k)
        mask[k] = img.data[k * static_cast<size_t>(img.channels)] > 0.5f ? 255 : 0;
    return mask;
}

}  // namespace sl
