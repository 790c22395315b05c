// Heightfield: the machined surface as Embree grid geometry (RTC_GEOMETRY_TYPE_GRID).
//
// CONVENTION (world frame): +Y up. Sample (row j, column i) of a W×H map with pitch p and height h
// sits at x = (i − (W−1)/2)·p, y = h, z = (j − (H−1)/2)·p: the map is centred at the origin, the
// surface faces +Y and row 0 is at −z. Each cell (quad v0=(i,j), v1=(i+1,j), v2=(i+1,j+1),
// v3=(i,j+1)) is split by Embree into triangles (v0,v1,v3) and (v2,v3,v1): diagonal v1–v3.
// Normals are the triangles' geometric normals, oriented toward +Y.
// Shading frame: s = normalize(cross(n, +z)) (the in-plane direction of constant z, i.e. the
// map's column direction +x), t = cross(n, s); this is Mitsuba's frame for a mesh whose uv has u
// along +x and v along +z, so `alpha_u` acts along +x and `alpha_v` along z.
#pragma once

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "core/Vec3.h"
#include "scene/Camera.h"

namespace sl {

struct HeightfieldStats {
    int gridCount = 0;           // RTCGrid primitives (blocks of <= 32767 vertices per side)
    size_t vertexBytes = 0;      // the grid's vertex buffer
    size_t embreeBytes = 0;      // everything Embree holds after the build, with the vertex buffer
    size_t embreePeakBytes = 0;  // peak during the build
    double buildSeconds = 0;     // vertex fill + BVH build
};

struct SurfaceHit {
    float t = 0;
    Vec3f position;
    Vec3f normal;  // unit geometric normal, y > 0
};

/// Shading frame at a surface point with unit normal n (see CONVENTION above).
inline Frame shadingFrame(const Vec3f& n) {
    Frame f;
    f.n = n;
    f.s = normalize(cross(n, Vec3f{0, 0, 1}));  // in-plane direction of constant z (≈ +x)
    f.t = cross(n, f.s);
    return f;
}

/// Origin for a ray leaving surface point p (unit normal n): offset along n by a few float
/// ulps of the coordinates' magnitude so the ray does not re-hit the triangle it leaves.
inline Vec3f offsetRayOrigin(const Vec3f& p, const Vec3f& n) {
    float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), 1.0f});
    return p + n * (m * 1e-5f);
}

/// An Embree query for `ray` over (tnear, inf), no hit yet.
inline RTCRayHit makeRayHit(const Ray& ray, float tnear) {
    RTCRayHit rh{};
    rh.ray.org_x = ray.origin.x;
    rh.ray.org_y = ray.origin.y;
    rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x;
    rh.ray.dir_y = ray.direction.y;
    rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = tnear;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rh;
}

/// The BVH is built on the first query (intersect, occluded, rtcScene or stats), not on
/// construction: a run that reads its transport matrix from the cache never traces a ray, and
/// building Embree's BVH of a 1024² map took ~0.1-0.2 s of it on 2 cores. The vertices are
/// filled with the BVH too (the grid's vertex buffer is ours, shared with Embree), from the
/// heights the Heightfield was made from: they must outlive it (Scene owns both).
class Heightfield {
  public:
    /// heights: W×H, row-major, row 0 first, in scene units, kept (not copied) until the BVH is
    /// built. Throws InputError if too small.
    Heightfield(int width, int height, double pitch, std::span<const float> heights);
    ~Heightfield();
    Heightfield(const Heightfield&) = delete;
    Heightfield& operator=(const Heightfield&) = delete;

    /// Closest hit along ray with t in (tnear, inf). Returns false on a miss.
    bool intersect(const Ray& ray, float tnear, SurfaceHit& hit) const;
    /// Whether anything lies along ray with t in (tnear, inf) (Embree's occlusion query).
    bool occluded(const Ray& ray, float tnear) const;

    int width() const { return width_; }
    int height() const { return height_; }
    double pitch() const { return pitch_; }
    double extentX() const { return (width_ - 1) * pitch_; }
    double extentZ() const { return (height_ - 1) * pitch_; }
    float minHeight() const { return minH_; }
    float maxHeight() const { return maxH_; }
    /// The build's figures (builds the BVH if it is not built yet).
    const HeightfieldStats& stats() const {
        ensureBuilt();
        return stats_;
    }
    RTCScene rtcScene() const {
        ensureBuilt();
        return scene_;
    }
    /// Whether the BVH has been built (by a query).
    bool built() const { return built_.load(std::memory_order_acquire); }
    /// Builds the BVH now if it is not built: call it before a parallel loop of queries, so
    /// that the build is not started from inside one of its tasks.
    void ensureBuilt() const {
        if (!built_.load(std::memory_order_acquire)) std::call_once(once_, [this] { build(); });
    }

  private:
    int width_, height_;
    double pitch_;
    float minH_ = 0, maxH_ = 0;
    std::span<const float> heights_;       // the caller's, read by build()
    mutable std::vector<float> vertices_;  // x, y, z per sample, then one float of padding
    mutable std::once_flag once_;
    mutable std::atomic<bool> built_{false};
    mutable RTCDevice device_ = nullptr;
    mutable RTCScene scene_ = nullptr;
    mutable HeightfieldStats stats_;
    std::unique_ptr<std::atomic<int64_t>[]> memory_;  // [current, peak] for Embree's monitor

    void build() const;
};

}  // namespace sl
