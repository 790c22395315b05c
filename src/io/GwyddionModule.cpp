// The Gwyddion module (io/GwyddionModule.h): the only file that includes Gwyddion's (and GTK's)
// headers. Built as libscratchlight-gwyddion.so (CMakeLists.txt, with SCRATCHLIGHT_GWYDDION),
// loaded by io/GwyddionReader.cpp when a file needs it; nothing else of this program is linked
// into it.
#include "io/GwyddionModule.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <mutex>
#include <new>
#include <string>
#include <system_error>
#include <vector>

#include "core/Text.h"

// After the standard headers, as before they were moved here (glib's libintl.h otherwise
// collides with them).
#include <libgwyddion/gwyddion.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <libprocess/gwyprocess.h>

namespace sl::detail {

namespace {

namespace fs = std::filesystem;

std::mutex& gwyLock() {
    static std::mutex m;
    return m;
}

/// Initialises Gwyddion headless, once, as its own gwyddion-thumbnailer does: the widget types,
/// the gradient resources, then only the file modules (`<libdir>/gwyddion/modules/file`; the
/// other module kinds need a display). The caller holds gwyLock(). False: *problem set.
bool initialise(GwyddionProblem* problem) {
    static std::string moduleDir;  // where the file modules are, or ""
    static std::once_flag once;
    std::call_once(once, [] {
        gwy_widgets_type_init();
        gwy_resource_class_load(
            static_cast<GwyResourceClass*>(g_type_class_peek(GWY_TYPE_GRADIENT)));
        gchar* self = gwy_find_self_dir("modules");
        gchar* dir = g_build_filename(self ? self : "", "file", nullptr);
        std::error_code ec;
        if (self && fs::is_directory(dir, ec)) {
            moduleDir = dir;
            const gchar* dirs[] = {dir, nullptr};
            gwy_module_register_modules(dirs);
        }
        g_free(dir);
        g_free(self);
    });
    if (!moduleDir.empty()) return true;
    *problem = {"Gwyddion", "its file modules are not installed (no modules/file folder)",
                "Install the Debian package gwyddion (scripts/install-deps)"};
    return false;
}

/// unitString of a dimensionless value (no unit).
constexpr const char* kNoUnit = "(none)";

std::string unitString(GwySIUnit* u) {
    gchar* s = gwy_si_unit_get_string(u, GWY_SI_UNIT_FORMAT_PLAIN);
    std::string r = s && *s ? s : kNoUnit;
    g_free(s);
    return r;
}

/// A channel of the file: its number N (/N/data), its title (/N/data/title) and units.
struct Channel {
    int id = 0;
    std::string title, zUnit, xyUnit;
    bool metres = false;        // heights and lateral both in metres: a height map
    bool uncalibrated = false;  // heights in metres on a grid without a lateral unit (or px)
    bool heights() const { return metres || uncalibrated; }  // a height map the rule may read
};

/// What a file module read: its channels (images), and the data that are not images.
struct FileContents {
    std::vector<Channel> channels;
    int pointClouds = 0;  // XYZ data (/xyz/N: GwySurface)
    int volumes = 0;      // volume data (/brick/N: GwyBrick)
    int curves = 0;       // graphs: profiles, spectra (GwyGraphModel)
};

void findChannel(gpointer quark, gpointer value, gpointer user) {
    auto* contents = static_cast<FileContents*>(user);
    const gchar* key = g_quark_to_string(GPOINTER_TO_UINT(quark));
    auto* v = static_cast<GValue*>(value);
    if (!key || key[0] != '/' || !G_VALUE_HOLDS_OBJECT(v)) return;
    GObject* obj = G_OBJECT(g_value_get_object(v));
    if (!obj) return;
    if (GWY_IS_SURFACE(obj)) ++contents->pointClouds;
    if (GWY_IS_BRICK(obj)) ++contents->volumes;
    if (GWY_IS_GRAPH_MODEL(obj)) ++contents->curves;
    if (!GWY_IS_DATA_FIELD(obj)) return;
    gchar* end = nullptr;
    const long id = std::strtol(key + 1, &end, 10);
    if (end == key + 1 || id < 0 || id > 1000000 || std::string(end) != "/data") return;
    GwyDataField* f = GWY_DATA_FIELD(obj);
    Channel c;
    c.id = static_cast<int>(id);
    c.zUnit = unitString(gwy_data_field_get_si_unit_z(f));
    c.xyUnit = unitString(gwy_data_field_get_si_unit_xy(f));
    const bool zMetres = gwy_si_unit_equal_string(gwy_data_field_get_si_unit_z(f), "m");
    c.metres = zMetres && gwy_si_unit_equal_string(gwy_data_field_get_si_unit_xy(f), "m");
    c.uncalibrated = zMetres && (c.xyUnit == kNoUnit || c.xyUnit == "px");
    contents->channels.push_back(std::move(c));
}

/// `1 "Height" (heights in m)`, `2 "Phase" (deg)`: how a channel is named in messages.
std::string channelName(const Channel& c) {
    std::string s = std::to_string(c.id);
    if (!c.title.empty()) s += " \"" + c.title + "\"";
    if (c.metres) return s + " (heights in m)";
    if (c.uncalibrated) return s + " (heights in m, lateral uncalibrated)";
    s += " (" + (c.zUnit == kNoUnit ? std::string("no unit") : c.zUnit);
    return s + (c.xyUnit == "m" ? ")" : ", lateral " + c.xyUnit + ")");
}

std::string channelList(const std::vector<Channel>& channels, int except = -1) {
    std::string s;
    for (const Channel& c : channels) {
        if (c.id == except) continue;
        if (!s.empty()) s += "; ";
        s += channelName(c);
    }
    return s;
}

/// The channel to read (io/GwyddionReader.h: the rule), or nullptr with *problem set.
const Channel* chooseChannel(const std::vector<Channel>& channels, const std::string& request,
                             const std::string& file, std::string* how, GwyddionProblem* problem) {
    const std::string all = "the file's channels: " + channelList(channels);
    const Channel* chosen = nullptr;
    if (!request.empty()) {
        const bool number = request.find_first_not_of("0123456789") == std::string::npos;
        const std::string asked = lower(request);
        std::vector<const Channel*> titled;
        for (const Channel& c : channels) {
            const std::string title = lower(c.title);
            if (number ? std::to_string(c.id) == request : title == asked) {
                chosen = &c;
                break;
            }
            if (!number && title.find(asked) != std::string::npos) titled.push_back(&c);
        }
        if (!chosen && titled.size() == 1) chosen = titled.front();
        if (!chosen) {
            *problem = {"heightmap.channel",
                        titled.size() > 1
                            ? "\"" + request + "\" names more than one channel of " + file + " (" +
                                  all + ")"
                            : "no channel \"" + request + "\" in " + file + " (" + all + ")",
                        "Give the channel's number or its whole title"};
            return nullptr;
        }
        if (!chosen->heights()) {
            *problem = {"heightmap.channel",
                        "channel " + channelName(*chosen) + " of " + file +
                            (chosen->zUnit == "m" ? " holds heights over lateral axes in " +
                                                        chosen->xyUnit + ", not a length ("
                                                  : " does not hold heights in metres (") +
                            all + ")",
                        "Choose the height (topography) channel"};
            return nullptr;
        }
        *how = "as heightmap.channel asks";
        return chosen;
    }
    for (const Channel& c : channels) {
        if (!c.heights()) continue;
        const std::string t = lower(c.title);
        if (t.find("height") != std::string::npos || t.find("topo") != std::string::npos) {
            *how = "its title names heights";
            return &c;
        }
    }
    for (const Channel& c : channels)
        if (c.heights()) {
            *how = "the first in metres";
            return &c;
        }
    *problem = {"", "no channel holds heights in metres (" + all + ")",
                "Export the height (topography) channel of the measurement"};
    return nullptr;
}

/// Why a file holds no image to read, by what it holds instead.
GwyddionProblem noImage(const FileContents& f, const std::string& module) {
    const std::string read = "Gwyddion's '" + module + "' module read ";
    const auto count = [](int n, const char* one, const char* many) {
        return std::to_string(n) + " " + (n == 1 ? one : many);
    };
    if (f.pointClouds > 0)
        return {"",
                read + count(f.pointClouds, "point cloud", "point clouds") +
                    " (XYZ data), not a grid of heights",
                "Rasterize the points onto a regular grid (Gwyddion: XYZ Data > Rasterize) and "
                "save the image as .gwy or X3P"};
    if (f.volumes > 0)
        return {"", read + count(f.volumes, "volume", "volumes") + " (volume data), no height map",
                "Export a height (topography) image of the measurement"};
    if (f.curves > 0)
        return {"",
                read + count(f.curves, "graph", "graphs") +
                    " (profiles or spectra), no height map: an areal measurement is needed",
                "Measure or export the surface as an image (a height map)"};
    return {"", "Gwyddion's '" + module + "' module found no image",
            "Export the height (topography) channel of the measurement"};
}

struct ContainerRef {
    GwyContainer* c = nullptr;
    ~ContainerRef() {
        if (c) g_object_unref(c);
    }
};

bool detect(const std::string& file, std::string* module, GwyddionProblem* problem) {
    const std::lock_guard<std::mutex> lock(gwyLock());
    if (!initialise(problem)) return false;
    const gchar* name = gwy_file_detect(file.c_str(), FALSE, GWY_FILE_OPERATION_LOAD);
    *module = name ? name : "";
    return true;
}

bool read(const std::string& file, const std::string& channel, HeightmapData* out,
          GwyddionProblem* problem) {
    const std::lock_guard<std::mutex> lock(gwyLock());
    if (!initialise(problem)) return false;
    const gchar* module = gwy_file_detect(file.c_str(), FALSE, GWY_FILE_OPERATION_LOAD);
    if (!module) {
        *problem = {"",
                    "not a height map any reader knows (EXR, TIFF, PNG, .npy, X3P, SDF, or "
                    "one of the instrument formats Gwyddion's file modules read)",
                    "Export the measurement as X3P, SDF or EXR"};
        return false;
    }
    GError* err = nullptr;
    ContainerRef ref;
    ref.c = gwy_file_load(file.c_str(), GWY_RUN_NONINTERACTIVE, &err);
    if (!ref.c) {
        const std::string msg = err && err->message ? err->message : "no reason given";
        if (err) g_error_free(err);
        *problem = {"", std::string("Gwyddion's '") + module + "' module could not read it: " + msg,
                    "Check that the file is complete; export it again (X3P, SDF or EXR)"};
        return false;
    }
    if (err) g_error_free(err);
    FileContents contents;
    gwy_container_foreach(ref.c, nullptr, findChannel, &contents);
    if (contents.channels.empty()) {
        *problem = noImage(contents, module);
        return false;
    }
    std::vector<Channel>& channels = contents.channels;
    std::sort(channels.begin(), channels.end(),
              [](const Channel& x, const Channel& y) { return x.id < y.id; });
    for (Channel& c : channels) {
        char titleKey[48];
        std::snprintf(titleKey, sizeof titleKey, "/%d/data/title", c.id);
        const guchar* title = nullptr;
        if (gwy_container_gis_string_by_name(ref.c, titleKey, &title) && title)
            c.title = reinterpret_cast<const char*>(title);
    }
    std::string how;
    const Channel* chosen = chooseChannel(channels, channel, file, &how, problem);
    if (!chosen) return false;
    const int chosenId = chosen->id;
    std::string chosenText;
    if (channels.size() > 1 || !channel.empty())
        chosenText =
            "channel " + channelName(*chosen) + ", " + how +
            (channels.size() > 1 ? "; the others: " + channelList(channels, chosenId) +
                                       (channel.empty() ? " (heightmap.channel chooses)" : "")
                                 : std::string());
    char key[48];
    std::snprintf(key, sizeof key, "/%d/data", chosenId);
    GwyDataField* f = GWY_DATA_FIELD(gwy_container_get_object_by_name(ref.c, key));
    std::snprintf(key, sizeof key, "/%d/mask", chosenId);
    GObject* maskObj = nullptr;
    GwyDataField* mask = nullptr;
    if (gwy_container_gis_object_by_name(ref.c, key, &maskObj) && maskObj &&
        GWY_IS_DATA_FIELD(maskObj))
        mask = GWY_DATA_FIELD(maskObj);

    const int w = gwy_data_field_get_xres(f), h = gwy_data_field_get_yres(f);
    if (mask && (gwy_data_field_get_xres(mask) != w || gwy_data_field_get_yres(mask) != h))
        mask = nullptr;
    if (static_cast<long long>(w) > kMaxMetrologySide ||
        static_cast<long long>(h) > kMaxMetrologySide ||
        static_cast<long long>(w) * h > kMaxMetrologySamples) {
        *problem = {"",
                    std::to_string(w) + " x " + std::to_string(h) + " points is more than the " +
                        std::to_string(kMaxMetrologySamples) + " accepted",
                    "Crop or resample the measurement"};
        return false;
    }
    HeightmapData& d = *out;
    d = HeightmapData{};
    d.width = w;
    d.height = h;
    d.format = std::string("gwyddion ") + module;
    d.channel = chosenText;
    if (chosen->uncalibrated) {
        // no lateral calibration: the samples' spacing is the scene's (heightmap.pixel_pitch)
        d.uncalibratedLateral = true;
        d.warnings.push_back("channel " + channelName(*chosen) +
                             " carries no lateral calibration (its grid is in " +
                             (chosen->xyUnit == "px" ? std::string("pixels") : "no unit") +
                             "): its samples are taken as square at the scene's "
                             "heightmap.pixel_pitch");
    } else {
        d.pitch = gwy_data_field_get_dx(f) * 1000.0;
        d.pitchY = gwy_data_field_get_dy(f) * 1000.0;
    }
    if (d.pitch &&
        !(std::isfinite(*d.pitch) && *d.pitch > 0 && std::isfinite(*d.pitchY) && *d.pitchY > 0)) {
        *problem = {"", "the file's sample spacing is not a positive number",
                    "Check the measurement's calibration; export it again"};
        return false;
    }
    try {
        d.heights.resize(static_cast<size_t>(w) * static_cast<size_t>(h));
    } catch (const std::bad_alloc&) {
        *problem = {"",
                    "not enough memory for a " + std::to_string(w) + "x" + std::to_string(h) +
                        " height map",
                    ""};
        return false;
    }
    const double* z = gwy_data_field_get_data_const(f);
    const double* m = mask ? gwy_data_field_get_data_const(mask) : nullptr;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t k = 0; k < d.heights.size(); ++k) {
        const bool bad = (m && m[k] > 0.5) || !std::isfinite(z[k]);
        d.heights[k] = bad ? nan : static_cast<float>(z[k] * 1000.0);
    }
    return true;
}

bool writeGwy(const std::string& path, int width, int height,
              const std::vector<GwyChannel>& channels, double pitchMm, GwyddionProblem* problem) {
    const std::lock_guard<std::mutex> lock(gwyLock());
    if (!initialise(problem)) return false;
    const double p = pitchMm / 1000.0;
    ContainerRef ref;
    ref.c = gwy_container_new();
    for (size_t i = 0; i < channels.size(); ++i) {
        const GwyChannel& c = channels[i];
        const bool calibrated = c.lateralUnit == "m";  // else one unit per sample
        GwyDataField* f = calibrated
                              ? gwy_data_field_new(width, height, width * p, height * p, FALSE)
                              : gwy_data_field_new(width, height, width, height, FALSE);
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(f), c.lateralUnit.c_str());
        gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(f), c.unit.c_str());
        double* z = gwy_data_field_get_data(f);
        const double mmPerUnit = c.unit == "m" ? 1000.0 : 1.0;  // heights are given in mm
        for (size_t k = 0; k < c.values.size(); ++k)
            z[k] = static_cast<double>(c.values[k]) / mmPerUnit;
        char key[48];
        std::snprintf(key, sizeof key, "/%zu/data", i);
        gwy_container_set_object_by_name(ref.c, key, f);
        g_object_unref(f);
        if (!c.title.empty()) {
            std::snprintf(key, sizeof key, "/%zu/data/title", i);
            gwy_container_set_const_string_by_name(
                ref.c, key, reinterpret_cast<const guchar*>(c.title.c_str()));
        }
    }
    GError* err = nullptr;
    if (!gwy_file_func_run_save("gwyfile", ref.c, path.c_str(), GWY_RUN_NONINTERACTIVE, &err)) {
        const std::string msg = err && err->message ? err->message : "no reason given";
        if (err) g_error_free(err);
        *problem = {"", "Gwyddion could not write it: " + msg, ""};
        return false;
    }
    return true;
}

const GwyddionModule kModule{kGwyddionModuleVersion, &detect, &read, &writeGwy};

}  // namespace

}  // namespace sl::detail

extern "C" __attribute__((visibility("default"))) const sl::detail::GwyddionModule*
sl_gwyddion_module_v1() {
    return &sl::detail::kModule;
}
