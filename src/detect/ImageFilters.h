// The defect map's image filters (detect/DefectMap.h, method auto): running medians along rows,
// columns and both, 2×2 pooling, separable and robust local quadratic fits, the robust spread of
// a map. W×H images are row-major float vectors; sums in double.
#pragma once

#include <cstddef>
#include <vector>

namespace sl::defectmap {

/// Mirror index into [0, n): reflection about the borders (… 2 1 0 1 2 …), any i.
int mirror(int i, int n);

/// Running medians along every row of a W×H image (windows shrink at the borders).
void rowMedians(const float* img, int W, int H, int w, float* out);

/// Running medians along every column of a W×H image (periodic or shrinking at the borders);
/// columns are gathered in blocks of 16, a cache line of each row at a time.
void columnMedians(const float* img, int W, int H, int w, bool periodic, float* out);

/// Separable running median of a W×H image: along x (rows), then along z (columns); windows
/// shrink at the borders.
std::vector<float> separableMedian(const std::vector<float>& img, int W, int H, int w);

/// The 2×2 mean of a W×H image: ⌈W/2⌉×⌈H/2⌉ (a border cell averages the samples it has).
std::vector<float> pool2(const float* img, int W, int H, int& W2, int& H2);

/// Separable quadratic Savitzky–Golay smoothing of a W×H image over w (odd) samples along x,
/// then along z: the local least-squares quadratic's value at the centre. Borders: mirrored.
/// alongX / alongZ false skips that pass.
std::vector<float> separableQuadratic(const std::vector<float>& img, int W, int H, int w,
                                      bool alongX = true, bool alongZ = true);

/// The residual of img against its local quadratic fit over w samples along one axis, the fit
/// taken without the samples whose least-squares residual `ls` exceeds `limit` (step 5,
/// edgeRobust). Where no sample of the window is left out, or fewer than 4 remain, the
/// least-squares residual stays.
std::vector<float> robustQuadraticResidual(const std::vector<float>& img,
                                           const std::vector<float>& ls, int W, int H, int w,
                                           bool alongX, double limit);

/// Median of |v| over at most ~4M samples taken at a fixed stride (deterministic).
double medianAbs(const std::vector<float>& v);

}  // namespace sl::defectmap

namespace sl {

/// Step 1's separable running median of a W×H image over w samples (odd): along x (rows),
/// then along z (columns); windows shrink at the borders. Shared with detect/LayMap.
std::vector<float> separableRunningMedian(const std::vector<float>& img, int W, int H, int w);

}  // namespace sl
