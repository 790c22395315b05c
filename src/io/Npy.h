// Npy: a small reader for NumPy's .npy format (numpy.lib.format), versions 1.0, 2.0 and 3.0.
//
// File layout: magic "\x93NUMPY", major and minor version bytes, header length (uint16 LE in
// 1.0, uint32 LE in 2.0 and 3.0), then a Python dict literal such as
//   {'descr': '<f4', 'fortran_order': False, 'shape': (480, 640), }
// padded with spaces and a newline, then the raw array data.
//
// Supported: little-endian float32 '<f4', float64 '<f8' and uint16 '<u2' ('u2' with '|' or '='
// on this little-endian host too); C order only; 2-D shapes (rows, columns), also (rows,
// columns, 1). Everything else is refused with an InputError that names the file and the fix.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace sl {

enum class NpyType { Float32, Float64, UInt16 };

/// Parsed and validated header of a .npy file.
struct NpyHeader {
    int versionMajor = 0, versionMinor = 0;
    std::string descr;  // as written, e.g. "<f4"
    NpyType type = NpyType::Float32;
    size_t itemSize = 4;  // bytes per element
    bool fortranOrder = false;
    std::vector<size_t> shape;  // as written
    size_t dataOffset = 0;      // byte offset of the array data
    size_t elementCount = 0;    // product of shape
};

/// A 2-D array converted to float (uint16 values become 0..65535, exactly).
struct NpyMatrix {
    int rows = 0, cols = 0;
    std::vector<float> data;  // row-major, row 0 first
    NpyType type = NpyType::Float32;
    std::string typeName() const;  // "float32", "float64" or "uint16"
};

/// Name of the element type: "float32", "float64" or "uint16".
const char* npyTypeName(NpyType t);

/// Reads and validates the header (magic, version, dict, dtype, order, shape, file length).
NpyHeader readNpyHeader(const std::filesystem::path& file);

/// Reads a 2-D array (shape (H, W) or (H, W, 1)) as float. float64 values are rounded to
/// float; values outside float's range become ±inf (callers check finiteness).
NpyMatrix readNpy2D(const std::filesystem::path& file);

/// Parses the header from bytes already in memory (used by readNpyHeader; exposed for tests).
/// `fileSize` is the total file length the data must fit; `where` names the file in errors.
NpyHeader parseNpyHeader(const uint8_t* bytes, size_t available, size_t fileSize,
                         const std::string& where);

}  // namespace sl
