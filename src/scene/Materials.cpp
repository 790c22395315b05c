// Named conductors. The RGB constants below are printed by scripts/derive_conductor_rgb.py, which
// embeds the spectral tables and reproduces Mitsuba 3's reduction; re-run it to check them.
//
// Procedure (Mitsuba 3, github.com/mitsuba-renderer/mitsuba3, RGB variants):
//   include/mitsuba/render/ior.h  complex_ior_from_file(material) loads data/ior/<material>.eta.spd
//       and .k.spd; ior_from_file() multiplies the values by MI_CIE_Y_NORMALIZATION
//       (1 / 106.7502593994140625) and calls spectrum_list_to_srgb(wavelengths, values,
//       bounded = false, d65 = false); the result becomes an `srgb` texture (unbounded), which in
//       RGB variants returns the colour unchanged.
//   src/core/spectrum.cpp  spectrum_list_to_srgb(): 1000 wavelengths evenly spaced over
//       [360, 830] nm (endpoints included), skipping those outside the data; the data are
//       interpolated linearly; XYZ += CIE 1931 2-degree CMF (include/mitsuba/core/spectrum.h
//       cie1931_xyz(), 5 nm table, linear interpolation) * value; XYZ *= 470 / 1000; then
//       xyz_to_srgb() (linear Rec.709 primaries, D65 white; no illuminant weighting) and negative
//       components clamped to 0.
//   Caveat: the newest ior.h revision in the Mitsuba 3 repository (Properties rewrite) no longer
//   shows the MI_CIE_Y_NORMALIZATION factor while spectrum_list_to_srgb() still integrates the
//   un-normalised table; every earlier Mitsuba 3 release applies it, and without it eta and k would
//   be ~107x larger (every metal a near-white mirror). We use the normalised values; exporters
//   should write explicit eta/k rather than `material` names so that the two renderers agree.
//
// Data:
//   Al, Cr, Cu, Au, Ag: Mitsuba's data/ior/<name>.{eta,k}.spd (resources/data in Mitsuba 3, the
//       mitsuba-data repository; identical to data/ior/ of github.com/mitsuba-renderer/mitsuba
//       0.6), "data from www.luxpop.com database" (Palik's handbook and LLNL/CXRO measurements;
//       Cr: "Cr_llnl_cxro + Cr_palik"). Mitsuba 3's src/bsdfs/tests/test_conductor.py quotes
//       "0.136125 + 4.010625j # IoR values of Ag at 635.816284nm", the Ag table's row.
//   Fe: P. B. Johnson and R. W. Christy, "Optical constants of transition metals: Ti, V, Cr, Mn,
//       Fe, Co, Ni, and Pd", Phys. Rev. B 9, 5056-5070 (1974), doi:10.1103/PhysRevB.9.5056, as
//       tabulated in the refractiveindex.info database (database/data-nk/main/Fe/Johnson.yml,
//       CC0), reduced by the same procedure.
// Cross-check: our Al agrees to < 1e-4 with the RGB Al that Mitsuba 0.6 writes into exported
// scenes (eta 1.65746 0.880369 0.521229, k 9.22387 6.26952 4.837; e.g. the scene quoted in
// github.com/mitsuba-renderer/mitsuba2 issue #597).
#include "scene/Materials.h"

#include <array>

#include "core/Error.h"

namespace sl {

namespace {

struct NamedConductor {
    const char* name;
    ComplexIor ior;
    bool mitsuba;
    const char* source;
};

// Normal-incidence reflectance R0 = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2) per channel, for
// orientation: Al 0.928 0.918 0.919; Cr 0.688 0.649 0.687; Fe 0.587 0.496 0.462;
// Cu 0.952 0.620 0.511; Au 0.967 0.802 0.324; Ag 0.975 0.958 0.906.
const std::array<NamedConductor, 7> kConductors = {{
    {"none",
     {Rgb(0.0f), Rgb(1.0f)},
     true,
     "perfect mirror: eta 0, k 1 (Mitsuba material \"none\")"},
    {"Al",
     {{1.65750086f, 0.880404711f, 0.521244466f}, {9.22381115f, 6.26950216f, 4.83700418f}},
     true,
     "Mitsuba 3 preset \"Al\" (data/ior/Al.{eta,k}.spd, luxpop.com), reduced to RGB as Mitsuba"},
    {"Cr",
     {{4.36966753f, 2.91650534f, 1.6549046f}, {5.20654678f, 4.23130608f, 3.75469875f}},
     true,
     "Mitsuba 3 preset \"Cr\" (data/ior/Cr.{eta,k}.spd, luxpop.com: LLNL/CXRO + Palik), reduced "
     "to RGB as Mitsuba"},
    {"Fe",
     {{3.51447845f, 2.7697618f, 2.30172873f}, {3.69502568f, 2.78612661f, 2.49298501f}},
     false,
     "Johnson & Christy, Phys. Rev. B 9, 5056 (1974) via refractiveindex.info Fe/Johnson.yml, "
     "reduced to RGB as Mitsuba reduces its presets (not a Mitsuba preset)"},
    {"Cu",
     {{0.201005474f, 0.923749506f, 1.10221541f}, {3.91326213f, 2.45304513f, 2.14208984f}},
     true,
     "Mitsuba 3 preset \"Cu\" (data/ior/Cu.{eta,k}.spd, luxpop.com), reduced to RGB as Mitsuba"},
    {"Au",
     {{0.143035978f, 0.375307083f, 1.44204533f}, {3.98299694f, 2.38555646f, 1.60335922f}},
     true,
     "Mitsuba 3 preset \"Au\" (data/ior/Au.{eta,k}.spd, luxpop.com), reduced to RGB as Mitsuba"},
    {"Ag",
     {{0.155276194f, 0.116727956f, 0.138387635f}, {4.82835436f, 3.12222242f, 2.14690113f}},
     true,
     "Mitsuba 3 preset \"Ag\" (data/ior/Ag.{eta,k}.spd, luxpop.com), reduced to RGB as Mitsuba"},
}};

const NamedConductor& lookup(const std::string& name) {
    for (const NamedConductor& c : kConductors)
        if (name == c.name) return c;
    std::string valid;
    for (const NamedConductor& c : kConductors) {
        if (!valid.empty()) valid += ", ";
        valid += c.name;
    }
    throw inputError("", "unknown conductor material \"" + name + "\"",
                     "Valid names (case-sensitive): " + valid +
                         "; for any other metal give explicit \"eta\" and \"k\" (RGB) instead");
}

}  // namespace

ComplexIor namedConductor(const std::string& name) {
    return lookup(name).ior;
}

std::vector<std::string> conductorNames() {
    std::vector<std::string> names;
    names.reserve(kConductors.size());
    for (const NamedConductor& c : kConductors) names.emplace_back(c.name);
    return names;
}

bool isMitsubaConductor(const std::string& name) {
    for (const NamedConductor& c : kConductors)
        if (name == c.name) return c.mitsuba;
    return false;
}

std::string conductorSource(const std::string& name) {
    return lookup(name).source;
}

}  // namespace sl
