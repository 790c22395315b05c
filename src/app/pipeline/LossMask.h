// The region of the image the loss is measured on: one table (core/Registry.h) of the choices,
// always within T's object mask (the part).
//   object    the whole part
//   scratch   the paper's scratch map (detect/ScratchMap.h) projected into the image
//   FILE      a PNG/EXR in image space, white inside (io/MaskIO.h loadImageMask)
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "detect/ScratchMap.h"

namespace sl {

struct Scene;
struct TransportMatrix;

enum class LossMaskKind { Object, Scratch, File };
struct LossMaskKindRow {
    LossMaskKind value;
    const char* name;  // what the option takes ("FILE": a path)
    const char* help;
};
std::span<const LossMaskKindRow> lossMaskKindTable();

struct LossMaskSpec {
    LossMaskKind kind = LossMaskKind::Object;
    std::filesystem::path file;  // File
    std::string name() const;    // "object", "scratch" or the file
};
/// "object", "scratch", or any other text as a mask file.
LossMaskSpec parseLossMask(std::string_view text);

struct LossMask {
    std::vector<uint8_t> pixels;        // image space, 1 inside
    size_t count = 0;                   // pixels inside
    std::vector<uint8_t> scratchCells;  // scratch: the map in height-map space (0/255)
};
/// The mask on T's image. scene: needed for scratch. InputError naming option 'mask' when the
/// mask is empty on the part.
LossMask lossMask(const LossMaskSpec& spec, const TransportMatrix& t, const Scene* scene,
                  const ScratchMapOptions& scratch);

/// The mask's region before any T exists (a file's or the scratch map's pixels, width·height
/// flags of the scene's camera), for tracing only those pixels; empty for `object` (the whole
/// part, which only the trace finds). InputError naming option 'mask' when the region is empty.
std::vector<uint8_t> lossMaskRegion(const LossMaskSpec& spec, const Scene& scene,
                                    const ScratchMapOptions& scratch);

}  // namespace sl
