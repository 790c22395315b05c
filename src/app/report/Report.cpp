#include "app/report/Report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "app/report/ReportDetail.h"
#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/InputFile.h"
#include "io/OptimizeOutDir.h"
#include "io/OptimizeSummary.h"

namespace sl {

using nlohmann::json;
using report::table;

namespace {

std::string readBytes(const std::filesystem::path& file, const std::string& what) {
    return readInputFile(file, what, 1ull << 30,
                         "Check that the file exists (re-run the command that writes it)");
}

std::string fmtNum(double v) {
    if (!std::isfinite(v)) return "—";
    char buf[64];
    const double a = std::abs(v);
    if (v == std::floor(v) && a < 1e15)
        std::snprintf(buf, sizeof buf, "%.0f", v);
    else if (a != 0 && (a < 1e-3 || a >= 1e6))
        std::snprintf(buf, sizeof buf, "%.4g", v);
    else
        std::snprintf(buf, sizeof buf, "%.4f", v);
    return buf;
}

std::string fmtJson(const json& v) {
    if (v.is_null()) return "—";
    if (v.is_number()) return fmtNum(v.get<double>());
    if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
    if (v.is_string()) return v.get<std::string>();
    return v.dump();
}

// Flattens nested objects into "a.b" keys, in order of first appearance.
void flatten(const json& j, const std::string& prefix, std::vector<std::string>& order,
             std::map<std::string, json>& out) {
    if (!j.is_object()) return;
    for (auto it = j.begin(); it != j.end(); ++it) {
        std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
        if (it->is_object()) {
            flatten(*it, key, order, out);
        } else {
            if (!out.count(key)) order.push_back(key);
            out[key] = *it;
        }
    }
}

}  // namespace

namespace report {

// Table: one row per key (union over runs), one column per run.
std::string table(const std::vector<std::string>& columns, const std::vector<json>& objects,
                  const std::string& cls) {
    std::vector<std::string> order;
    std::vector<std::map<std::string, json>> flat(objects.size());
    std::map<std::string, json> all;
    for (size_t r = 0; r < objects.size(); ++r) {
        std::vector<std::string> o;
        flatten(objects[r], "", o, flat[r]);
        for (const auto& k : o)
            if (!all.count(k)) all[k] = nullptr, order.push_back(k);
    }
    if (order.empty()) return {};
    std::ostringstream h;
    h << "<table class=\"" << cls << "\"><thead><tr><th></th>";
    for (const auto& c : columns) h << "<th>" << escapeXml(c) << "</th>";
    h << "</tr></thead><tbody>\n";
    for (const auto& k : order) {
        h << "<tr><th>" << escapeXml(k) << "</th>";
        for (const auto& f : flat) {
            auto it = f.find(k);
            h << "<td>" << escapeXml(it == f.end() ? std::string("") : fmtJson(it->second))
              << "</td>";
        }
        h << "</tr>\n";
    }
    h << "</tbody></table>\n";
    return h.str();
}

}  // namespace report

namespace {

const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                         "#9467bd", "#8c564b", "#e377c2", "#17becf"};

const char* kStyle = R"(
body{font-family:sans-serif;margin:24px;color:#222;max-width:1600px}
h1{font-size:1.6em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}
h3{font-size:1em;margin:.2em 0}
.runs{display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start}
.run{border:1px solid #ddd;padding:8px;margin:0;background:#fafafa}
.imgs{display:flex;flex-wrap:wrap;gap:6px}
.imgs figure{margin:0}
.imgs img{width:256px;image-rendering:pixelated;display:block;border:1px solid #ccc}
figcaption{font-size:.8em;color:#555}
table{border-collapse:collapse;margin:.8em 0;font-size:.85em}
td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}
tbody th{text-align:left;font-weight:normal;background:#f3f3f3}
.caption{color:#444}.note{background:#fff8e0;padding:6px 10px;border-left:3px solid #e0b000}
svg{background:#fff;border:1px solid #ddd}
)";

}  // namespace

std::string base64Encode(const std::string& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((in.size() + 2) / 3 * 4);
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const uint32_t v = (static_cast<uint32_t>(static_cast<unsigned char>(in[i])) << 16) |
                           (static_cast<uint32_t>(static_cast<unsigned char>(in[i + 1])) << 8) |
                           static_cast<unsigned char>(in[i + 2]);
        out += t[(v >> 18) & 63];
        out += t[(v >> 12) & 63];
        out += t[(v >> 6) & 63];
        out += t[v & 63];
    }
    if (i < in.size()) {
        uint32_t v = static_cast<uint32_t>(static_cast<unsigned char>(in[i])) << 16;
        if (i + 1 < in.size())
            v |= static_cast<uint32_t>(static_cast<unsigned char>(in[i + 1])) << 8;
        out += t[(v >> 18) & 63];
        out += t[(v >> 12) & 63];
        out += i + 1 < in.size() ? t[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

std::string dataUri(const std::filesystem::path& png) {
    std::string out = "data:image/png;base64,";
    out += base64Encode(readBytes(png, "image for the report"));
    return out;
}

LossSeries readLossCsv(const std::filesystem::path& file) {
    std::istringstream in(readBytes(file, "loss curve"));
    std::string line;
    if (!std::getline(in, line)) throw inputError(file.string(), "empty loss.csv");
    std::vector<std::string> cols;
    {
        std::istringstream h(line);
        std::string c;
        while (std::getline(h, c, ',')) cols.push_back(c);
    }
    auto col = [&](const std::string& name) {
        auto it = std::find(cols.begin(), cols.end(), name);
        if (it == cols.end())
            throw inputError(file.string(), "no \"" + name + "\" column in the header",
                             "Expected the loss.csv that `optimize` writes");
        return static_cast<size_t>(it - cols.begin());
    };
    const size_t ci = col("iteration"), cl = col("loss");
    LossSeries s;
    int lineNo = 1;
    while (std::getline(in, line)) {
        ++lineNo;
        if (line.empty()) continue;
        std::vector<std::string> f;
        std::istringstream r(line);
        std::string c;
        while (std::getline(r, c, ',')) f.push_back(c);
        if (f.size() <= std::max(ci, cl))
            throw inputError(file.string() + ":" + std::to_string(lineNo), "too few columns");
        try {
            s.iteration.push_back(std::stod(f[ci]));
            s.loss.push_back(std::stod(f[cl]));
        } catch (const std::exception&) {
            throw inputError(file.string() + ":" + std::to_string(lineNo), "not a number");
        }
    }
    return s;
}

std::string lossCurveSvg(const std::vector<LossSeries>& series, int width, int height) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    bool allPositive = true;
    for (const auto& s : series)
        for (size_t k = 0; k < s.loss.size(); ++k) {
            if (!std::isfinite(s.loss[k]) || !std::isfinite(s.iteration[k])) continue;
            x0 = std::min(x0, s.iteration[k]);
            x1 = std::max(x1, s.iteration[k]);
            y0 = std::min(y0, s.loss[k]);
            y1 = std::max(y1, s.loss[k]);
            allPositive = allPositive && s.loss[k] > 0;
        }
    if (!(x1 >= x0) || !(y1 >= y0)) return "<p>(no loss values)</p>";
    const bool logY = allPositive && y1 / y0 > 100.0;
    auto ty = [&](double v) { return logY ? std::log10(v) : v; };
    double a = ty(y0), b = ty(y1);
    if (b - a < 1e-12 * std::max(1.0, std::abs(a))) a -= 0.5, b += 0.5;
    if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
    const double L = 62, R = 10, T = 10, B = 34;
    const double pw = width - L - R, ph = height - T - B;
    auto px = [&](double x) { return L + (x - x0) / (x1 - x0) * pw; };
    auto py = [&](double y) { return T + (1.0 - (ty(y) - a) / (b - a)) * ph; };
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(1);
    o << "<svg width=\"" << width << "\" height=\"" << height << "\" viewBox=\"0 0 " << width << ' '
      << height << "\" font-family=\"sans-serif\" font-size=\"10\">";
    o << "<rect x=\"" << L << "\" y=\"" << T << "\" width=\"" << pw << "\" height=\"" << ph
      << "\" fill=\"none\" stroke=\"#888\"/>";
    for (int k = 0; k <= 4; ++k) {  // y ticks
        const double v = a + (b - a) * k / 4.0, yy = T + (1.0 - k / 4.0) * ph;
        o << "<line x1=\"" << L - 3 << "\" x2=\"" << L << "\" y1=\"" << yy << "\" y2=\"" << yy
          << "\" stroke=\"#888\"/><text x=\"" << L - 5 << "\" y=\"" << yy + 3
          << "\" text-anchor=\"end\">" << escapeXml(fmtNum(logY ? std::pow(10.0, v) : v))
          << "</text>";
        const double xv = x0 + (x1 - x0) * k / 4.0, xx = L + pw * k / 4.0;
        o << "<line x1=\"" << xx << "\" x2=\"" << xx << "\" y1=\"" << T + ph << "\" y2=\""
          << T + ph + 3 << "\" stroke=\"#888\"/><text x=\"" << xx << "\" y=\"" << T + ph + 14
          << "\" text-anchor=\"middle\">" << escapeXml(fmtNum(std::round(xv))) << "</text>";
    }
    o << "<text x=\"" << L + pw / 2 << "\" y=\"" << height - 4
      << "\" text-anchor=\"middle\">iteration</text>";
    o << "<text x=\"12\" y=\"" << T + ph / 2
      << "\" text-anchor=\"middle\" transform=\"rotate(-90 12 " << T + ph / 2 << ")\">loss"
      << (logY ? " (log)" : "") << "</text>";
    for (size_t si = 0; si < series.size(); ++si) {
        const auto& s = series[si];
        const char* c = kColors[si % (sizeof kColors / sizeof *kColors)];
        o << "<polyline fill=\"none\" stroke=\"" << c << "\" stroke-width=\"1.5\" points=\"";
        for (size_t k = 0; k < s.loss.size(); ++k)
            if (std::isfinite(s.loss[k]) && std::isfinite(s.iteration[k]))
                o << px(s.iteration[k]) << ',' << py(s.loss[k]) << ' ';
        o << "\"/>";
        if (series.size() > 1 || !s.label.empty())
            o << "<text x=\"" << L + pw - 4 << "\" y=\"" << T + 12 + 12 * static_cast<double>(si)
              << "\" text-anchor=\"end\" fill=\"" << c << "\">" << escapeXml(s.label) << "</text>";
    }
    o << "</svg>";
    return o.str();
}

ReportRun reportRunFromOutDir(const std::filesystem::path& dir, const std::string& title,
                              RunState state) {
    const outdir::OptimizeSummary summary = outdir::readOptimizeSummary(dir);
    const json& s = summary.document;
    ReportRun r;
    r.title = title.empty() ? dir.filename().string() : title;
    if (r.title.empty()) r.title = dir.string();
    r.settings = json::object();
    for (auto it = s.begin(); it != s.end(); ++it)
        if (!it->is_object() && !it->is_array()) r.settings[it.key()] = *it;
    r.metrics = json::object();
    const bool fin = state == RunState::Final;
    // every optimize writes both (a loss that was not finite as null)
    r.metrics["loss_initial"] = summary.initialLoss;
    if (fin) r.metrics["loss_final"] = summary.finalLoss;
    const json& m = fin ? summary.metrics : summary.metricsInitial;
    if (m.is_object())
        for (auto it = m.begin(); it != m.end(); ++it) r.metrics[it.key()] = *it;

    auto add = [&](const char* file, const char* caption) {
        if (std::filesystem::exists(dir / file)) r.images.push_back({caption, dir / file});
    };
    if (fin) {
        add(outdir::kInitialPng, "before: T·E₀ (initial env map)");
        add(outdir::kRenderPng, "after: T·E* (optimized)");
        add(outdir::kEnvMapPng, "optimized env map E*");
        add(outdir::kInitialEnvMapPng, "initial env map E₀");
    } else {
        add(outdir::kInitialPng, "render under E₀");
        add(outdir::kInitialEnvMapPng, "env map E₀");
    }
    add(outdir::kRegionsPng, "defects objective: defect region red, reference blue");
    add(outdir::kScratchMapPng, "scratch map");
    add(outdir::kMaskPng, "loss mask");
    if (fin && std::filesystem::exists(dir / outdir::kLossCsv)) {
        r.loss = readLossCsv(dir / outdir::kLossCsv);
        r.loss.label = r.title;
    }
    return r;
}

std::string renderReportHtml(const ReportContent& c) {
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
      << escapeXml(c.title) << "</title>\n<style>" << kStyle << "</style></head><body>\n";
    h << "<h1>" << escapeXml(c.title) << "</h1>\n";
    for (const auto& n : c.notes) h << "<p class=\"note\">" << escapeXml(n) << "</p>\n";
    if (c.settings.is_object() && !c.settings.empty())
        h << "<h2>Settings</h2>\n" << table({"value"}, {c.settings}, "settings");
    int fig = 0;
    for (const auto& f : c.figures) {
        ++fig;
        h << "<section class=\"figure\" id=\"figure-" << fig << "\"><h2>" << escapeXml(f.title)
          << "</h2>\n";
        if (!f.caption.empty()) h << "<p class=\"caption\">" << escapeXml(f.caption) << "</p>\n";
        h << "<div class=\"runs\">\n";
        std::vector<std::string> cols;
        std::vector<json> metrics, settings;
        std::vector<LossSeries> curves;
        for (const auto& r : f.runs) {
            h << "<figure class=\"run\"><h3>" << escapeXml(r.title) << "</h3>";
            if (!r.caption.empty()) h << "<figcaption>" << escapeXml(r.caption) << "</figcaption>";
            h << "<div class=\"imgs\">";
            for (const auto& im : r.images) {
                const std::string png = readBytes(im.png, "image for the report");
                h << "<figure><img alt=\"" << escapeXml(im.caption)
                  << "\" src=\"data:image/png;base64," << base64Encode(png) << "\"><figcaption>"
                  << escapeXml(im.caption) << "</figcaption></figure>";
            }
            h << "</div>";
            if (!r.loss.loss.empty() && !f.combinedLossPlot)
                h << "<div class=\"loss\">" << lossCurveSvg({r.loss}) << "</div>";
            h << "</figure>\n";
            cols.push_back(r.title);
            metrics.push_back(r.metrics);
            settings.push_back(r.settings);
            if (!r.loss.loss.empty()) {
                curves.push_back(r.loss);
                curves.back().label = r.title;
            }
        }
        h << "</div>\n";
        if (f.combinedLossPlot && !curves.empty())
            h << "<h3>Loss curves</h3>\n<div class=\"loss\">" << lossCurveSvg(curves, 640, 320)
              << "</div>\n";
        std::string mt = table(cols, metrics, "metrics");
        if (!mt.empty()) h << "<h3>Metrics</h3>\n" << mt;
        std::string st = table(cols, settings, "settings");
        if (!st.empty()) h << "<h3>Settings</h3>\n" << st;
        h << "</section>\n";
    }
    h << "<p class=\"caption\">Metrics: gradient = mean |ΔY| over pixel pairs (right and lower "
         "neighbour) with both pixels in the region (inside: the loss mask; outside: the rest "
         "of the part); clipped = share of part pixels with Y ≥ 1 (any channel for RGB); "
         "env sparsity = share of env-map values &lt; 1e-3; env chroma = mean CIE LUV C*uv/100 "
         "of E's texels (0 = gray); truth: mean |ΔY| over pairs touching a true defect / over "
         "the other pairs of the part (objective/Metrics.h).</p>\n";
    h << "</body></html>\n";
    return h.str();
}

void writeReport(const std::filesystem::path& path, const ReportContent& content) {
    writeTextAtomically(path, renderReportHtml(content));
}

namespace {

std::string str(const json& j, const char* key, const std::string& where) {
    if (!j.contains(key)) return {};
    if (!j[key].is_string())
        throw inputError(where, std::string("\"") + key + "\" must be a string");
    return j[key].get<std::string>();
}

void merge(json& into, const json& from) {
    if (!from.is_object()) return;
    if (!into.is_object()) into = json::object();
    for (auto it = from.begin(); it != from.end(); ++it) into[it.key()] = *it;
}

}  // namespace

ReportContent readReportSpec(const std::filesystem::path& specFile) {
    json s = readJsonInput(specFile, "the report spec");
    const auto base = specFile.parent_path();
    const std::string w = specFile.string();
    ReportContent c;
    if (s.contains("title")) c.title = str(s, "title", w);
    if (s.contains("notes"))
        for (const auto& n : s["notes"]) c.notes.push_back(n.get<std::string>());
    if (s.contains("settings")) c.settings = s["settings"];
    if (!s.contains("figures") || !s["figures"].is_array())
        throw inputError(
            w, "needs a \"figures\" array",
            "e.g. {\"figures\": [{\"title\": \"...\", \"runs\": [{\"dir\": \"OUTDIR\"}]}]}");
    int fi = 0;
    for (const auto& f : s["figures"]) {
        const std::string fw = w + ": figures[" + std::to_string(fi++) + "]";
        ReportFigure fig;
        fig.title = str(f, "title", fw);
        fig.caption = str(f, "caption", fw);
        fig.combinedLossPlot = f.value("loss_plot", false);
        int ri = 0;
        for (const auto& r : f.value("runs", json::array())) {
            const std::string rw = fw + ".runs[" + std::to_string(ri++) + "]";
            ReportRun run;
            const std::string state = r.value("state", std::string("final"));
            if (state != "final" && state != "initial")
                throw inputError(rw, "\"state\" must be \"final\" or \"initial\"");
            if (r.contains("dir"))
                run = reportRunFromOutDir(base / str(r, "dir", rw), str(r, "title", rw),
                                          state == "final" ? RunState::Final : RunState::Initial);
            else if (!r.contains("images"))
                throw inputError(rw, "needs \"dir\" (an optimize OUTDIR) or \"images\"");
            if (r.contains("title")) run.title = str(r, "title", rw);
            run.caption = str(r, "caption", rw);
            for (const auto& im : r.value("images", json::array()))
                run.images.push_back({str(im, "caption", rw), base / str(im, "png", rw)});
            if (r.contains("metrics")) merge(run.metrics, r["metrics"]);
            if (r.contains("settings")) merge(run.settings, r["settings"]);
            if (!run.loss.loss.empty()) run.loss.label = run.title;
            fig.runs.push_back(std::move(run));
        }
        c.figures.push_back(std::move(fig));
    }
    return c;
}

}  // namespace sl
