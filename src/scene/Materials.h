// Named conductors: complex IORs (eta + i k) per linear-RGB channel, reduced from measured spectra
// exactly as Mitsuba 3's RGB variants reduce their `material` presets (see Materials.cpp and
// scripts/derive_conductor_rgb.py for the data, its sources and the procedure).
//
//   "none"  eta 0, k 1: a perfect mirror (F == 1 exactly), Mitsuba's default `material`
//   "Al", "Cr", "Cu", "Au", "Ag"   Mitsuba 3 presets of the same names
//   "Fe"    iron; NOT a Mitsuba preset: Johnson & Christy (1974), reduced the same way. A scene
//           exported to Mitsuba must write Fe as explicit eta/k.
#pragma once

#include <string>
#include <vector>

#include "scene/Conductor.h"

namespace sl {

/// The complex IOR of a named conductor (names are case-sensitive, as Mitsuba's). Throws
/// InputError for an unknown name; the message contains the name, lists the valid names and says
/// to give explicit "eta"/"k" instead.
ComplexIor namedConductor(const std::string& name);

/// All valid names, in a fixed order: none, Al, Cr, Fe, Cu, Au, Ag.
std::vector<std::string> conductorNames();

/// True if Mitsuba 3 knows `name` as a `material` preset (every name except "Fe").
bool isMitsubaConductor(const std::string& name);

/// One-line provenance of a named conductor's data (for reports and exported scene comments).
/// Throws InputError for an unknown name.
std::string conductorSource(const std::string& name);

}  // namespace sl
