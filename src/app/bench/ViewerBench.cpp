#include "app/bench/ViewerBench.h"

#include <httplib.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/host/Plot.h"
#include "app/pipeline/Transport.h"
#include "app/viewer/ViewerApi.h"
#include "app/viewer/ViewerServer.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/AtomicFile.h"
#include "io/SceneFile.h"
#include "scene/Scene.h"

namespace sl {

std::vector<ViewerBenchRow> runViewerBench(const ViewerBenchOptions& o) {
    if (o.repeats < 1) throw inputError(option("repeats"), "must be >= 1");
    const std::filesystem::path sceneFile = o.scene.empty() ? bundledDefaultScene() : o.scene;
    std::vector<ViewerBenchRow> rows;
    for (const int size : o.sizes) {
        if (size < 8 || size > 8192) throw inputError(option("size"), "must be in [8, 8192]");
        std::vector<std::string> ov = o.sceneOverrides;
        ov.push_back("camera.width=" + std::to_string(size));
        ov.push_back("camera.height=" + std::to_string(size));
        auto scene = loadScene(sceneFile, ov);
        PrecomputeOptions po;
        po.spp = o.spp;
        po.threads = o.threads;
        po.label = "bench view: trace T";
        TransportSource t = transportForScene(*scene, po, cacheDirectory(o.cache));
        ViewerBenchRow row;
        row.size = size;
        row.nnz = t.file.matrix.nnz();
        row.traceSeconds = t.secondsTotal;
        ViewerOptions vo;
        vo.threads = o.threads;
        vo.judge = false;
        ViewerSession session(std::move(t), std::nullopt, vo);
        const size_t cols = session.transport().cols();

        std::vector<double> relight, encode, image, light;
        for (int k = 0; k < o.repeats; ++k) {
            throwIfInterrupted();
            ViewerTimings tm;
            session.imagePng(0, 1.0, &tm);
            relight.push_back(tm.relightMs);
            encode.push_back(tm.encodeMs);
            row.pngBytes = tm.pngBytes;
        }
        ViewerServer server(session, "127.0.0.1", 0);
        server.start();
        httplib::Client client("127.0.0.1", server.port());
        client.set_read_timeout(60, 0);
        std::vector<double> e(cols, 0.5);
        const double exposure = session.autoExposure(0);
        const std::string imagePath = "/api/image.png?slot=a&exposure=" + std::to_string(exposure);
        for (int k = 0; k < o.repeats + 1; ++k) {  // the first round warms up
            throwIfInterrupted();  // the server stops as the exception leaves its scope
            e[static_cast<size_t>(k) % cols] += 1.0;
            nlohmann::json body = {{"slot", "a"}, {"E", e}};
            Stopwatch c1;
            auto r1 = client.Post("/api/light", body.dump(), "application/json");
            const double l = c1.seconds() * 1e3;
            if (!r1 || r1->status != 200)
                throw std::runtime_error("bench view: POST /api/light failed");
            Stopwatch c2;
            auto r2 = client.Get(imagePath.c_str());
            const double im = c2.seconds() * 1e3;
            if (!r2 || r2->status != 200 || r2->body.size() < 8)
                throw std::runtime_error("bench view: GET /api/image.png failed");
            if (k == 0) continue;
            light.push_back(l);
            image.push_back(im);
        }
        server.stop();
        row.relightMs = median(relight);
        row.encodeMs = median(encode);
        row.imageMs = median(image);
        row.lightMs = median(light);
        rows.push_back(row);
    }
    std::ostringstream csv;
    csv << "size,nnz,trace_s,image_ms_median,light_ms_median,relight_ms_median,"
           "encode_ms_median,png_bytes,target_ms\n";
    for (const auto& r : rows)
        csv << r.size << ',' << r.nnz << ',' << r.traceSeconds << ',' << r.imageMs << ','
            << r.lightMs << ',' << r.relightMs << ',' << r.encodeMs << ',' << r.pngBytes << ','
            << (r.size <= 512 ? 50 : 150) << '\n';
    enterCommit();  // the last safe point (core/Interrupt.h)
    writeTextAtomically(o.csv, csv.str());
    return rows;
}

std::string formatViewerBench(const std::vector<ViewerBenchRow>& rows) {
    std::string out =
        "  size        nnz  image ms  light ms  relight ms  encode ms   PNG KB  target\n";
    char line[256];
    for (const auto& r : rows) {
        const double target = r.size <= 512 ? 50 : 150;
        std::snprintf(line, sizeof line, "%6d %10zu %9.1f %9.1f %11.1f %10.1f %8.0f  %s %g ms\n",
                      r.size, r.nnz, r.imageMs, r.lightMs, r.relightMs, r.encodeMs,
                      static_cast<double>(r.pngBytes) / 1024.0,
                      r.imageMs <= target ? "met   <=" : "MISSED >", target);
        out += line;
    }
    return out;
}

}  // namespace sl
