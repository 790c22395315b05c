// Helpers shared by tests: temporary directories, tiny file writers, running the CLI.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "core/Error.h"
#include "io/HeightmapIO.h"
#include "scene/Scene.h"
#include "transport/TransportMatrix.h"

namespace sl::test {

/// A fresh directory under the system temp dir, removed when the object dies.
class TempDir {
  public:
    explicit TempDir(const std::string& tag) {
        std::random_device rd;
        path_ = std::filesystem::temp_directory_path() /
                ("sl-test-" + tag + "-" + std::to_string(rd()) + std::to_string(rd()));
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  private:
    std::filesystem::path path_;
};

/// An n×n height map of gentle bumps, 0.03·sin(0.5 i)·cos(0.37 j) (scene units): a small
/// surface whose transport matrix has structure in every row.
inline std::vector<float> bumpyHeightMap(int n) {
    std::vector<float> h(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            h[size_t(j) * n + i] =
                static_cast<float>(0.03 * std::sin(i * 0.5) * std::cos(j * 0.37));
    return h;
}

/// The bumpy test part's scene: 0.05 mm samples, GGX α 0.1, max_depth 3, a width×height view
/// (the scene file's defaults otherwise). With bumpyHeightMap(n), n 32–48, the part fills it.
inline SceneDesc bumpyPartDesc(int width, int height) {
    SceneDesc d;
    d.heightmap.pitch = 0.05;
    d.material.params.alphaU = d.material.params.alphaV = 0.1f;
    d.camera.width = width;
    d.camera.height = height;
    d.render.maxDepth = 3;
    return d;
}

/// A dense 1×1-pixel T on a 2×3 env-map grid, every entry 0.5: the smallest matrix a .tm file
/// holds (for tests of the file and the cache, not of light transport).
inline TransportMatrix tinyTransportMatrix() {
    TransportMatrix t;
    t.width = t.height = 1;
    t.envWidth = 2;
    t.envHeight = 3;
    t.storage = TransportStorage::Dense;
    t.values.assign(t.cols(), 0.5f);
    t.objectMask.assign(1, 1);
    return t;
}

/// A file's bytes ("" when it cannot be read).
/// The mean of a sample, and its standard deviation (n − 1): what a standard error is checked
/// against over independent estimates.
/// max |a − b| over max |b|: the relative difference of two vectors in the larger one's scale.
inline double maxRelDiff(std::span<const double> a, std::span<const double> b) {
    double scale = 0, diff = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        scale = std::max(scale, std::abs(b[i]));
        diff = std::max(diff, std::abs(a[i] - b[i]));
    }
    return diff / std::max(scale, 1e-300);
}

inline double sampleMean(const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m += x;
    return m / static_cast<double>(v.size());
}
inline double sampleSd(const std::vector<double>& v) {
    const double m = sampleMean(v);
    double q = 0;
    for (double x : v) q += (x - m) * (x - m);
    return std::sqrt(q / static_cast<double>(v.size() - 1));
}

/// Expects f() to throw InputError whose message holds every part.
template <typename F>
void expectInputError(F&& f, const std::vector<std::string>& parts) {
    try {
        f();
        ADD_FAILURE() << "accepted; expected a refusal saying " << (parts.empty() ? "" : parts[0]);
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << p << " | " << msg;
    }
}

/// Expects loadHeightmap(file, opt) to throw InputError naming the file and every part.
inline void expectRefused(const std::filesystem::path& file, std::vector<std::string> parts,
                          const HeightmapOptions& opt = {}) {
    parts.insert(parts.begin(), file.string());
    expectInputError([&] { loadHeightmap(file, opt); }, parts);
}

inline std::string readFile(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void writeText(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

/// Writes a float32 C-order .npy file of shape (rows, cols).
inline void writeNpyF32(const std::filesystem::path& p, int rows, int cols,
                        const std::vector<float>& v) {
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                         std::to_string(rows) + ", " + std::to_string(cols) + "), }";
    size_t total = 10 + header.size() + 1;
    header += std::string((64 - total % 64) % 64, ' ') + "\n";
    std::ofstream os(p, std::ios::binary);
    os.write("\x93NUMPY\x01\x00", 8);
    auto len = static_cast<uint16_t>(header.size());
    os.put(static_cast<char>(len & 0xff));
    os.put(static_cast<char>(len >> 8));
    os << header;
    os.write(reinterpret_cast<const char*>(v.data()),
             static_cast<std::streamsize>(v.size() * sizeof(float)));
}

struct RunResult {
    int exitCode = -1;
    std::string output;  // stdout and stderr
};

/// Runs a shell command line; its exit code and its output (stdout and stderr).
inline RunResult runShell(const std::string& line) {
    RunResult r;
    FILE* f = popen((line + " 2>&1").c_str(), "r");
    if (!f) return r;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) r.output.append(buf, n);
    const int status = pclose(f);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

/// Runs the scratchlight CLI with the given argument string; captures its output.
inline RunResult runCli(const std::string& args) {
    return runShell(std::string(SL_CLI_PATH) + " " + args);
}

/// scripts/slurm-precompute SCENE ROWS SHARDS JOBDIR ARGS, then its array's tasks run here one
/// by one (SLURM_ARRAY_TASK_ID 0 … shards−1): JOBDIR gets the shards and T.shards. The first
/// failure's result, else the last task's.
inline RunResult runSlurmPrecompute(const std::string& scene, int rows, int shards,
                                    const std::string& jobDir, const std::string& args) {
    RunResult r =
        runShell("SCRATCHLIGHT=" + std::string(SL_CLI_PATH) + " " + std::string(SL_SOURCE_DIR) +
                 "/scripts/slurm-precompute " + scene + " " + std::to_string(rows) + " " +
                 std::to_string(shards) + " " + jobDir + " " + args);
    for (int k = 0; k < shards && r.exitCode == 0; ++k)
        r = runShell("SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " + jobDir +
                     "/precompute.sbatch");
    return r;
}

/// A small labelled part in `dir`: a 96×96 ball-end map with three scratches and a chatter half
/// (part.exr, part-truth.png) and a scene rendering it at 96×96, 4 spp (scene.json). Returns
/// gen-surface's exit code.
inline int writeSmallLabelledPart(const std::filesystem::path& dir) {
    return runCli("gen-surface -o " + (dir / "part.exr").string() +
                  " --width 96 --height 96 --scratches 3 --chatter-start 0.5 --scene " +
                  (dir / "scene.json").string() + " --image-size 96 --spp 4 --max-depth 3")
        .exitCode;
}

/// The CLI tests' defects part in `dir`: a 160×160 map with three labelled scratches (part.exr,
/// part-truth.png) and a scene seeing it at 40×40, 8 spp, depth 3 (scene.json). Returns
/// gen-surface's exit code.
inline int writeScratchedPart(const std::filesystem::path& dir) {
    return runCli("gen-surface -o " + (dir / "part.exr").string() +
                  " --width 160 --height 160 --scratches 3 --scene " +
                  (dir / "scene.json").string() + " --image-size 40 --spp 8 --max-depth 3")
        .exitCode;
}

}  // namespace sl::test
