#include "io/LampsFile.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/InputFile.h"
#include "scene/EnvMap.h"

namespace sl {

namespace {

using json = nlohmann::ordered_json;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = 180 / kPi;

double wrapDegrees(double deg) {
    double d = std::fmod(deg, 360.0);
    if (d < 0) d += 360.0;
    return d + 0.0;
}

json lampJson(const Lamp& l, double brightest, double distance) {
    json j;
    j["kind"] = lampKindName(l.kind);
    if (l.kind != LampKind::Ring) j["azimuth_deg"] = wrapDegrees(l.azimuth * kDeg);
    j["elevation_deg"] = l.elevation * kDeg;
    j["radiance_relative"] = brightest > 0 ? l.radiance / brightest : 0.0;
    j["radiance"] = l.radiance;
    j["solid_angle_sr"] = lampSharpSolidAngle(l);
    json at;
    at["distance_mm"] = distance;
    switch (l.kind) {
        case LampKind::Disk:
            j["angular_radius_deg"] = l.size * kDeg;
            at["diameter_mm"] = 2 * distance * std::tan(std::min(l.size, 1.5));
            break;
        case LampKind::Bar:
            j["angular_length_deg"] = 2 * l.size * kDeg;
            j["angular_width_deg"] = 2 * l.width * kDeg;
            j["roll_deg"] = l.roll * kDeg;
            at["length_mm"] = 2 * distance * std::tan(l.size);
            at["width_mm"] = 2 * distance * std::tan(l.width);
            break;
        case LampKind::Ring:
            j["elevation_band_deg"] = {(l.elevation - l.size) * kDeg,
                                       (l.elevation + l.size) * kDeg};
            at["ring_radius_mm"] = distance * std::cos(l.elevation);
            at["ring_height_above_part_mm"] = distance * std::sin(l.elevation);
            at["band_height_mm"] = distance * (std::sin(std::min(l.elevation + l.size, kPi / 2)) -
                                               std::sin(std::max(l.elevation - l.size, -kPi / 2)));
            break;
    }
    if (l.kind != LampKind::Ring) {
        const Vec3d p = lampDirection(l.azimuth, l.elevation) * distance;
        at["position_mm"] = {p.x, p.y, p.z};
    }
    j["mount"] = at;
    return j;
}

double number(const json& j, const char* key, const std::string& where) {
    if (!j.contains(key) || !j[key].is_number() || !std::isfinite(j[key].get<double>()))
        throw inputError(where + " " + key, "missing or not a finite number",
                         "write it as `scratchlight lamps` does");
    return j[key].get<double>();
}

std::string vec(const Vec3d& v) {
    std::ostringstream s;
    s.precision(9);
    s << v.x << ", " << v.y << ", " << v.z;
    return s.str();
}

}  // namespace

json lampsToJson(const std::vector<Lamp>& lamps, double distanceMm) {
    double brightest = 0;
    for (const Lamp& l : lamps) brightest = std::max(brightest, l.radiance);
    json j;
    j["distance_mm"] = distanceMm;
    j["frame"] =
        "part frame: +Y up; azimuth 0 deg toward -z, 90 deg toward +x; elevation 90 deg = +Y "
        "(scene/Lamp.h)";
    j["lamps"] = json::array();
    for (const Lamp& l : lamps)
        if (l.radiance > 0) j["lamps"].push_back(lampJson(l, brightest, distanceMm));
    return j;
}

LampsFile readLampsFile(const std::filesystem::path& file) {
    const std::string where = file.string();
    json j = readJsonInput(file, "a lamps file", "give the lamps.json `scratchlight lamps` wrote");
    if (!j.is_object())
        throw inputError(where, "is not a JSON object",
                         "give the lamps.json `scratchlight lamps` wrote");
    LampsFile f;
    f.distanceMm = number(j, "distance_mm", where);
    if (!(f.distanceMm > 0))
        throw inputError(where + " distance_mm", "must be > 0", "use e.g. 500");
    if (!j.contains("lamps") || !j["lamps"].is_array())
        throw inputError(where, "has no \"lamps\" array",
                         "give the lamps.json `scratchlight lamps` wrote");
    for (size_t i = 0; i < j["lamps"].size(); ++i) {
        const json& e = j["lamps"][i];
        const std::string at = where + " lamps[" + std::to_string(i) + "]";
        if (!e.contains("kind") || !e["kind"].is_string())
            throw inputError(at + " kind", "missing", "use disk, bar or ring");
        Lamp l;
        l.kind = parseLampKind(e["kind"].get<std::string>(), at + " kind");
        l.radiance = number(e, "radiance", at);
        l.elevation = number(e, "elevation_deg", at) / kDeg;
        switch (l.kind) {
            case LampKind::Disk:
                l.azimuth = number(e, "azimuth_deg", at) / kDeg;
                l.size = number(e, "angular_radius_deg", at) / kDeg;
                break;
            case LampKind::Bar:
                l.azimuth = number(e, "azimuth_deg", at) / kDeg;
                l.size = number(e, "angular_length_deg", at) / kDeg / 2;
                l.width = number(e, "angular_width_deg", at) / kDeg / 2;
                l.roll = number(e, "roll_deg", at) / kDeg;
                break;
            case LampKind::Ring: {
                const json* band =
                    e.contains("elevation_band_deg") ? &e["elevation_band_deg"] : nullptr;
                if (!band || !band->is_array() || band->size() != 2 || !(*band)[0].is_number() ||
                    !(*band)[1].is_number() || !std::isfinite((*band)[0].get<double>()) ||
                    !std::isfinite((*band)[1].get<double>()))
                    throw inputError(at + " elevation_band_deg",
                                     "missing or not [lo, hi] in degrees",
                                     "write it as `scratchlight lamps` does");
                const double lo = (*band)[0].get<double>(), hi = (*band)[1].get<double>();
                if (!(lo >= -90 && hi <= 90 && lo < hi))
                    throw inputError(at + " elevation_band_deg",
                                     "is [" + formatNumber(lo) + ", " + formatNumber(hi) +
                                         "]: a band must lie within [-90, 90] degrees (horizon "
                                         "0, zenith 90) with lo < hi",
                                     "write it as `scratchlight lamps` does");
                l.elevation = 0.5 * (lo + hi) / kDeg;
                l.size = 0.5 * (hi - lo) / kDeg;
                break;
            }
        }
        // What the lamps admit (scene/Lamp.h): angles in degrees, sizes in (0, 90].
        auto refuse = [&](const char* field, double value, const char* range) {
            throw inputError(at + " " + field, "is " + formatNumber(value) + ", outside " + range,
                             "write it as `scratchlight lamps` does");
        };
        if (!(l.radiance >= 0 && l.radiance <= kMaxRadiance))  // scene/EnvMap.h
            refuse("radiance", l.radiance, ("[0, " + formatNumber(kMaxRadiance) + "]").c_str());
        if (std::abs(l.elevation) > kPi / 2 + 1e-9)
            refuse("elevation_deg", l.elevation * kDeg, "[-90, 90] degrees");
        if (l.kind == LampKind::Disk && !(l.size > 0 && l.size <= kPi / 2 + 1e-9))
            refuse("angular_radius_deg", l.size * kDeg, "(0, 90] degrees");
        if (l.kind == LampKind::Bar) {
            if (!(l.size > 0 && l.size <= kPi / 2 + 1e-9))
                refuse("angular_length_deg", 2 * l.size * kDeg, "(0, 180] degrees");
            if (!(l.width > 0 && l.width <= kPi / 4 + 1e-9))
                refuse("angular_width_deg", 2 * l.width * kDeg, "(0, 90] degrees");
        }
        if (std::abs(l.azimuth) > 1e6) refuse("azimuth_deg", l.azimuth * kDeg, "[-1e6, 1e6]");
        if (std::abs(l.roll) > 1e6) refuse("roll_deg", l.roll * kDeg, "[-1e6, 1e6]");
        f.lamps.push_back(l);
    }
    return f;
}

std::string mitsubaLampShapes(const LampsFile& f) {
    std::ostringstream x;
    x.precision(9);
    const double D = f.distanceMm;
    for (size_t i = 0; i < f.lamps.size(); ++i) {
        const Lamp& l = f.lamps[i];
        if (!(l.radiance > 0)) continue;
        const auto fr = lamp_detail::frame<double>(l.azimuth, l.elevation, l.roll);
        const Vec3d c{fr.c[0], fr.c[1], fr.c[2]}, e2{fr.e2[0], fr.e2[1], fr.e2[2]};
        const Vec3d eEl = lampDirection(l.azimuth, l.elevation + kPi / 2);  // e_ε
        x << "    <!-- lamp " << i + 1 << ": " << lampKindName(l.kind) << " (lamps.json) -->\n";
        switch (l.kind) {
            case LampKind::Disk: {
                const double r = D * std::tan(std::min(l.size, 1.5));
                x << "    <shape type=\"disk\">\n        <transform name=\"to_world\">\n"
                  << "            <scale x=\"" << r << "\" y=\"" << r << "\" z=\"1\"/>\n"
                  << "            <lookat origin=\"" << vec(c * D) << "\" target=\"0, 0, 0\" up=\""
                  << vec(eEl) << "\"/>\n        </transform>\n";
                break;
            }
            case LampKind::Bar:
                x << "    <shape type=\"rectangle\">\n        <transform name=\"to_world\">\n"
                  << "            <scale x=\"" << D * std::tan(l.size) << "\" y=\""
                  << D * std::tan(l.width) << "\" z=\"1\"/>\n"
                  << "            <lookat origin=\"" << vec(c * D) << "\" target=\"0, 0, 0\" up=\""
                  << vec(e2) << "\"/>\n        </transform>\n";
                break;
            case LampKind::Ring: {
                // Heights R·tan(lo), R·tan(hi) on a cylinder of radius R = D·cos ε: seen from
                // the centre its wall spans exactly the elevations [lo, hi] (and so the band's
                // solid angle 2π(sin hi − sin lo)).
                const double lim = kRingElevationLimit;
                const double lo = std::clamp(l.elevation - l.size, -lim, lim),
                             hi = std::clamp(l.elevation + l.size, -lim, lim);
                const double R = D * std::cos(std::clamp(l.elevation, -lim, lim));
                x << "    <shape type=\"cylinder\">\n"
                  << "        <point name=\"p0\" value=\"0, " << R * std::tan(lo) << ", 0\"/>\n"
                  << "        <point name=\"p1\" value=\"0, " << R * std::tan(hi) << ", 0\"/>\n"
                  << "        <float name=\"radius\" value=\"" << R
                  << "\"/>\n        <boolean name=\"flip_normals\" value=\"true\"/>\n";
                break;
            }
        }
        x << "        <emitter type=\"area\">\n            <rgb name=\"radiance\" value=\""
          << l.radiance << "\"/>\n        </emitter>\n    </shape>\n";
    }
    return x.str();
}

void addLampsToMitsubaScene(const std::filesystem::path& xml, const LampsFile& lamps) {
    std::ifstream in(xml);
    std::stringstream s;
    s << in.rdbuf();
    std::string text = s.str();
    const size_t end = text.rfind("</scene>");
    if (end == std::string::npos)
        throw inputError(xml.string(), "has no </scene>", "export the scene again");
    text.insert(end, mitsubaLampShapes(lamps));
    writeTextAtomically(xml, text);
}

}  // namespace sl
