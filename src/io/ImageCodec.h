// ImageCodec: the one door between io/ and OpenImageIO, opened on first use. OpenImageIO pulls
// in some 260 shared libraries (codecs, OpenCV, OpenVDB, ...), whose loading took 0.35-0.6 s
// of every run's start on a quiet 2-core machine, most of `optimize`'s one second. So the
// program does not link it: io/OiioCodec.cpp, the only file that includes its headers, is built
// as a module (libscratchlight-oiio.so beside the executable, or in ../lib/scratchlight when
// installed) that imageCodec() loads with dlopen the first time a file needs it. The files a
// run of this program writes and reads back never do: EXRs of float or half channels are read
// with OpenEXR itself (io/ExrReader.cpp) and PNGs are written with zlib (io/PngBuffer.h), so
// only other formats (TIFF, JPEG, HDR, 8/16-bit PNG input, EXRs of other channels) open it.
//
// The interface is C++ (both sides are built together, same compiler and standard library):
// ImageReader below, made by the module's createReader. Errors are returned as text, never
// thrown across the door; io/ImageFile.cpp turns them into InputErrors naming the file.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace sl::detail {

/// The pixel types io/ distinguishes (OpenImageIO's TypeDesc, as far as io/ reads them).
enum class PixelType { Unknown, UInt8, UInt16, Half, Float, Double, Other };

/// Bytes of one value (0 for Unknown and Other).
size_t pixelTypeSize(PixelType t);

/// What io/ reads from an image's header (OpenImageIO's ImageSpec, as far as io/ uses it).
struct ImageHeader {
    int x = 0, y = 0, z = 0;               // the data window's origin
    int width = 0, height = 0, depth = 1;  // the data window's size
    int nchannels = 0;
    int alphaChannel = -1;
    bool deep = false;
    PixelType format = PixelType::Unknown;  // the file's pixel type (the widest channel's)
    std::string formatText;                 // its name, e.g. "float", "uint8"
    bool perChannelFormats = false;         // channels of different types (OpenEXR)
    int tileWidth = 0, tileHeight = 0, tileDepth = 0;  // 0: scanlines
    int rowsPerStrip = 0;                              // TIFF strips (0: none given)
    std::string colorSpace;                            // "oiio:ColorSpace" (empty: none)
    float gamma = 0;                                   // "oiio:Gamma" (0: none)
    size_t nativePixelBytes = 0;                       // bytes of one pixel as readNative stores it
};

/// One opened image file, read band by band (io/ImageFile.h readBands).
class ImageReader {
  public:
    virtual ~ImageReader() = default;
    /// OpenImageIO's name of the format ("openexr", "png", "tiff", ...).
    virtual std::string formatName() const = 0;
    /// Opens the file and reads its header; false: see error().
    virtual bool open(const std::string& path) = 0;
    virtual const ImageHeader& header() const = 0;
    /// Reads rows [y0, y1) (relative to header().y; a tiled file: whole rows of tiles) of all
    /// channels, interleaved, header().nativePixelBytes per pixel; false: see error().
    virtual bool readNative(int y0, int y1, void* native) = 0;
    /// Converts `pixels` pixels read by readNative to `type` (interleaved channels): integers
    /// to float are v / max, uint8 to uint16 is v·257 (OpenImageIO's conversions). False if it
    /// cannot.
    virtual bool convert(const void* native, size_t pixels, PixelType type, void* out) const = 0;
    /// The reader's error text (empty: none), cleared by the call.
    virtual std::string error() = 0;
    virtual void close() = 0;
};

/// The module's entry points (kImageCodecVersion: both sides must agree).
inline constexpr int kImageCodecVersion = 1;
struct ImageCodec {
    int version = kImageCodecVersion;
    /// A reader for files with this extension (lower case, no dot), or null with *error set.
    std::unique_ptr<ImageReader> (*createReader)(const std::string& extension, std::string* error);
};

/// The OpenImageIO module, loaded on first use (thread-safe). Throws InputError naming `what`
/// (the file that needs it) when the module cannot be found or loaded.
const ImageCodec& imageCodec(const std::string& what);

/// True once imageCodec() has loaded the module in this process (for tests and `bench read`).
bool imageCodecLoaded();

}  // namespace sl::detail

/// The module's one exported symbol (io/OiioCodec.cpp).
extern "C" const sl::detail::ImageCodec* sl_image_codec_v1();
