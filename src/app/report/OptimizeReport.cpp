// optimize's own page (app/report/OptimizeReport.h): the headline in words, the renders with an
// A/B slider, the env map, the loss and the three lights' metrics.
#include "app/report/OptimizeReport.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/report/Preview.h"
#include "app/report/Report.h"
#include "app/report/ReportDetail.h"
#include "core/Error.h"
#include "core/Text.h"
#include "io/OptimizeOutDir.h"
#include "io/OptimizeSummary.h"
#include "objective/DefectVisibility.h"
#include "optimize/PaperSetup.h"

namespace sl {

using nlohmann::json;
using report::table;

namespace {

/// A light's judge score as summary.json records it (io/OptimizeSummary.h), none when the run
/// had no judge's estimate.
using Judged = std::optional<outdir::JudgedLight>;

/// A judge score's regions: pixels, visibility and JND (NaN where absent).
std::vector<RegionVisibility> regionsOf(const std::vector<outdir::JudgedRegion>& judged) {
    std::vector<RegionVisibility> regions;
    for (const outdir::JudgedRegion& r : judged) {
        RegionVisibility v;
        v.visibility = r.visibility;
        v.jnd = r.jnd;
        v.pixels = std::isfinite(r.pixels) && r.pixels > 0 ? static_cast<size_t>(r.pixels) : 0;
        regions.push_back(v);
    }
    return regions;
}

/// All defect regions as one (objective/DefectVisibility.h combinedVisibility) from a judge
/// score; NaN without regions.
double combinedVisibility(const Judged& judge) {
    if (!judge || !judge->regions) return std::nan("");
    return sl::combinedVisibility(regionsOf(*judge->regions));
}

/// The regions' JND pooled (objective/DefectVisibility.h combinedJnd); NaN without JND.
double combinedJnd(const Judged& judge) {
    if (!judge || !judge->regions) return std::nan("");
    return sl::combinedJnd(regionsOf(*judge->regions));
}

/// The defects' JND as the answer is chosen on it: the least visible kind's
/// (objective/DefectVisibility.h leastVisibleJnd); NaN without JND.
double leastVisibleJnd(const Judged& judge) {
    if (!judge || !judge->regions) return std::nan("");
    return sl::leastVisibleJnd(regionsOf(*judge->regions));
}

/// " ± 0.12": the standard error of the least visible kind's JND in a judge score
/// (app/pipeline/Judge.h toJson, se.least_visible_jnd); empty when it was not estimated.
std::string leastVisibleJndError(const Judged& judge) {
    if (!judge || !std::isfinite(judge->leastVisibleJndSe)) return "";
    char buf[64];
    std::snprintf(buf, sizeof buf, " ± %.2g", judge->leastVisibleJndSe);
    return buf;
}

/// How many defect kinds the judge scored (regions with pixels).
size_t defectKinds(const Judged& judge) {
    size_t n = 0;
    if (judge && judge->regions)
        for (const outdir::JudgedRegion& r : *judge->regions) n += r.pixels > 0;
    return n;
}

/// A judge score's number, NaN without the judge's estimate.
double judged(const Judged& judge, double outdir::JudgedLight::*figure) {
    return judge ? (*judge).*figure : std::nan("");
}

std::string fmt(double v, int digits = 3) {
    if (!std::isfinite(v)) return "—";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

/// With two or more labelled regions, the one that shows least under the answer, first: "The
/// least visible label is dent: 1.2 (your lamp 3.4)." (empty with fewer regions).
std::string worstLabelSentence(const Judged& answer, const Judged& lamp) {
    if (!answer || !answer->regions || answer->regions->size() < 2) return "";
    // In JND where the judge has it (the answer is chosen on it), else the visibility ratio.
    const bool jnd = std::isfinite(leastVisibleJnd(answer));
    double outdir::JudgedRegion::*key =
        jnd ? &outdir::JudgedRegion::jnd : &outdir::JudgedRegion::visibility;
    const outdir::JudgedRegion* worst = nullptr;
    for (const outdir::JudgedRegion& r : *answer->regions)
        if (std::isfinite(r.*key) && r.pixels > 0 && (!worst || r.*key < (*worst).*key)) worst = &r;
    if (!worst) return "";
    const std::string name = worst->name.empty() ? std::string("?") : worst->name;
    double atLamp = std::nan("");
    if (lamp && lamp->regions)
        for (const outdir::JudgedRegion& r : *lamp->regions)
            if (r.name == name) atLamp = r.*key;
    return " The least visible label is " + name + ": " + fmt((*worst).*key, 3) +
           (jnd ? " JND" : "") + " (your lamp " + fmt(atLamp, 3) + ").";
}

std::string degrees(double deg) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.0f°", deg);
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

/// With the JND first, the visibility ratio says how far the defects stand out of the texture:
/// "2.6× as much as under X" / "as much as under X" / "LESS than under X (0.81× as much)".
std::string standOut(double opt, double other, const std::string& under) {
    const double r = opt / other;
    if (!std::isfinite(r)) return "(no comparison with " + under + ")";
    if (r >= 1.005) return fmt(r, 2) + "× as much as " + under;
    if (r > 0.995) return "as much as " + under;
    return "LESS than " + under + " (" + fmt(r, 2) + "× as much)";
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
std::string jndSentence(const Judged& opt, const Judged& lamp, const Judged& paper,
                        const std::string& underLamp, const std::string& viewing) {
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
    if (!viewing.empty()) out += " (" + viewing + ")";
    out += ". ";
    return out;
}

/// The user's lamp's name in the comparison (the studio preset when it names none).
std::string lampNameOf(const outdir::Comparison& c) {
    return c.lamp.name.empty() ? std::string("studio preset") : c.lamp.name;
}

std::string lampUnder(const outdir::Comparison& c) {
    std::string out = "under your lamp (";
    out += lampNameOf(c);
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

/// When the judge sees the defects more under the lamp than under the returned optimized light
/// (JND), why the self-check did not return the lamp (app/pipeline/Answer.h): it failed a check on
/// the validation estimate, or it showed less there. Empty otherwise.
std::string lampNotChosen(const std::optional<outdir::AnswerCheck>& answer, double jndOptimized,
                          double jndLamp, const std::string& lampName) {
    if (!(jndLamp > jndOptimized) || !answer) return "";
    for (const outdir::AnswerCandidate& c : answer->candidates) {
        if (c.name != lampName || c.kind != "reference") continue;
        if (!c.eligible)
            return "Your lamp was not the answer: on the validation estimate it did not pass the "
                   "checks (" +
                   c.why + "). ";
        const std::string merit = answer->merit.empty() ? "figure" : answer->merit;
        double mo = std::nan("");
        for (const outdir::AnswerCandidate& o : answer->candidates)
            if (o.name == answer->light) mo = o.merit;
        return "Your lamp was not the answer: on the validation estimate, where the answer is "
               "chosen, it showed them less (" +
               merit + " " + fmt(c.merit, 3) + " vs " + fmt(mo, 3) + "). ";
    }
    return "";
}

/// The headline from the summary typed (optimizeHeadline).
std::string headlineOf(const outdir::OptimizeSummary& summary) {
    if (!summary.comparison)
        return "This output directory has no comparison with a lamp (it predates it).";
    const outdir::Comparison& cmp = *summary.comparison;
    const outdir::ComparedLight &lamp = cmp.lamp, &paper = cmp.paper, &opt = cmp.optimized;
    const std::string underLamp = lampUnder(cmp), underPaper = "under the paper's light";
    const std::string spp = fmt(summary.judgeSpp ? *summary.judgeSpp : std::nan(""), 6);
    const std::string objective = cmp.objective.empty() ? "objective" : cmp.objective;
    std::string out;
    // A reference that beat E* on the validation estimate is the answer (app/pipeline/Answer.h):
    // said first, then the judge's figures of the answer beside E*'s.
    if (cmp.answer) {
        const outdir::ComparedAnswer& ans = *cmp.answer;
        const std::string name = ans.name.empty() ? "a reference light" : ans.name;
        const std::string& why = ans.optimizedWhy;
        const std::string figures = (ans.merit.empty() ? "figure" : ans.merit) + " " +
                                    fmt(ans.meritAnswer, 3) + " vs " + fmt(ans.meritOptimized, 3);
        out = "The answer is " + name + ", not the optimized light: " +
              (why.empty() ? "on an independent validation estimate it showed the defects "
                             "better (" +
                                 figures + ")"
                           : "on an independent validation estimate the optimized light did not "
                             "pass the checks (" +
                                 why + "; " + figures + ")") +
              "; the optimized light is kept beside it (envmap-optimized.exr).";
        if (ans.judge && opt.judge) {
            const double va = combinedVisibility(ans.judge), vo = combinedVisibility(opt.judge);
            const double ja = leastVisibleJnd(ans.judge), jo = leastVisibleJnd(opt.judge);
            if (std::isfinite(ja) && std::isfinite(jo) && std::isfinite(va) && std::isfinite(vo))
                out += std::string(" Judge: ") +
                       (defectKinds(ans.judge) > 1 ? "the least visible defect kind is "
                                                   : "the defects are ") +
                       jndPhrase(ja) + " under " + name + ", " + fmt(jo, 3) +
                       " JND under the optimized light (visibility ratio " + fmt(va, 3) + " vs " +
                       fmt(vo, 3) + "), on an independent " + spp + "-spp estimate." +
                       worstLabelSentence(ans.judge, lamp.judge);
            else if (std::isfinite(va) && std::isfinite(vo))
                out += " Judge: defect visibility " + fmt(va, 3) + " (" + name + ") vs " +
                       fmt(vo, 3) + " (optimized), on an independent " + spp + "-spp estimate." +
                       worstLabelSentence(ans.judge, lamp.judge);
            else
                out += " Judge: U " + fmt(ans.judge->unbiased, 3) + " (" + name + ") vs " +
                       fmt(opt.judge->unbiased, 3) +
                       " (optimized; lower is better), on an independent " + spp + "-spp estimate.";
        }
        return out;
    }
    if (opt.judge) {
        const double vo = combinedVisibility(opt.judge), vl = combinedVisibility(lamp.judge),
                     vp = combinedVisibility(paper.judge);
        if (std::isfinite(vo) && std::isfinite(vl) && std::isfinite(vp)) {
            out = jndSentence(opt.judge, lamp.judge, paper.judge, underLamp, cmp.viewing);
            out += lampNotChosen(summary.answer, leastVisibleJnd(opt.judge),
                                 leastVisibleJnd(lamp.judge), lamp.name);
            if (out.empty()) {  // no JND: the visibility ratio is the visibility
                out = "Under the optimized light the defects are " + moreVisible(vo, vl, underLamp);
                out += " and " + moreVisible(vo, vp, "under the paper's light");
                out += ". Judge: defect visibility " + fmt(vo, 3) + " (optimized) vs " +
                       fmt(vl, 3) + " (your lamp) vs " + fmt(vp, 3);
            } else {  // JND first; the ratio says how far they stand out of the texture
                out +=
                    "By the visibility ratio (their gradient over the texture's) they stand "
                    "out of the texture " +
                    standOut(vo, vl, underLamp) + " and " +
                    standOut(vo, vp, "under the paper's light");
                if (vo < vl / 1.005) out += ": this light shows the texture more strongly too";
                out += ". Judge: visibility ratio " + fmt(vo, 3) + " (optimized) vs " + fmt(vl, 3) +
                       " (your lamp) vs " + fmt(vp, 3);
            }
            out += " (paper's light), on an independent " + spp + "-spp estimate.";
            out += worstLabelSentence(opt.judge, lamp.judge);
            return out;
        }
        const double uo = opt.judge->unbiased,
                     ul = judged(lamp.judge, &outdir::JudgedLight::unbiased),
                     up = judged(paper.judge, &outdir::JudgedLight::unbiased);
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
    const double lo = opt.trainingLoss, ll = lamp.trainingLoss, lp = paper.trainingLoss;
    out = "Training figures only (no judge's estimate was asked for): the " + objective +
          " loss (lower is better) under the optimized light is " + lowerLoss(lo, ll, underLamp);
    out += " and " + lowerLoss(lo, lp, underPaper);
    out += " (" + fmt(lo, 3) + " vs " + fmt(ll, 3) + " vs " + fmt(lp, 3) + ").";
    return out;
}

/// The outlines' colours: each judged region's name and colour (outlineOf its label), else
/// (no judge) the colour of each value.
std::string outlineLegend(const outdir::Comparison& cmp) {
    std::string out;
    const auto& judged = cmp.optimized.judge;
    if (judged && judged->regions)
        for (const outdir::JudgedRegion& r : *judged->regions) {
            if (r.pixels <= 0 || r.value < 1 || r.value > 255) continue;
            out += (out.empty() ? "" : ", ") + r.name + " " +
                   outlineOf(static_cast<uint8_t>(r.value)).name;
        }
    if (out.empty())
        for (const OutlineColour& c : outlineColours())
            out += (out.empty() ? "" : ", ") + std::string(c.name) + " " + std::to_string(c.value);
    return out;
}

}  // namespace

std::string optimizeHeadline(const json& s) {
    return headlineOf(outdir::optimizeSummaryFromJson(s, "summary.json"));
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
    if (hm.contains("channel") && hm["channel"].is_string())
        f << "; " << hm["channel"].get<std::string>();
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
    return headlineOf(outdir::readOptimizeSummary(outDir));
}

std::string renderOptimizeReportHtml(const std::filesystem::path& dir,
                                     const std::string& figureProblem) {
    const outdir::OptimizeSummary summary = outdir::readOptimizeSummary(dir);
    const outdir::Comparison cmp = summary.comparison.value_or(outdir::Comparison{});
    const outdir::ComparedLight &lamp = cmp.lamp, &paper = cmp.paper, &opt = cmp.optimized;
    const std::string lampName = lampNameOf(cmp);
    const std::string objective = cmp.objective.empty() ? "objective" : cmp.objective;
    const std::string headline = headlineOf(summary);
    // Worse than the lamp: in JND when the judge has it (the visibility; a ratio below the
    // lamp's only says the texture shows more too), else by the ratio or U.
    const double jndOpt = leastVisibleJnd(opt.judge), jndLamp = leastVisibleJnd(lamp.judge);
    const bool referenceWon = summary.answer && summary.answer->kind == "reference";
    const bool worse = std::isfinite(jndOpt) && std::isfinite(jndLamp)
                           ? !referenceWon && jndOpt < jndLamp
                           : headline.find("LESS visible") != std::string::npos ||
                                 headline.find("HIGHER") != std::string::npos;
    std::ostringstream h;
    std::string title = "scratchlight optimize: the light that shows the defects";
    if (std::isfinite(summary.lambda)) title += " (λ " + fmt(summary.lambda, 4) + ")";
    h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
      << escapeXml(title) << "</title>\n<style>" << kOptimizeStyle << "</style></head><body>\n";

    // 1. The first screen: what was found and how much better it is, in words.
    h << "<section id=\"headline\"><h1>" << escapeXml(title) << "</h1>\n";
    h << "<p class=\"headline" << (worse ? " worse" : "") << "\">" << escapeXml(headline)
      << "</p>\n";
    {
        std::ostringstream f;
        const outdir::EnvDirections dirs =
            summary.envmapDirections.value_or(outdir::EnvDirections{});
        const std::vector<outdir::EnvDirection>& bright = dirs.brightest;
        if (!bright.empty()) {
            f << "The optimized light comes mainly from azimuth " << degrees(bright[0].azimuthDeg)
              << ", elevation " << degrees(bright[0].elevationDeg);
            for (size_t k = 1; k < bright.size(); ++k)
                f << (k + 1 == bright.size() ? " and " : "; ") << "azimuth "
                  << degrees(bright[k].azimuthDeg) << ", elevation "
                  << degrees(bright[k].elevationDeg);
            f << " (brightest directions of the env map";
            if (dirs.camera)
                f << "; the camera is at azimuth " << degrees(dirs.camera->azimuthDeg)
                  << ", elevation " << degrees(dirs.camera->elevationDeg);
            f << "). ";
        }
        f << "It was found with " << (summary.optimizer.empty() ? "?" : summary.optimizer)
          << " on the " << (summary.objective.empty() ? "?" : summary.objective) << " objective, λ "
          << fmt(summary.lambda, 4)
          << ". The paper's light is the paper's method run on our T (eq. 2, λ "
          << kPaperSetup.lambda << ", Adam lr " << kPaperSetup.learningRate << " × "
          << kPaperSetup.steps << " from E₀ = " << kPaperSetup.start
          << "), not the paper's own result.";
        if (cmp.regions && !cmp.regions->empty()) f << " Defect regions: " << *cmp.regions << ".";
        h << "<p class=\"found\">" << escapeXml(f.str()) << "</p>\n";
    }
    if (summary.heightmap.is_object())
        h << "<p class=\"part\">" << escapeXml(heightmapSentence(summary.heightmap)) << "</p>\n";
    for (const std::string& w : summary.warnings)
        h << "<p class=\"warn\">" << escapeXml(w) << "</p>\n";
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
        const int width = summary.image ? (*summary.image)[0] : 0;
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
        h << " Outlines: " << escapeXml(cmp.regions.value_or("defect regions")) << " ("
          << escapeXml(outlineLegend(cmp)) << ").";
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
    if (opt.judge) {
        const Judged &jl = lamp.judge, &jp = paper.judge, &jo = opt.judge;
        using L = outdir::JudgedLight;
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
        if (jo->regions)
            for (size_t k = 0; k < jo->regions->size(); ++k) {
                const std::string& named = (*jo->regions)[k].name;
                const std::string name = named.empty() ? std::string("?") : named;
                auto at = [&](const Judged& j, double outdir::JudgedRegion::*figure) {
                    return j && j->regions && k < j->regions->size() ? (*j->regions)[k].*figure
                                                                     : std::nan("");
                };
                using R = outdir::JudgedRegion;
                if (std::isfinite(at(jo, &R::jnd)))
                    h << compareRow("judge: JND of " + name, at(jl, &R::jnd), at(jp, &R::jnd),
                                    at(jo, &R::jnd), 0);
                h << compareRow("judge: visibility of " + name, at(jl, &R::visibility),
                                at(jp, &R::visibility), at(jo, &R::visibility), 0);
                h << compareRow("judge: contrast of " + name, at(jl, &R::contrast),
                                at(jp, &R::contrast), at(jo, &R::contrast), 0);
            }
        h << compareRow("judge: U (lower is better)", judged(jl, &L::unbiased),
                        judged(jp, &L::unbiased), judged(jo, &L::unbiased), 1);
        h << compareRow("judge: eq. 2 (lower is better)", judged(jl, &L::eq2), judged(jp, &L::eq2),
                        judged(jo, &L::eq2), 1);
        h << compareRow("brightness (white sky = 1)", judged(jl, &L::brightness),
                        judged(jp, &L::brightness), judged(jo, &L::brightness), -1);
        h << compareRow("mean E", judged(jl, &L::meanE), judged(jp, &L::meanE),
                        judged(jo, &L::meanE), -1);
        h << compareRow("share of dark texels", judged(jl, &L::sparsity), judged(jp, &L::sparsity),
                        judged(jo, &L::sparsity), -1);
    }
    h << compareRow("training loss (" + objective + ", lower is better)", lamp.trainingLoss,
                    paper.trainingLoss, opt.trainingLoss, 1);
    // The held-out figures of the run: the objective it optimized on the independent estimate,
    // and U there (scored for the returned light only).
    if (std::isfinite(summary.heldoutLoss)) {  // written with U beside it (io/OptimizeOutDir.h)
        const double nan = std::nan("");
        h << compareRow(
            "held out: the " + objective + " loss on the independent estimate (lower is better)",
            nan, nan, summary.heldoutLoss, -1);
        h << compareRow("held out: U on the independent estimate (lower is better)", nan, nan,
                        summary.heldoutU, -1);
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
