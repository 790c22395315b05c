// lamps.json (written by `scratchlight lamps`, app/LampsJob.h) and the lamps as Mitsuba 3 area
// emitters (`export-mitsuba --lamps`).
//
// lamps.json: {"distance_mm", "frame", "lamps": [ per lamp: "kind" (scene/Lamp.h's table),
// "azimuth_deg" (not for a ring), "elevation_deg", "radiance" (E's units), "radiance_relative"
// (to the brightest), "solid_angle_sr" (the sharp shape's), the kind's angular size (disk
// "angular_radius_deg"; bar "angular_length_deg", "angular_width_deg", "roll_deg"; ring
// "elevation_band_deg" [lo, hi]) and "mount": the source at distance_mm from the part's centre
// (position_mm x, y, z in the scene's frame; disk diameter_mm; bar length_mm, width_mm; ring
// ring_radius_mm, ring_height_above_part_mm, band_height_mm) ]}. Reading takes kind, the angles
// and radiance; the mount is derived.
//
// Mitsuba: each lamp is an `area` emitter of radiance R (rgb, gray) on a shape at distance D
// whose front face (Mitsuba's area lights emit on the side of the normal) looks at the origin:
//   disk  `disk` scaled to radius D·tan r, to_world lookat(D·c → 0, up e_ε)
//   bar   `rectangle` scaled to (D·tan a, D·tan b) along (e₁, e₂): lookat(D·c → 0, up e₂) maps
//         the rectangle's x to e₂ × (−c) = e₁ (the frame (e₁, e₂, −c) is right-handed)
//   ring  `cylinder` about +Y of radius D·cos ε from height D·sin(ε−a) to D·sin(ε+a), normals
//         flipped inward (a zone of the sphere at distance D, approximated by its cylinder)
// At a finite distance a lamp is seen from points of the part under slightly different angles:
// the env map of the lamps (lamps-envmap.exr) is the exact light of the fit, the emitters are
// the booth.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/Lamp.h"

namespace sl {

struct LampsFile {
    double distanceMm = 500;
    std::vector<Lamp> lamps;
};

/// The JSON of lamps.json (lamps with radiance 0 are left out).
nlohmann::ordered_json lampsToJson(const std::vector<Lamp>& lamps, double distanceMm);
/// Reads lamps.json; InputError naming the file and the field otherwise.
LampsFile readLampsFile(const std::filesystem::path& file);

/// The lamps as Mitsuba 3 XML elements (one <shape> with an area <emitter> per lamp).
std::string mitsubaLampShapes(const LampsFile& lamps);
/// Inserts mitsubaLampShapes before </scene> of a written Mitsuba scene file (atomically).
void addLampsToMitsubaScene(const std::filesystem::path& xml, const LampsFile& lamps);

}  // namespace sl
