// lamps.json (written by `scratchlight lamps`, app/jobs/LampsJob.h) and the lamps as Mitsuba 3 area
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
//         (seen from the part's centre: exactly the cap of angular radius r)
//   bar   `rectangle` scaled to (D·tan a, D·tan b) along (e₁, e₂): lookat(D·c → 0, up e₂) maps
//         the rectangle's x to e₂ × (−c) = e₁ (the frame (e₁, e₂, −c) is right-handed). Seen
//         from the centre it spans exactly ±a along e₁ and ±b across at its middle; toward its
//         ends the flat source narrows to about b·cos a (the spherical rectangle of scene/Lamp.h
//         keeps ±b): a bar of ±20° is 6 % narrower at its ends
//   ring  `cylinder` about +Y of radius R = D·cos ε from height R·tan(ε−a) to R·tan(ε+a),
//         normals flipped inward: seen from the centre exactly the band [ε−a, ε+a] (elevations
//         clipped to ±kRingElevationLimit, where the cylinder would be infinitely tall)
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

/// The steepest elevation a ring's cylinder reaches (radians, 85°).
inline constexpr double kRingElevationLimit = 85 * 3.14159265358979323846 / 180;

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
