// `bench view`: the viewer's latency under a real HTTP client. Per image size: T of the scene
// traced at `spp` (cached), a ViewerSession and its server on 127.0.0.1 (an ephemeral port),
// then `repeats` times: POST /api/light (one texel changed) and GET /api/image.png through
// httplib's client; medians of the image request (relight + PNG encode + transfer), of the
// light update, and of the relight and encode inside the server.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/pipeline/Cache.h"

namespace sl {

struct ViewerBenchOptions {
    std::filesystem::path scene;  // empty: the bundled scene
    std::vector<std::string> sceneOverrides;
    std::vector<int> sizes = {512, 2048};
    int spp = 1;
    int repeats = 20;
    int threads = 0;
    CacheLocation cache;
    std::filesystem::path csv = "bench-view.csv";
};

struct ViewerBenchRow {
    int size = 0;
    size_t nnz = 0;
    double traceSeconds = 0;
    double imageMs = 0;  // GET /api/image.png, median, client side (relight + encode + transfer)
    double lightMs = 0;  // POST /api/light (E as JSON, no judge), median
    double relightMs = 0, encodeMs = 0;  // inside the server, median
    size_t pngBytes = 0;
};

std::vector<ViewerBenchRow> runViewerBench(const ViewerBenchOptions& options);

/// The table the command prints (with the targets: 50 ms at 512², 150 ms at 2048²).
std::string formatViewerBench(const std::vector<ViewerBenchRow>& rows);

}  // namespace sl
