// The Gwyddion module (io/GwyddionModule.h): the only file that includes Gwyddion's (and GTK's)
// headers. Built as libscratchlight-gwyddion.so (CMakeLists.txt, with SCRATCHLIGHT_GWYDDION),
// loaded by io/GwyddionReader.cpp when a file needs it; nothing else of this program is linked
// into it.
#include "io/GwyddionModule.h"

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

struct ChannelSearch {
    GwyContainer* container = nullptr;
    int id = -1;             // the lowest id with metre units
    int firstAny = -1;       // the lowest id of any channel
    std::string otherUnits;  // what the other channels hold, for the error
};

std::string unitString(GwySIUnit* u) {
    gchar* s = gwy_si_unit_get_string(u, GWY_SI_UNIT_FORMAT_PLAIN);
    std::string r = s && *s ? s : "(none)";
    g_free(s);
    return r;
}

void findChannel(gpointer quark, gpointer value, gpointer user) {
    auto* search = static_cast<ChannelSearch*>(user);
    const gchar* key = g_quark_to_string(GPOINTER_TO_UINT(quark));
    auto* v = static_cast<GValue*>(value);
    if (!key || key[0] != '/' || !G_VALUE_HOLDS_OBJECT(v)) return;
    GObject* obj = G_OBJECT(g_value_get_object(v));
    if (!obj || !GWY_IS_DATA_FIELD(obj)) return;
    gchar* end = nullptr;
    const long id = std::strtol(key + 1, &end, 10);
    if (end == key + 1 || id < 0 || id > 1000000 || std::string(end) != "/data") return;
    GwyDataField* f = GWY_DATA_FIELD(obj);
    const int i = static_cast<int>(id);
    if (search->firstAny < 0 || i < search->firstAny) search->firstAny = i;
    const bool metres = gwy_si_unit_equal_string(gwy_data_field_get_si_unit_z(f), "m") &&
                        gwy_si_unit_equal_string(gwy_data_field_get_si_unit_xy(f), "m");
    if (metres) {
        if (search->id < 0 || i < search->id) search->id = i;
    } else {
        std::string& u = search->otherUnits;
        if (!u.empty()) u += "; ";
        u += "channel ";
        u += std::to_string(i);
        u += ": heights in ";
        u += unitString(gwy_data_field_get_si_unit_z(f));
        u += ", lateral in ";
        u += unitString(gwy_data_field_get_si_unit_xy(f));
    }
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

bool read(const std::string& file, HeightmapData* out, GwyddionProblem* problem) {
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
    ChannelSearch search;
    search.container = ref.c;
    gwy_container_foreach(ref.c, nullptr, findChannel, &search);
    if (search.id < 0) {
        *problem = {
            "",
            search.firstAny < 0
                ? std::string("Gwyddion's '") + module + "' module found no image"
                : std::string("no channel holds heights in metres (") + search.otherUnits + ")",
            "Export the height (topography) channel of the measurement"};
        return false;
    }
    char key[48];
    std::snprintf(key, sizeof key, "/%d/data", search.id);
    GwyDataField* f = GWY_DATA_FIELD(gwy_container_get_object_by_name(ref.c, key));
    std::snprintf(key, sizeof key, "/%d/mask", search.id);
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
    d.pitch = gwy_data_field_get_dx(f) * 1000.0;
    d.pitchY = gwy_data_field_get_dy(f) * 1000.0;
    d.format = std::string("gwyddion ") + module;
    if (!(std::isfinite(*d.pitch) && *d.pitch > 0 && std::isfinite(*d.pitchY) && *d.pitchY > 0)) {
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

bool writeGwy(const std::string& path, int width, int height, const std::vector<float>& heightsMm,
              double pitchMm, GwyddionProblem* problem) {
    const std::lock_guard<std::mutex> lock(gwyLock());
    if (!initialise(problem)) return false;
    const double p = pitchMm / 1000.0;
    GwyDataField* f = gwy_data_field_new(width, height, width * p, height * p, FALSE);
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_xy(f), "m");
    gwy_si_unit_set_from_string(gwy_data_field_get_si_unit_z(f), "m");
    double* z = gwy_data_field_get_data(f);
    for (size_t k = 0; k < heightsMm.size(); ++k) z[k] = static_cast<double>(heightsMm[k]) / 1000.0;
    ContainerRef ref;
    ref.c = gwy_container_new();
    gwy_container_set_object_by_name(ref.c, "/0/data", f);
    g_object_unref(f);
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
