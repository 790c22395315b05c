// The fuzz targets' findings stay fixed (README "Fuzzing and sanitizers"): every input that once
// crashed a target, broke a check, exhausted its memory or escaped as another exception type
// (tests/fuzz/regressions/<target>/) is fed to the same target function as the fuzzer feeds it
// (tests/fuzz/FuzzTargets.h) and must now be refused with an InputError that names its source
// and says what is wrong; every seed of the corpora (tests/fuzz/corpus/<target>/) must be
// accepted, so that the fuzzers start from valid files.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "fuzz/FuzzTargets.h"

namespace {

namespace fs = std::filesystem;
using sl::fuzz::Target;

const fs::path kFuzzDir = fs::path(SL_SOURCE_DIR) / "tests" / "fuzz";
constexpr Target kTargets[] = {Target::Scene,     Target::Npy,    Target::Heightmap,
                               Target::Transport, Target::Envmap, Target::Metrology};

std::vector<fs::path> filesIn(const fs::path& dir) {
    std::vector<fs::path> out;
    if (fs::is_directory(dir))
        for (const auto& e : fs::directory_iterator(dir))
            if (e.is_regular_file()) out.push_back(e.path());
    std::sort(out.begin(), out.end());
    return out;
}

std::string bytesOf(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void feed(Target t, const std::string& bytes) {
    sl::fuzz::feed(t, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

// What each finding's refusal must say (the fix it got); a new finding is added here with its
// file.
const std::map<std::string, std::string> kExpected = {
    // nlohmann::json threw out_of_range, not parse_error, for a number beyond double's range.
    {"scene/number-overflow.json", "not valid JSON"},
    // A damaged EXR named .exr was tried by every OpenImageIO reader (DICOM, FITS, RAW, ...),
    // whose caches filled the fuzzer's 2 GB; its capDate attribute claims 1.7 GB.
    {"heightmap/exr-tried-by-every-reader.bin", "damaged OpenEXR header"},
    // libpng allocated the 1.8 GB a tEXt chunk's length claimed in a 154-byte 4x4 PNG.
    {"heightmap/png-text-chunk-length.bin", "damaged PNG: chunk 'tEXt' claims 1819475990 bytes"},
    // The EXR header walker's first version allocated a channel list's claimed size (1.9 GB)
    // before checking it against the file.
    {"heightmap/exr-channel-list-size.bin", "the file ends inside attribute 'channels'"},
    {"envmap/exr-channel-list-size.bin", "the file ends inside attribute 'channels'"},
    // An empty channel list of 19 bytes under another name: OpenEXR reads a chlist to its end
    // marker and read the next 18 bytes as attributes, one of them a 2 GB string (1.3 KB file).
    {"heightmap/exr-chlist-read-past-its-end.bin", "the channel list's end is not its last byte"},
    // OpenEXR allocated the 1.7 GB an attribute's size field claimed in a 211-byte file.
    {"envmap/exr-attribute-size.bin", "damaged OpenEXR header"},
    // A 5242846x1 EXR in 222 bytes: OpenImageIO converted through a 256-row (5 GB) buffer.
    {"envmap/exr-one-row-256-row-buffer.bin", "more than a 222-byte file can hold"},
    // NaN entries of T were accepted (checksums repaired by the fuzz target).
    {"transport/nan-values.tm", "entries of T are finite and >= 0"},
    // A section without "bytes": nlohmann::json's out_of_range escaped the reader.
    {"transport/section-without-bytes.tm", "damaged transport-matrix file"},
    // Issue 35: a value nested 70 000 deep (140 KB) overflowed the stack when quoted in a
    // message; past the fuzzers' old 600-2500-byte inputs. Refused by depth before parsing.
    {"scene/nested-70000-deep.json", "nested deeper than 64"},
    // An SDF whose y pitch is 1e70 times its x pitch: resampling to square pixels converted
    // the 6e72 points to size_t (undefined behaviour) before refusing them.
    {"heightmap/sdf-pitch-ratio-1e70.bin", "differ more than 1000-fold"},
    {"metrology/pitch-ratio-overflow.bin", "differ more than 1000-fold"},
    // A 124-byte SDF with a 1e7 pitch ratio: 1.6 GB of interpolated points, 43 s (timeout).
    {"metrology/pitch-ratio-1e7-slow.bin", "differ more than 1000-fold"},
};

}  // namespace

TEST(FuzzRegressions, EveryFindingIsRefusedWithAnInputError) {
    sl::fuzz::initialize();
    size_t count = 0;
    for (Target t : kTargets) {
        const std::string name = sl::fuzz::kTargetNames[static_cast<int>(t)];
        for (const fs::path& f : filesIn(kFuzzDir / "regressions" / name)) {
            const std::string key = name + "/" + f.filename().string();
            SCOPED_TRACE(key);
            ++count;
            try {
                feed(t, bytesOf(f));
                ADD_FAILURE() << "accepted";
            } catch (const sl::InputError& e) {
                const std::string msg = e.what();
                EXPECT_NE(msg.find("fuzz"), std::string::npos) << "names no source: " << msg;
                const auto it = kExpected.find(key);
                ASSERT_NE(it, kExpected.end()) << "add the finding to kExpected: " << msg;
                EXPECT_NE(msg.find(it->second), std::string::npos) << msg;
            }
        }
    }
    EXPECT_EQ(count, kExpected.size());
}

TEST(FuzzCorpus, EverySeedIsAccepted) {
    sl::fuzz::initialize();
    for (Target t : kTargets) {
        const std::string name = sl::fuzz::kTargetNames[static_cast<int>(t)];
        const std::vector<fs::path> seeds = filesIn(kFuzzDir / "corpus" / name);
        EXPECT_GE(seeds.size(), 3u) << name;
        for (const fs::path& f : seeds) {
            SCOPED_TRACE(name + "/" + f.filename().string());
            try {
                feed(t, bytesOf(f));
            } catch (const sl::InputError& e) {
                ADD_FAILURE() << "refused: " << e.what();
            }
        }
    }
}
