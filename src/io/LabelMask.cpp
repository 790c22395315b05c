#include "io/LabelMask.h"

#include <OpenImageIO/imageio.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/Error.h"

namespace sl {

namespace {

std::vector<RegionLabel> readLegend(const std::filesystem::path& file) {
    const std::string where = file.string();
    std::ifstream in(file);
    if (!in) throw inputError(where, "cannot open the legend");
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw inputError(where, std::string("is not valid JSON (") + e.what() + ")",
                         "write {\"labels\": [{\"value\": 255, \"name\": \"defect\"}]}");
    }
    if (!j.is_object() || !j.contains("labels") || !j["labels"].is_array())
        throw inputError(where, "has no \"labels\" array",
                         "write {\"labels\": [{\"value\": 255, \"name\": \"defect\"}]}");
    std::vector<RegionLabel> legend;
    for (const auto& e : j["labels"]) {
        if (!e.is_object() || !e.contains("value") || !e["value"].is_number_integer() ||
            !e.contains("name") || !e["name"].is_string())
            throw inputError(where + ": labels[" + std::to_string(legend.size()) + "]",
                             "needs an integer \"value\" and a string \"name\"");
        const int v = e["value"].get<int>();
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
    auto in = OIIO::ImageInput::open(where);
    if (!in) throw inputError(where, "cannot read the image (" + OIIO::geterror() + ")");
    const OIIO::ImageSpec& spec = in->spec();
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
    std::vector<uint8_t> all(n * static_cast<size_t>(spec.nchannels));
    // UINT8 reads integer files raw (16-bit scaled to 8 bits); no colour decoding.
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, all.data()))
        throw inputError(where, "cannot read the pixels (" + in->geterror() + ")");
    in->close();
    m.labels.resize(n);
    for (size_t p = 0; p < n; ++p) m.labels[p] = all[p * static_cast<size_t>(spec.nchannels)];

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

}  // namespace sl
