// The part's footprint on the film: for each image row, the pixels whose camera samples can meet
// the height field at all. A pixel outside it sees only the hidden background (PathTracer.h:
// 0, no paths), so the tracer skips it: the same image and T, without the camera rays.
//
// How: the 8 corners of the height field's bounding box (padded by 1e-5 of its size, for
// Embree's float geometry) are projected onto the film (Camera::project); the box lies inside
// their convex hull there, so a pixel square that misses the hull (widened by 0.01 px, for the
// float rays) cannot see the part. When a corner is not in front of the camera the projection
// does not bound the box, and every pixel is kept.
#pragma once

#include <vector>

namespace sl {

struct Scene;

struct PixelSpan {
    int begin = 0, end = 0;  // pixels [begin, end) of a row
};

/// One span per image row (empty spans for rows that cannot see the part).
std::vector<PixelSpan> partFootprint(const Scene& scene);

}  // namespace sl
