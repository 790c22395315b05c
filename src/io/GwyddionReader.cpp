#include "io/GwyddionReader.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <new>
#include <system_error>

#include "core/Error.h"
#include "io/AtomicFile.h"

#if SL_HAVE_GWYDDION
#include <libgwyddion/gwyddion.h>
#include <libgwydgets/gwydgets.h>
#include <libgwymodule/gwymodule.h>
#include <libprocess/gwyprocess.h>
#endif

namespace sl {

namespace fs = std::filesystem;

#if SL_HAVE_GWYDDION

namespace {

std::mutex& gwyLock() {
    static std::mutex m;
    return m;
}

/// Where the file modules are, or "" (set once by initialise()).
std::string& moduleDir() {
    static std::string dir;
    return dir;
}

/// Initialises Gwyddion headless, once; the caller holds gwyLock().
void initialise() {
    static std::once_flag once;
    std::call_once(once, [] {
        gwy_widgets_type_init();
        gwy_resource_class_load(
            static_cast<GwyResourceClass*>(g_type_class_peek(GWY_TYPE_GRADIENT)));
        gchar* self = gwy_find_self_dir("modules");
        gchar* dir = g_build_filename(self ? self : "", "file", nullptr);
        std::error_code ec;
        if (self && fs::is_directory(dir, ec)) {
            moduleDir() = dir;
            const gchar* dirs[] = {dir, nullptr};
            gwy_module_register_modules(dirs);
        }
        g_free(dir);
        g_free(self);
    });
    if (moduleDir().empty())
        throw inputError("Gwyddion", "its file modules are not installed (no modules/file folder)",
                         "Install the Debian package gwyddion (scripts/install-deps)");
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

}  // namespace

bool gwyddionBuilt() {
    return true;
}

std::string gwyddionDetect(const fs::path& file) {
    const std::lock_guard<std::mutex> lock(gwyLock());
    initialise();
    const gchar* name = gwy_file_detect(file.c_str(), FALSE, GWY_FILE_OPERATION_LOAD);
    return name ? name : "";
}

HeightmapData readGwyddion(const fs::path& file) {
    const std::string where = file.string();
    const std::lock_guard<std::mutex> lock(gwyLock());
    initialise();
    const gchar* module = gwy_file_detect(file.c_str(), FALSE, GWY_FILE_OPERATION_LOAD);
    if (!module)
        throw inputError(where,
                         "not a height map any reader knows (EXR, TIFF, PNG, .npy, X3P, SDF, or "
                         "one of the instrument formats Gwyddion's file modules read)",
                         "Export the measurement as X3P, SDF or EXR");
    GError* err = nullptr;
    ContainerRef ref;
    ref.c = gwy_file_load(file.c_str(), GWY_RUN_NONINTERACTIVE, &err);
    if (!ref.c) {
        const std::string msg = err && err->message ? err->message : "no reason given";
        if (err) g_error_free(err);
        throw inputError(
            where, std::string("Gwyddion's '") + module + "' module could not read it: " + msg,
            "Check that the file is complete; export it again (X3P, SDF or EXR)");
    }
    if (err) g_error_free(err);
    ChannelSearch search;
    search.container = ref.c;
    gwy_container_foreach(ref.c, nullptr, findChannel, &search);
    if (search.id < 0)
        throw inputError(
            where,
            search.firstAny < 0
                ? std::string("Gwyddion's '") + module + "' module found no image"
                : std::string("no channel holds heights in metres (") + search.otherUnits + ")",
            "Export the height (topography) channel of the measurement");
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
    if (static_cast<long long>(w) > detail::kMaxMetrologySide ||
        static_cast<long long>(h) > detail::kMaxMetrologySide ||
        static_cast<long long>(w) * h > detail::kMaxMetrologySamples)
        throw inputError(where,
                         std::to_string(w) + " x " + std::to_string(h) +
                             " points is more than the " +
                             std::to_string(detail::kMaxMetrologySamples) + " accepted",
                         "Crop or resample the measurement");
    HeightmapData d;
    d.width = w;
    d.height = h;
    d.pitch = gwy_data_field_get_dx(f) * 1000.0;
    d.pitchY = gwy_data_field_get_dy(f) * 1000.0;
    d.format = std::string("gwyddion ") + module;
    if (!(std::isfinite(*d.pitch) && *d.pitch > 0 && std::isfinite(*d.pitchY) && *d.pitchY > 0))
        throw inputError(where, "the file's sample spacing is not a positive number",
                         "Check the measurement's calibration; export it again");
    try {
        d.heights.resize(static_cast<size_t>(w) * static_cast<size_t>(h));
    } catch (const std::bad_alloc&) {
        throw inputError(where, "not enough memory for a " + std::to_string(w) + "x" +
                                    std::to_string(h) + " height map");
    }
    const double* z = gwy_data_field_get_data_const(f);
    const double* m = mask ? gwy_data_field_get_data_const(mask) : nullptr;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t k = 0; k < d.heights.size(); ++k) {
        const bool bad = (m && m[k] > 0.5) || !std::isfinite(z[k]);
        d.heights[k] = bad ? nan : static_cast<float>(z[k] * 1000.0);
    }
    return d;
}

void writeGwy(const fs::path& file, int width, int height, const std::vector<float>& heightsMm,
              double pitchMm) {
    const std::string where = file.string();
    if (width < 1 || height < 1 ||
        heightsMm.size() != static_cast<size_t>(width) * static_cast<size_t>(height) ||
        !(pitchMm > 0))
        throw inputError(where, "cannot write a .gwy file of " + std::to_string(heightsMm.size()) +
                                    " heights as " + std::to_string(width) + "x" +
                                    std::to_string(height));
    const std::lock_guard<std::mutex> lock(gwyLock());
    initialise();
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
    writeAtomically(file, [&](const fs::path& temp) {
        GError* err = nullptr;
        if (!gwy_file_func_run_save("gwyfile", ref.c, temp.c_str(), GWY_RUN_NONINTERACTIVE, &err)) {
            const std::string msg = err && err->message ? err->message : "no reason given";
            if (err) g_error_free(err);
            throw inputError(where, "Gwyddion could not write it: " + msg);
        }
    });
}

#else  // !SL_HAVE_GWYDDION

namespace {
[[noreturn]] void notBuilt(const fs::path& file) {
    throw inputError(file.string(),
                     "is not a height map this build reads (EXR, TIFF, PNG, .npy, X3P, SDF); "
                     "instrument formats need Gwyddion's file modules, and this binary was built "
                     "without them",
                     "Export the measurement as X3P, SDF or EXR, or build scratchlight with "
                     "-DSCRATCHLIGHT_GWYDDION=ON (scripts/install-deps installs Gwyddion)");
}
}  // namespace

bool gwyddionBuilt() {
    return false;
}
std::string gwyddionDetect(const fs::path&) {
    return "";
}
HeightmapData readGwyddion(const fs::path& file) {
    notBuilt(file);
}
void writeGwy(const fs::path& file, int, int, const std::vector<float>&, double) {
    notBuilt(file);
}

#endif

}  // namespace sl
