// ExrReader: OpenEXR files read with OpenEXR itself, without loading OpenImageIO
// (io/ImageCodec.h), for the EXRs it reads exactly as OpenImageIO does: the first part, flat,
// scanlines or tiles, every channel float32 or every channel float16, either one channel (not
// an alpha) or R, G, B (and A), and no "oiio:ColorSpace" or "oiio:Gamma" attribute. Values are
// read as float (float16 -> float is exact), so the pixels are OpenImageIO's to the bit. Any
// other EXR is left to OpenImageIO. The header is walked first (io/ImageFile.h checkExrHeader).
#pragma once

#include <memory>
#include <string>

#include "io/ImageCodec.h"

namespace sl::detail {

/// An opened reader for `path`, or null if the file is not such an EXR or OpenEXR cannot open
/// it (OpenImageIO then reads it, or says why it cannot). Its convert() makes float only.
std::unique_ptr<ImageReader> openExrDirect(const std::string& path);

}  // namespace sl::detail
