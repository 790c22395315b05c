#include "app/report/Report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/InputFile.h"
#include "io/OptimizeOutDir.h"
#include "objective/DefectVisibility.h"

namespace sl {

using nlohmann::json;

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

namespace {

/// An optimize OUTDIR's summary.json; InputError naming it when missing or malformed.
json readOptimizeSummary(const std::filesystem::path& dir) {
    const auto summaryPath = dir / outdir::kSummary;
    json s = parseJsonInput(readInputFile(summaryPath, "the optimize summary", kMaxJsonFileBytes,
                                          "Check that the file exists (re-run the "
                                          "command that writes it)"),
                            summaryPath.string());
    if (!s.is_object()) throw inputError(summaryPath.string(), "not a JSON object");
    return s;
}

}  // namespace

ReportRun reportRunFromOutDir(const std::filesystem::path& dir, const std::string& title,
                              RunState state) {
    const json s = readOptimizeSummary(dir);
    ReportRun r;
    r.title = title.empty() ? dir.filename().string() : title;
    if (r.title.empty()) r.title = dir.string();
    r.settings = json::object();
    for (auto it = s.begin(); it != s.end(); ++it)
        if (!it->is_object() && !it->is_array()) r.settings[it.key()] = *it;
    r.metrics = json::object();
    const bool fin = state == RunState::Final;
    if (s.contains("initial_loss")) r.metrics["loss_initial"] = s["initial_loss"];
    if (fin && s.contains("final_loss")) r.metrics["loss_final"] = s["final_loss"];
    const char* key = fin ? "metrics" : "metrics_initial";
    if (s.contains(key) && s[key].is_object())
        for (auto it = s[key].begin(); it != s[key].end(); ++it) r.metrics[it.key()] = *it;

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

// ---- optimize's page (renderOptimizeReportHtml) ----

namespace sl {

namespace {

double num(const json& j, const char* key) {
    if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return std::nan("");
    return j[key].get<double>();
}

/// A judge score's regions from its JSON: pixels, visibility and JND (NaN where absent).
std::vector<RegionVisibility> regionsOf(const json& judge) {
    std::vector<RegionVisibility> regions;
    for (const json& r : judge["visibility"]) {
        RegionVisibility v;
        v.visibility = num(r, "visibility");
        v.jnd = num(r, "jnd");
        const double p = num(r, "pixels");
        v.pixels = std::isfinite(p) && p > 0 ? static_cast<size_t>(p) : 0;
        regions.push_back(v);
    }
    return regions;
}

/// All defect regions as one (objective/DefectVisibility.h combinedVisibility) from a judge
/// score's JSON.
double combinedVisibility(const json& judge) {
    if (!judge.is_object() || !judge.contains("visibility")) return std::nan("");
    return sl::combinedVisibility(regionsOf(judge));
}

/// The regions' JND pooled (objective/DefectVisibility.h combinedJnd); NaN without JND.
double combinedJnd(const json& judge) {
    if (!judge.is_object() || !judge.contains("visibility")) return std::nan("");
    return sl::combinedJnd(regionsOf(judge));
}

/// The defects' JND as the answer is chosen on it: the least visible kind's
/// (objective/DefectVisibility.h leastVisibleJnd); NaN without JND.
double leastVisibleJnd(const json& judge) {
    if (!judge.is_object() || !judge.contains("visibility")) return std::nan("");
    return sl::leastVisibleJnd(regionsOf(judge));
}

/// " ± 0.12": the standard error of the least visible kind's JND in a judge score's JSON
/// (app/pipeline/Judge.h toJson, se.least_visible_jnd); empty when it was not estimated.
std::string leastVisibleJndError(const json& judge) {
    if (!judge.is_object() || !judge.contains("se") || !judge["se"].is_object()) return "";
    const json& se = judge["se"];
    if (!se.contains("least_visible_jnd") || !se["least_visible_jnd"].is_number()) return "";
    const double e = se["least_visible_jnd"].get<double>();
    if (!std::isfinite(e)) return "";
    char buf[64];
    std::snprintf(buf, sizeof buf, " ± %.2g", e);
    return buf;
}

/// How many defect kinds the judge scored (regions with pixels).
size_t defectKinds(const json& judge) {
    size_t n = 0;
    if (judge.is_object() && judge.contains("visibility"))
        for (const json& r : judge["visibility"]) n += num(r, "pixels") > 0;
    return n;
}

std::string fmt(double v, int digits = 3) {
    if (!std::isfinite(v)) return "—";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

/// With two or more labelled regions, the one that shows least under the answer, first: "The
/// least visible label is dent: 1.2 (your lamp 3.4)." (empty with fewer regions).
std::string worstLabelSentence(const json& answer, const json& lamp) {
    if (!answer.is_object() || !answer.contains("visibility") || answer["visibility"].size() < 2)
        return "";
    // In JND where the judge has it (the answer is chosen on it), else the visibility ratio.
    const bool jnd = std::isfinite(leastVisibleJnd(answer));
    const char* key = jnd ? "jnd" : "visibility";
    const json* worst = nullptr;
    for (const json& r : answer["visibility"])
        if (std::isfinite(num(r, key)) && num(r, "pixels") > 0 &&
            (!worst || num(r, key) < num(*worst, key)))
            worst = &r;
    if (!worst) return "";
    const std::string name = worst->value("name", std::string("?"));
    double atLamp = std::nan("");
    if (lamp.is_object() && lamp.contains("visibility"))
        for (const json& r : lamp["visibility"])
            if (r.value("name", std::string()) == name) atLamp = num(r, key);
    return " The least visible label is " + name + ": " + fmt(num(*worst, key), 3) +
           (jnd ? " JND" : "") + " (your lamp " + fmt(atLamp, 3) + ").";
}

std::string degrees(const json& d, const char* key) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f°", num(d, key));
    return buf;
}

std::string percent(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.0f %%", 100.0 * v);
    return buf;
}

/// "3.2× as visible as under X" / "less visible than under X (0.8×)".
std::string moreVisible(double opt, double other, const std::string& under) {
    const double r = opt / other;
    std::string out;
    if (!std::isfinite(r)) return "not comparable with " + under;
    if (r >= 1.005) {
        out = fmt(r, 2) + "× as visible as ";
        out += under;
        return out;
    }
    if (r > 0.995) {
        out = "as visible as ";
        out += under;
        out += " (no gain)";
        return out;
    }
    out = "LESS visible than ";
    out += under;
    out += ", only ";
    out += fmt(r, 2);
    out += "× as visible";
    return out;
}

/// "X % lower than under Y" for a loss (lower is better), honest when it is not lower. A loss
/// that can be negative (the defects objective's) has no meaningful ratio: then the difference.
std::string lowerLoss(double opt, double other, const std::string& under) {
    if (!std::isfinite(opt) || !std::isfinite(other) || other == 0)
        return "not comparable with " + under;
    std::string out;
    if (!(other > 0 && opt >= 0)) {
        out = opt < other ? "lower (better) by " : "HIGHER (worse) by ";
        out += fmt(std::abs(opt - other));
        out += " than ";
        out += under;
        return out;
    }
    if (opt < other) {
        out = percent(1.0 - opt / other) + " lower (better) than ";
        out += under;
        return out;
    }
    out = percent(opt / other - 1.0) + " HIGHER (worse) than ";
    out += under;
    return out;
}

/// "1.9 JND above threshold" / "below threshold (0.4 JND)": 1 JND is the threshold of seeing.
/// se: " ± 0.12" or empty (leastVisibleJndError).
std::string jndPhrase(double j, const std::string& se = {}) {
    if (!std::isfinite(j)) return "—";
    if (j >= 1.0) return fmt(j, 3) + se + " JND above threshold";
    return "below threshold (" + fmt(j, 2) + se + " JND)";
}

/// The headline's first sentence in the units of the eye (perception/JndVisibility.h): "Under
/// the optimized light the defects are 8.9 JND above threshold, 3.1 under your lamp (...) and
/// 2.0 under the paper's light, as a person sees the image (38.8 px/deg, white 200 cd/m²). "
/// Empty when the judge has no JND.
std::string jndSentence(const json& opt, const json& lamp, const json& paper,
                        const std::string& underLamp, const json& viewing) {
    const double jo = leastVisibleJnd(opt), jl = leastVisibleJnd(lamp), jp = leastVisibleJnd(paper);
    if (!std::isfinite(jo) || !std::isfinite(jl)) return "";
    const std::string what =
        defectKinds(opt) > 1 ? "the least visible defect kind is" : "the defects are";
    std::string out = "Under the optimized light " + what + " " +
                      jndPhrase(jo, leastVisibleJndError(opt)) + ", " + fmt(jl, 3) +
                      leastVisibleJndError(lamp) + " " + underLamp;
    if (std::isfinite(jp))
        out += " and " + fmt(jp, 3) + leastVisibleJndError(paper) + " under the paper's light";
    out += ", as a person sees the image";
    if (viewing.contains("text") && viewing["text"].is_string())
        out += " (" + viewing["text"].get<std::string>() + ")";
    out += ". ";
    return out;
}

std::string lampUnder(const json& cmp) {
    const json lamp = cmp.value("lamp", json::object());
    std::string out = "under your lamp (";
    out += lamp.value("name", std::string("studio preset"));
    out += ")";
    return out;
}

/// An <img> of `file` in `dir`, or the reason it is missing.
std::string figureOrReason(const std::filesystem::path& dir, const char* file, const char* alt,
                           const std::string& problem, const char* cls = "plot") {
    std::ostringstream h;
    if (std::filesystem::exists(dir / file)) {
        h << "<img class=\"" << cls << "\" alt=\"" << escapeXml(alt) << "\" src=\""
          << dataUri(dir / file) << "\">";
    } else {
        h << "<p class=\"missing\">figure not made: "
          << escapeXml(problem.empty() ? std::string(file) + " was not written" : problem)
          << "</p>";
    }
    return h.str();
}

const char* kOptimizeStyle = R"(
body{font-family:sans-serif;margin:24px;color:#222;max-width:1500px}
h1{font-size:1.5em;margin-bottom:.3em}h2{font-size:1.2em;margin-top:1.8em;border-bottom:1px solid #ccc}
.headline{font-size:1.25em;line-height:1.45;background:#eef6ee;border-left:5px solid #3a8a3a;padding:10px 14px}
.headline.worse{background:#fdeeee;border-left-color:#b33}
.found{font-size:1.05em;line-height:1.4}
.warn{background:#fff8e0;padding:6px 10px;border-left:3px solid #e0b000}
.ab{position:relative;display:inline-block;line-height:0;border:1px solid #999;cursor:crosshair}
.ab img{image-rendering:pixelated;display:block}
.ab .top{position:absolute;left:0;top:0}
.ab .regions{position:absolute;left:0;top:0;display:none}
.ab.show-regions .regions{display:block}
.ab .bar{position:absolute;top:0;bottom:0;width:2px;background:#ff0;pointer-events:none}
.ab .tag{position:absolute;top:6px;font:12px sans-serif;line-height:1.2;background:rgba(0,0,0,.6);color:#fff;padding:2px 6px}
.controls{margin:8px 0;font-size:.9em}.controls input[type=range]{width:320px;vertical-align:middle}
.viewer{display:flex;flex-wrap:wrap;gap:18px;align-items:flex-start}
.loupes{display:flex;gap:10px}
.loupe{width:256px;height:256px;overflow:hidden;position:relative;border:1px solid #999;background:#000}
.loupe img{position:absolute;image-rendering:pixelated;transform-origin:0 0}
figure{margin:0}figcaption{font-size:.85em;color:#555;margin-top:4px;line-height:1.3}
.stills{display:flex;flex-wrap:wrap;gap:12px}.stills img{image-rendering:pixelated;display:block;border:1px solid #ccc}
img.plot{max-width:100%;border:1px solid #ddd}
.missing{color:#a00;font-style:italic}
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}
td,th{border:1px solid #ccc;padding:3px 9px;text-align:right}
tbody th{text-align:left;font-weight:normal;background:#f3f3f3}
td.best{font-weight:bold;background:#eef6ee}
.caption{color:#444;font-size:.9em}
#selfcheck{font-size:.8em;color:#555;background:#f6f6f6;padding:4px 8px}
details{margin-top:1em}
)";

// The page's only script: the A/B slider, the regions toggle, the 1:1 loupes (4× crops where the
// render is clicked) and the self-check that a headless browser reads (#selfcheck).
const char* kOptimizeScript = R"(
(function(){
  var ab=document.getElementById('ab'), top=document.getElementById('ab-top');
  var slider=document.getElementById('ab-slider'), bar=document.getElementById('ab-bar');
  function slide(){var p=slider.value;top.style.clipPath='inset(0 '+(100-p)+'% 0 0)';bar.style.left=p+'%';}
  if(slider){slider.addEventListener('input',slide);slide();}
  var reg=document.getElementById('show-regions');
  if(reg){reg.addEventListener('change',function(){ab.classList.toggle('show-regions',reg.checked);});
          ab.classList.toggle('show-regions',reg.checked);}
  var zoom=4, loupes=document.querySelectorAll('.loupe img');
  function look(x,y){
    loupes.forEach(function(img){
      var src=document.getElementById(img.dataset.of);
      if(!img.src) img.src=src.src;
      img.style.width=(src.naturalWidth*zoom)+'px';
      img.style.left=(128-x*zoom)+'px';img.style.top=(128-y*zoom)+'px';
    });
    var at=document.getElementById('loupe-at'); if(at) at.textContent='pixel ('+x+', '+y+')';
  }
  if(ab){ab.addEventListener('click',function(ev){
    var r=ab.getBoundingClientRect(), im=document.getElementById('ab-bottom');
    var s=im.naturalWidth/r.width;
    look(Math.floor((ev.clientX-r.left)*s),Math.floor((ev.clientY-r.top)*s));});}
  window.addEventListener('load',function(){
    var im=document.getElementById('ab-bottom');
    if(im) look(Math.floor(im.naturalWidth/2),Math.floor(im.naturalHeight/2));
    var bad=[], n=0;
    ['headline','renders','envmap','loss','metrics'].forEach(function(id){
      if(!document.getElementById(id)) bad.push('no section #'+id);});
    if(!document.querySelector('#headline .headline')) bad.push('no headline sentence');
    if(!document.querySelector('#renders input[type=range]')) bad.push('no A/B slider');
    if(!document.querySelector('#envmap img')) bad.push('no env-map plot');
    if(!document.querySelector('#loss img')) bad.push('no loss plot');
    if(!document.querySelector('#metrics table')) bad.push('no metrics table');
    Array.prototype.forEach.call(document.images,function(img){
      if(!img.src) return; n++;
      if(!(img.complete&&img.naturalWidth>0)) bad.push('image not loaded: '+(img.alt||img.id));});
    document.getElementById('selfcheck').textContent=bad.length?
      'selfcheck: FAIL: '+bad.join('; '):'selfcheck: ok ('+n+' images loaded)';
  });
})();
)";

/// One row of the comparison table: the lamp's, the paper's and E*'s value; `lowerBetter`
/// marks the best (-1: no marking).
std::string compareRow(const std::string& name, double lamp, double paper, double opt,
                       int lowerBetter) {
    const double v[3] = {lamp, paper, opt};
    int best = -1;
    if (lowerBetter >= 0)
        for (int k = 0; k < 3; ++k)
            if (std::isfinite(v[k]) &&
                (best < 0 || (lowerBetter ? v[k] < v[best] : v[k] > v[best])))
                best = k;
    std::ostringstream h;
    h << "<tr><th>" << escapeXml(name) << "</th>";
    for (int k = 0; k < 3; ++k)
        h << "<td" << (k == best ? " class=\"best\"" : "") << ">" << escapeXml(fmt(v[k], 4))
          << "</td>";
    h << "</tr>\n";
    return h.str();
}

}  // namespace

/// When the judge sees the defects more under the lamp than under the returned optimized light
/// (JND), why the self-check did not return the lamp (app/pipeline/Answer.h): it failed a check on
/// the validation estimate, or it showed less there. Empty otherwise.
std::string lampNotChosen(const json& s, double jndOptimized, double jndLamp,
                          const std::string& lampName) {
    if (!(jndLamp > jndOptimized) || !s.contains("answer") || !s["answer"].is_object() ||
        !s["answer"].contains("candidates"))
        return "";
    for (const json& c : s["answer"]["candidates"]) {
        if (c.value("name", std::string()) != lampName ||
            c.value("kind", std::string()) != "reference")
            continue;
        if (!c.value("eligible", true))
            return "Your lamp was not the answer: on the validation estimate it did not pass the "
                   "checks (" +
                   c.value("why", std::string()) + "). ";
        const std::string merit = s["answer"].value("merit", std::string("figure"));
        double mo = std::nan("");
        for (const json& o : s["answer"]["candidates"])
            if (o.value("name", std::string()) == s["answer"].value("light", std::string()))
                mo = num(o, "merit");
        return "Your lamp was not the answer: on the validation estimate, where the answer is "
               "chosen, it showed them less (" +
               merit + " " + fmt(num(c, "merit"), 3) + " vs " + fmt(mo, 3) + "). ";
    }
    return "";
}

std::string optimizeHeadline(const json& s) {
    if (!s.contains("compare") || !s["compare"].is_object())
        return "This output directory has no comparison with a lamp (it predates it).";
    const json& cmp = s["compare"];
    const json lamp = cmp.value("lamp", json::object()), paper = cmp.value("paper", json::object()),
               opt = cmp.value("optimized", json::object());
    const std::string underLamp = lampUnder(cmp), underPaper = "under the paper's light";
    std::string out;
    // A reference that beat E* on the validation estimate is the answer (app/pipeline/Answer.h):
    // said first, then the judge's figures of the answer beside E*'s.
    if (cmp.contains("answer") && cmp["answer"].is_object()) {
        const json& ans = cmp["answer"];
        const std::string name = ans.value("name", std::string("a reference light"));
        const std::string why = ans.value("optimized_why", std::string());
        const std::string figures = ans.value("merit", std::string("figure")) + " " +
                                    fmt(num(ans, "merit_answer"), 3) + " vs " +
                                    fmt(num(ans, "merit_optimized"), 3);
        out = "The answer is " + name + ", not the optimized light: " +
              (why.empty() ? "on an independent validation estimate it showed the defects "
                             "better (" +
                                 figures + ")"
                           : "on an independent validation estimate the optimized light did not "
                             "pass the checks (" +
                                 why + "; " + figures + ")") +
              "; the optimized light is kept beside it (envmap-optimized.exr).";
        if (ans.contains("judge") && opt.contains("judge")) {
            const std::string spp = fmt(num(cmp, "judge_spp"), 6);
            const double va = combinedVisibility(ans["judge"]),
                         vo = combinedVisibility(opt["judge"]);
            const double ja = leastVisibleJnd(ans["judge"]), jo = leastVisibleJnd(opt["judge"]);
            if (std::isfinite(ja) && std::isfinite(jo) && std::isfinite(va) && std::isfinite(vo))
                out += std::string(" Judge: ") +
                       (defectKinds(ans["judge"]) > 1 ? "the least visible defect kind is "
                                                      : "the defects are ") +
                       jndPhrase(ja) + " under " + name + ", " + fmt(jo, 3) +
                       " JND under the optimized light (visibility ratio " + fmt(va, 3) + " vs " +
                       fmt(vo, 3) + "), on an independent " + spp + "-spp estimate." +
                       worstLabelSentence(ans["judge"], lamp.value("judge", json::object()));
            else if (std::isfinite(va) && std::isfinite(vo))
                out += " Judge: defect visibility " + fmt(va, 3) + " (" + name + ") vs " +
                       fmt(vo, 3) + " (optimized), on an independent " + spp + "-spp estimate." +
                       worstLabelSentence(ans["judge"], lamp.value("judge", json::object()));
            else
                out += " Judge: U " + fmt(num(ans["judge"], "unbiased"), 3) + " (" + name +
                       ") vs " + fmt(num(opt["judge"], "unbiased"), 3) +
                       " (optimized; lower is better), on an independent " + spp + "-spp estimate.";
        }
        return out;
    }
    if (opt.contains("judge")) {
        const std::string spp = fmt(num(cmp, "judge_spp"), 6);
        const double vo = combinedVisibility(opt["judge"]), vl = combinedVisibility(lamp["judge"]),
                     vp = combinedVisibility(paper["judge"]);
        if (std::isfinite(vo) && std::isfinite(vl) && std::isfinite(vp)) {
            out = jndSentence(opt["judge"], lamp["judge"], paper["judge"], underLamp,
                              cmp.value("viewing", json::object()));
            out += lampNotChosen(s, leastVisibleJnd(opt["judge"]), leastVisibleJnd(lamp["judge"]),
                                 lamp.value("name", std::string()));
            out += (out.empty() ? "Under the optimized light the defects are "
                                : "By the visibility ratio they are ") +
                   moreVisible(vo, vl, underLamp);
            out += " and " + moreVisible(vo, vp, "under the paper's light");
            out += ". Judge: defect visibility " + fmt(vo, 3) + " (optimized) vs " + fmt(vl, 3) +
                   " (your lamp) vs " + fmt(vp, 3);
            out += " (paper's light), on an independent " + spp + "-spp estimate.";
            out += worstLabelSentence(opt["judge"], lamp["judge"]);
            return out;
        }
        const double uo = num(opt["judge"], "unbiased"), ul = num(lamp["judge"], "unbiased"),
                     up = num(paper["judge"], "unbiased");
        out =
            "No defect region is known, so the judge's loss U (image gradient over the part, "
            "noise-unbiased; lower is better) stands for visibility: under the optimized "
            "light it is " +
            lowerLoss(uo, ul, underLamp);
        out += " and " + lowerLoss(uo, up, underPaper);
        out += " (U " + fmt(uo, 3) + " vs " + fmt(ul, 3) + " vs " + fmt(up, 3) +
               ", on an independent " + spp + "-spp estimate).";
        return out;
    }
    const json& to = opt.value("training", json::object());
    const double lo = num(to, "loss"), ll = num(lamp.value("training", json::object()), "loss"),
                 lp = num(paper.value("training", json::object()), "loss");
    out = "Training figures only (no judge's estimate was asked for): the " +
          cmp.value("objective", std::string("objective")) +
          " loss (lower is better) under the optimized light is " + lowerLoss(lo, ll, underLamp);
    out += " and " + lowerLoss(lo, lp, underPaper);
    out += " (" + fmt(lo, 3) + " vs " + fmt(ll, 3) + " vs " + fmt(lp, 3) + ").";
    return out;
}

std::string heightmapSentence(const json& hm) {
    std::ostringstream f;
    f << "The part: "
      << std::filesystem::path(hm.value("file", std::string("?"))).filename().string() << " ("
      << hm.value("format", std::string("?")) << ")";
    if (hm.contains("size") && hm["size"].is_array() && hm["size"].size() == 2)
        f << ", " << hm["size"][0].dump() << "×" << hm["size"][1].dump() << " samples";
    if (hm.contains("pitch") && hm["pitch"].is_number())
        f << " at " << fmt(hm["pitch"].get<double>(), 4) << " mm";
    if (hm.contains("resampling") && hm["resampling"].is_string())
        f << "; " << hm["resampling"].get<std::string>();
    f << ".";
    if (hm.contains("levelling") && hm["levelling"].is_object()) {
        const json& l = hm["levelling"];
        f << " Levelling: " << l.value("mode", std::string("?"));
        if (l.value("auto", false)) f << " (the default for this kind of map)";
        if (l.contains("rms_before") && l["rms_before"].is_number() && l["rms_after"].is_number())
            f << ", RMS height " << fmt(l["rms_before"].get<double>(), 4) << " → "
              << fmt(l["rms_after"].get<double>(), 4) << " mm over "
              << l.value("points", json(0)).dump() << " valid points";
        if (l.contains("radius") && l["radius"].is_number())
            f << ", cylinder radius " << fmt(std::abs(l["radius"].get<double>()), 4) << " mm";
        f << ".";
    }
    return f.str();
}

std::string optimizeHeadlineOf(const std::filesystem::path& outDir) {
    return optimizeHeadline(readOptimizeSummary(outDir));
}

std::string renderOptimizeReportHtml(const std::filesystem::path& dir,
                                     const std::string& figureProblem) {
    const json s = readOptimizeSummary(dir);
    const json cmp = s.value("compare", json::object());
    const json lamp = cmp.value("lamp", json::object()), paper = cmp.value("paper", json::object()),
               opt = cmp.value("optimized", json::object());
    const std::string lampName = lamp.value("name", std::string("studio preset"));
    const std::string headline = optimizeHeadline(s);
    const bool worse =
        headline.find("LESS") != std::string::npos || headline.find("HIGHER") != std::string::npos;
    std::ostringstream h;
    std::string title = "scratchlight optimize: the light that shows the defects";
    if (s.contains("lambda") && s["lambda"].is_number())
        title += " (λ " + fmt(num(s, "lambda"), 4) + ")";
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
      << escapeXml(title) << "</title>\n<style>" << kOptimizeStyle << "</style></head><body>\n";

    // 1. The first screen: what was found and how much better it is, in words.
    h << "<section id=\"headline\"><h1>" << escapeXml(title) << "</h1>\n";
    h << "<p class=\"headline" << (worse ? " worse" : "") << "\">" << escapeXml(headline)
      << "</p>\n";
    {
        std::ostringstream f;
        const json dirs = s.value("envmap_directions", json::object());
        const json bright = dirs.value("brightest", json::array());
        if (!bright.empty()) {
            f << "The optimized light comes mainly from azimuth "
              << degrees(bright[0], "azimuth_deg") << ", elevation "
              << degrees(bright[0], "elevation_deg");
            for (size_t k = 1; k < bright.size(); ++k)
                f << (k + 1 == bright.size() ? " and " : "; ") << "azimuth "
                  << degrees(bright[k], "azimuth_deg") << ", elevation "
                  << degrees(bright[k], "elevation_deg");
            f << " (brightest directions of the env map";
            if (dirs.contains("camera"))
                f << "; the camera is at azimuth " << degrees(dirs["camera"], "azimuth_deg")
                  << ", elevation " << degrees(dirs["camera"], "elevation_deg");
            f << "). ";
        }
        f << "It was found with " << s.value("optimizer", std::string("?")) << " on the "
          << s.value("objective", std::string("?")) << " objective, λ " << fmt(num(s, "lambda"), 4)
          << ". The paper's light is "
          << "the paper's method run "
          << "on our T (eq. 2, λ 30, Adam lr 0.02 × 100 from E₀ = 0.5), not the paper's own "
          << "result.";
        if (cmp.contains("regions") && !cmp["regions"].get<std::string>().empty())
            f << " Defect regions: " << cmp["regions"].get<std::string>() << ".";
        h << "<p class=\"found\">" << escapeXml(f.str()) << "</p>\n";
    }
    if (s.contains("heightmap") && s["heightmap"].is_object())
        h << "<p class=\"part\">" << escapeXml(heightmapSentence(s["heightmap"])) << "</p>\n";
    if (s.contains("warnings"))
        for (const json& w : s["warnings"])
            h << "<p class=\"warn\">" << escapeXml(w.get<std::string>()) << "</p>\n";
    h << "</section>\n";

    // 2. The renders: A/B slider, the regions' outline, 1:1 crops.
    h << "<section id=\"renders\"><h2>Before (your lamp) and after (optimized), full size</h2>\n";
    const bool regions = std::filesystem::exists(dir / outdir::kViewRegions);
    if (std::filesystem::exists(dir / outdir::kViewLamp) &&
        std::filesystem::exists(dir / outdir::kViewOptimized)) {
        h << "<div class=\"controls\"><label>your lamp ◀ <input type=\"range\" id=\"ab-slider\" "
             "min=\"0\" max=\"100\" value=\"50\" aria-label=\"A/B position\"> ▶ "
             "optimized</label>";
        if (regions)
            h << " &nbsp; <label><input type=\"checkbox\" id=\"show-regions\" checked> outline "
                 "the defect regions</label>";
        // Full size (1:1); a render narrower than 400 pixels is shown enlarged by a whole factor.
        int width = 0;
        if (s.contains("transport") && s["transport"].contains("image") &&
            s["transport"]["image"].is_array() && !s["transport"]["image"].empty())
            width = s["transport"]["image"][0].get<int>();
        std::string size;
        if (width > 0 && width < 400)
            size = " style=\"width:" + std::to_string(400 / width * width) + "px\"";
        h << " &nbsp; click the render for a 4× crop</div>\n<div class=\"viewer\"><div "
             "class=\"ab\" id=\"ab\"><img id=\"ab-bottom\" alt=\"after: optimized light\""
          << size << " src=\"" << dataUri(dir / outdir::kViewOptimized)
          << "\"><img id=\"ab-top\" class=\"top\" alt=\"before: your lamp\"" << size << " src=\""
          << dataUri(dir / outdir::kViewLamp) << "\">";
        if (regions)
            h << "<img class=\"regions\" alt=\"defect regions outlined\"" << size << " src=\""
              << dataUri(dir / outdir::kViewRegions) << "\">";
        h << "<div class=\"bar\" id=\"ab-bar\"></div><span class=\"tag\" style=\"left:6px\">"
          << escapeXml(lampName)
          << "</span><span class=\"tag\" style=\"right:6px\">optimized</span></div>\n";
        h << "<div><div class=\"loupes\"><figure><div class=\"loupe\"><img alt=\"\" "
             "data-of=\"ab-top\"></div><figcaption>your lamp, 4×</figcaption></figure>"
             "<figure><div class=\"loupe\"><img alt=\"\" data-of=\"ab-bottom\"></div>"
             "<figcaption>optimized, 4×</figcaption></figure></div><p class=\"caption\" "
             "id=\"loupe-at\"></p></div></div>\n";
    }
    h << "<p class=\"caption\">T·E at full resolution, each exposed on its own (the part's 99th "
         "percentile at 0.8), as a camera would. Drag the slider to move between your lamp ("
      << escapeXml(lampName) << ") on the left and the optimized light on the right.";
    if (regions)
        h << " Outlines: " << escapeXml(cmp.value("regions", std::string("defect regions")))
          << " (red 255, orange 224, magenta 192, yellow 160, cyan 144, blue 128).";
    h << "</p>\n";
    if (std::filesystem::exists(dir / outdir::kViewPaper))
        h << "<div class=\"stills\"><figure><img alt=\"the paper's light\" src=\""
          << dataUri(dir / outdir::kViewPaper)
          << "\"><figcaption>under the paper's light (its method on our T)</figcaption></figure>"
             "</div>\n";
    h << "</section>\n";

    // 3. The env map as a plot; 4. the loss curve (app/report/OptimizeFigures.h).
    h << "<section id=\"envmap\"><h2>The light: env map with axes</h2>\n"
      << figureOrReason(dir, outdir::kPlotEnvMap, "env-map plot", figureProblem)
      << "<p class=\"caption\">Azimuth 0° points toward −z, 90° toward +x; elevation 90° is "
         "straight up (+Y), 0° the horizon (scene/EnvMapBasis.h). The camera and the mirror "
         "direction (what a flat part reflects into the camera) are marked.</p></section>\n";
    h << "<section id=\"loss\"><h2>Loss during the optimization</h2>\n"
      << figureOrReason(dir, outdir::kPlotLoss, "loss plot", figureProblem)
      << "<p class=\"caption\">The optimizer's loss on its training estimate and, every few "
         "iterations, the same objective on the held-out estimate (lower is better; "
         "summary.json heldout_U has the noise-unbiased U there).</p></section>\n";

    // 5. The numbers: the three lights side by side, then before/after metrics and settings.
    h << "<section id=\"metrics\"><h2>The numbers</h2>\n";
    h << "<table class=\"compare\"><thead><tr><th></th><th>your lamp (" << escapeXml(lampName)
      << ")</th><th>paper's light</th><th>optimized</th></tr></thead><tbody>\n";
    if (opt.contains("judge")) {
        const json &jl = lamp["judge"], &jp = paper["judge"], &jo = opt["judge"];
        // JND first (as a person sees it: README "Visibility in JND"), the ratio beside it.
        if (std::isfinite(leastVisibleJnd(jo))) {
            h << compareRow("judge: JND of the least visible defect kind", leastVisibleJnd(jl),
                            leastVisibleJnd(jp), leastVisibleJnd(jo), 0);
            if (defectKinds(jo) > 1)
                h << compareRow("judge: JND of all defect kinds pooled", combinedJnd(jl),
                                combinedJnd(jp), combinedJnd(jo), 0);
        }
        h << compareRow("judge: defect visibility (all regions)", combinedVisibility(jl),
                        combinedVisibility(jp), combinedVisibility(jo), 0);
        if (jo.contains("visibility"))
            for (size_t k = 0; k < jo["visibility"].size(); ++k) {
                const std::string name = jo["visibility"][k].value("name", std::string("?"));
                auto at = [&](const json& j, const char* key) {
                    return j.contains("visibility") && k < j["visibility"].size()
                               ? num(j["visibility"][k], key)
                               : std::nan("");
                };
                if (std::isfinite(at(jo, "jnd")))
                    h << compareRow("judge: JND of " + name, at(jl, "jnd"), at(jp, "jnd"),
                                    at(jo, "jnd"), 0);
                h << compareRow("judge: visibility of " + name, at(jl, "visibility"),
                                at(jp, "visibility"), at(jo, "visibility"), 0);
                h << compareRow("judge: contrast of " + name, at(jl, "contrast"),
                                at(jp, "contrast"), at(jo, "contrast"), 0);
            }
        h << compareRow("judge: U (lower is better)", num(jl, "unbiased"), num(jp, "unbiased"),
                        num(jo, "unbiased"), 1);
        h << compareRow("judge: eq. 2 (lower is better)", num(jl, "eq2"), num(jp, "eq2"),
                        num(jo, "eq2"), 1);
        h << compareRow("brightness (white sky = 1)", num(jl, "brightness"), num(jp, "brightness"),
                        num(jo, "brightness"), -1);
        h << compareRow("mean E", num(jl, "mean_E"), num(jp, "mean_E"), num(jo, "mean_E"), -1);
        h << compareRow("share of dark texels", num(jl, "sparsity"), num(jp, "sparsity"),
                        num(jo, "sparsity"), -1);
    }
    auto training = [](const json& j) { return num(j.value("training", json::object()), "loss"); };
    h << compareRow(
        "training loss (" + cmp.value("objective", std::string("objective")) + ", lower is better)",
        training(lamp), training(paper), training(opt), 1);
    // The held-out figures of the run: the objective it optimized on the independent estimate,
    // and U there (scored for the returned light only).
    if (s.contains("heldout_loss") && s["heldout_loss"].is_number()) {
        const double nan = std::nan("");
        h << compareRow("held out: the " + cmp.value("objective", std::string("objective")) +
                            " loss on the independent estimate (lower is better)",
                        nan, nan, num(s, "heldout_loss"), -1);
        if (s.contains("heldout_U"))
            h << compareRow("held out: U on the independent estimate (lower is better)", nan, nan,
                            num(s, "heldout_U"), -1);
    }
    h << "</tbody></table>\n<p class=\"caption\">JND: how many times its threshold a person "
         "sees the region on the screen (1: at the threshold, 0: nothing to see; the viewing "
         "model in summary.json compare.viewing). Defect visibility: a region's RMS image "
         "gradient (noise-unbiased, from two independent halves of the judge's estimate) over "
         "that of the defect-free surface; 1 = no more salient than the machining texture. "
         "\"All regions\" pools every region's pixels. Contrast: the RMS gradient over the "
         "part's mean brightness. Bold: the best of the three.</p>\n";
    const ReportRun run = reportRunFromOutDir(dir);
    std::string mt = table({"value"}, {run.metrics}, "metrics");
    if (!mt.empty()) h << "<details><summary>All metrics of E*</summary>" << mt << "</details>\n";
    std::string st = table({"value"}, {run.settings}, "settings");
    if (!st.empty()) h << "<details><summary>Settings</summary>" << st << "</details>\n";
    h << "</section>\n";
    h << "<section id=\"overview\"><h2>Overview figure</h2>\n"
      << figureOrReason(dir, outdir::kOverview, "overview", figureProblem) << "</section>\n";
    h << "<pre id=\"selfcheck\">selfcheck: the page's script did not run</pre>\n";
    h << "<script>" << kOptimizeScript << "</script>\n</body></html>\n";
    return h.str();
}

}  // namespace sl
