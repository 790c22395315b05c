// scratchlight report (OUTDIR... | --spec FIGURES.json) [-o report.html] [--title T]
//                     [--note TEXT]... [--combined-loss] [--initial]
// The figures page (app/report/Report.h).
//
// report --spec FIGURES.json (paths relative to the spec file):
//   {"title": "...", "notes": ["..."], "settings": {...},
//    "figures": [{"title": "...", "caption": "...", "loss_plot": false,
//                 "runs": [{"dir": "OUTDIR", "title": "...", "caption": "...",
//                           "state": "final" | "initial",
//                           "images": [{"png": "FILE.png", "caption": "..."}],
//                           "metrics": {...}, "settings": {...}}]}]}
// A run needs "dir" (an optimize OUTDIR) or "images" (e.g. a `render` PNG) or both; its
// "metrics"/"settings" are merged over what the OUTDIR provides.
#include <cstdio>
#include <memory>

#include "app/report/Report.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"

namespace sl::cli {

namespace {

struct ReportArgs {
    std::vector<std::string> dirs, notes;
    std::string spec, out = "report.html", title = "scratchlight report";
    bool combinedLoss = false, initial = false;
};

int runReport(const ReportArgs& a) {
    if (a.spec.empty() == a.dirs.empty())
        throw UsageError("give either OUTDIR... or --spec FIGURES.json");
    ReportContent c;
    if (!a.spec.empty()) {
        c = readReportSpec(a.spec);
    } else {
        ReportFigure f;
        f.title = "Runs";
        f.combinedLossPlot = a.combinedLoss;
        for (const auto& d : a.dirs)
            f.runs.push_back(
                reportRunFromOutDir(d, "", a.initial ? RunState::Initial : RunState::Final));
        c.figures.push_back(std::move(f));
        c.title = a.title;
    }
    if (!a.spec.empty() && a.title != "scratchlight report") c.title = a.title;
    for (const auto& n : a.notes) c.notes.push_back(n);
    writeReport(a.out, c);
    size_t runs = 0;
    for (const auto& f : c.figures) runs += f.runs.size();
    std::printf("wrote %s (%zu figure(s), %zu run(s))\n", a.out.c_str(), c.figures.size(), runs);
    return kOk;
}

}  // namespace

void registerReport(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<ReportArgs>();
    CLI::App* c =
        app.add_subcommand("report", "Assemble a self-contained report.html from optimize OUTDIRs");
    c->add_option("outdirs", a->dirs, "optimize OUTDIRs (one figure, one run each)");
    c->add_option("--spec", a->spec,
                  "JSON file grouping runs into figures with captions (see src/cli/"
                  "ReportCmd.cpp for the format)");
    c->add_option("-o,--output", a->out, "The HTML page")->capture_default_str();
    c->add_option("--title", a->title, "Page title")->capture_default_str();
    c->add_option("--note", a->notes, "A paragraph under the title (repeatable)");
    c->add_flag("--combined-loss", a->combinedLoss, "One loss plot for all runs");
    c->add_flag("--initial", a->initial, "Show the runs' initial state instead of the result");
    c->callback([a, &run] { run = [a] { return runReport(*a); }; });
}

}  // namespace sl::cli
