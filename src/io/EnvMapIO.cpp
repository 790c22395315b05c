#include "io/EnvMapIO.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "core/Color.h"
#include "core/Error.h"
#include "core/Text.h"
#include "io/ImageIO.h"
#include "scene/EnvMapPresets.h"

namespace sl {

namespace {

constexpr double kPi = std::numbers::pi;

/// cos a − cos b, accurate also for tiny intervals: 2 sin((a+b)/2) sin((b−a)/2).
double cosDiff(double a, double b) {
    return 2.0 * std::sin(0.5 * (a + b)) * std::sin(0.5 * (b - a));
}

/// θ range of output row j's cell.
void cellTheta(int j, int height, double& t0, double& t1) {
    const double step = kPi / (height - 1);
    t0 = std::max(0.0, (j - 0.5) * step);
    t1 = std::min(kPi, (j + 0.5) * step);
}

/// ∫ sinθ dθ over row j's cell, computed on the mirrored row in the southern half so the
/// map of cell areas is exactly symmetric about the equator.
double cellCosDiff(int j, int height) {
    double t0, t1;
    cellTheta(std::min(j, height - 1 - j), height, t0, t1);
    return cosDiff(t0, t1);
}

/// One contribution of an input row/column to an output row/column.
struct Weight {
    int out;
    double w;
};

/// For every input column x (0..nIn-1): the output columns its interval overlaps and the
/// overlap lengths in u. `first[x]`..`first[x+1]` index into `w`.
void uWeights(int nIn, int nOut, std::vector<size_t>& first, std::vector<Weight>& w) {
    first.assign(static_cast<size_t>(nIn) + 1, 0);
    w.clear();
    for (int x = 0; x < nIn; ++x) {
        first[static_cast<size_t>(x)] = w.size();
        const double a = static_cast<double>(x) / nIn, b = static_cast<double>(x + 1) / nIn;
        int i0 = std::clamp(static_cast<int>(std::floor(a * nOut)) - 1, 0, nOut - 1);
        for (int i = i0; i < nOut; ++i) {
            const double c = static_cast<double>(i) / nOut, d = static_cast<double>(i + 1) / nOut;
            if (c >= b) break;
            const double len = std::min(b, d) - std::max(a, c);
            if (len > 0.0) w.push_back({i, len});
        }
    }
    first[static_cast<size_t>(nIn)] = w.size();
}

/// For every input row y: the output rows whose cells it overlaps and ∫ sinθ dθ over the
/// overlap.
void thetaWeights(int nIn, int nOut, std::vector<size_t>& first, std::vector<Weight>& w) {
    first.assign(static_cast<size_t>(nIn) + 1, 0);
    w.clear();
    const double step = kPi / (nOut - 1);
    for (int y = 0; y < nIn; ++y) {
        first[static_cast<size_t>(y)] = w.size();
        const double a = y * kPi / nIn, b = (y + 1) * kPi / nIn;
        int j0 = std::clamp(static_cast<int>(std::floor(a / step + 0.5)) - 1, 0, nOut - 1);
        for (int j = j0; j < nOut; ++j) {
            double c, d;
            cellTheta(j, nOut, c, d);
            if (c >= b) break;
            const double lo = std::max(a, c), hi = std::min(b, d);
            if (hi > lo) w.push_back({j, cosDiff(lo, hi)});
        }
    }
    first[static_cast<size_t>(nIn)] = w.size();
}

void checkGrid(const std::string& where, int width, int height, int channels) {
    if (width < 1 || height < 2)
        throw inputError(
            where,
            "env map size " + std::to_string(width) + "x" + std::to_string(height) + " is invalid",
            "Use width >= 1 and height >= 2 (rows sit at θ = jπ/(H−1))");
    if (channels != 1 && channels != 3)
        throw inputError(where, "env map channels = " + std::to_string(channels) + " is invalid",
                         "Use 1 (gray) or 3 (RGB)");
}

void checkSource(const std::string& where, const Image& src) {
    if (src.width < 1 || src.height < 1) throw inputError(where, "the env map image is empty");
    if (src.channels < 1 || src.channels > 4)
        throw inputError(where,
                         "env map image has " + std::to_string(src.channels) +
                             " channels (supported: 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA)",
                         "Save the env map as gray or RGB");
    if (src.data.size() != src.pixelCount() * static_cast<size_t>(src.channels))
        throw inputError(where, "internal error: image data size does not match its dimensions");
    const size_t c = static_cast<size_t>(src.channels);
    for (size_t k = 0; k < src.data.size(); ++k) {
        if (!std::isfinite(src.data[k])) {
            const size_t p = k / c, w = static_cast<size_t>(src.width);
            throw inputError(where,
                             std::string("env map value is ") +
                                 (std::isnan(src.data[k]) ? "NaN" : "infinite") + " at row " +
                                 std::to_string(p / w) + ", column " + std::to_string(p % w),
                             "Fix or replace the env map image");
        }
    }
}

/// A file's pixels are radiance, never negative. Resampling ringing in real HDR photos leaves
/// tiny negative values: up to kEnvNegativeTolerance of the map's largest colour value they are
/// clamped to 0 with one warning line; anything larger is refused with the numbers. Alpha is
/// ignored.
void clampOrRefuseNegative(const std::string& where, Image& src) {
    const size_t c = static_cast<size_t>(src.channels);
    const size_t colour = src.channels >= 3 ? 3 : 1;
    float maxValue = 0.0f, worst = 0.0f;
    size_t worstAt = 0, negativeValues = 0, negativePixels = 0;
    for (size_t p = 0; p * c < src.data.size(); ++p) {
        bool negative = false;
        for (size_t k = p * c; k < p * c + colour; ++k) {
            const float v = src.data[k];
            maxValue = std::max(maxValue, v);
            if (!(v < 0.0f)) continue;
            negative = true;
            ++negativeValues;
            if (v < worst) {
                worst = v;
                worstAt = k;
            }
        }
        negativePixels += negative ? 1 : 0;
    }
    if (negativePixels == 0) return;
    const size_t p = worstAt / c, w = static_cast<size_t>(src.width);
    const std::string at = "row " + std::to_string(p / w) + ", column " + std::to_string(p % w) +
                           ", channel " + std::to_string(worstAt % c);
    const double ratio = maxValue > 0.0f ? -static_cast<double>(worst) / maxValue : 0.0;
    if (maxValue <= 0.0f || ratio > kEnvNegativeTolerance)
        throw inputError(
            where,
            "env map value is negative (" + formatNumber(worst) + ") at " + at + ", the worst of " +
                std::to_string(negativeValues) + " negative value" +
                (negativeValues == 1 ? "" : "s") + " against a maximum of " +
                formatNumber(maxValue) + " (" + formatNumber(ratio) + " of it; up to " +
                formatNumber(kEnvNegativeTolerance) +
                " is resampling ringing, clamped with a warning); an environment map holds "
                "radiance, which is never negative",
            "Clamp the image's negative values to 0 and save it again");
    for (size_t k = 0; k < src.data.size(); ++k)
        if (k % c < colour && src.data[k] < 0.0f) src.data[k] = 0.0f;
    spdlog::warn(
        "{}: {} pixel{} slightly negative (the worst {} at {}, {} of the maximum {}: "
        "resampling ringing); clamped to 0",
        where, negativePixels, negativePixels == 1 ? " was" : "s were", formatNumber(worst), at,
        formatNumber(ratio), formatNumber(maxValue));
}

/// Pixel (x, y) of src converted to `channels` output channels, in double.
inline void convertPixel(const Image& src, const float* px, int channels, double out[3]) {
    if (src.channels >= 3) {
        if (channels == 1) {
            out[0] = luminance<double>(px[0], px[1], px[2]);
        } else {
            out[0] = px[0];
            out[1] = px[1];
            out[2] = px[2];
        }
    } else {
        out[0] = out[1] = out[2] = px[0];
    }
}

}  // namespace

EnvMap resampleEquirect(const Image& src, int width, int height, int channels,
                        const std::string& where) {
    checkGrid(where, width, height, channels);
    checkSource(where, src);

    std::vector<size_t> uFirst, tFirst;
    std::vector<Weight> uW, tW;
    uWeights(src.width, width, uFirst, uW);
    thetaWeights(src.height, height, tFirst, tW);

    const size_t C = static_cast<size_t>(channels), W = static_cast<size_t>(width);
    std::vector<double> acc(static_cast<size_t>(height) * W * C, 0.0);
    std::vector<double> rowU(W * C);
    for (int y = 0; y < src.height; ++y) {
        // Integrate the input row over each output column's u interval.
        std::fill(rowU.begin(), rowU.end(), 0.0);
        const float* row = src.data.data() + static_cast<size_t>(y) * src.width * src.channels;
        for (int x = 0; x < src.width; ++x) {
            double v[3];
            convertPixel(src, row + static_cast<size_t>(x) * src.channels, channels, v);
            for (size_t k = uFirst[static_cast<size_t>(x)]; k < uFirst[static_cast<size_t>(x) + 1];
                 ++k) {
                double* o = &rowU[static_cast<size_t>(uW[k].out) * C];
                for (size_t c = 0; c < C; ++c) o[c] += uW[k].w * v[c];
            }
        }
        // Spread it over the output rows whose θ cells the input row overlaps.
        for (size_t k = tFirst[static_cast<size_t>(y)]; k < tFirst[static_cast<size_t>(y) + 1];
             ++k) {
            double* o = &acc[static_cast<size_t>(tW[k].out) * W * C];
            const double w = tW[k].w;
            for (size_t q = 0; q < W * C; ++q) o[q] += w * rowU[q];
        }
    }

    EnvMap env;
    env.width = width;
    env.height = height;
    env.channels = channels;
    env.texels.resize(acc.size());
    const double du = 1.0 / width;
    for (int j = 0; j < height; ++j) {
        const double norm = 1.0 / (du * cellCosDiff(j, height));
        for (size_t q = 0; q < W * C; ++q) {
            const size_t idx = static_cast<size_t>(j) * W * C + q;
            env.texels[idx] = static_cast<float>(acc[idx] * norm);
        }
    }
    return env;
}

EnvMap loadEnvMap(const std::filesystem::path& file, int width, int height, int channels) {
    const std::string where = file.string();
    if (channels != 0) checkGrid(where, width, height, channels);
    Image img = readImage(file);
    checkSource(where, img);
    clampOrRefuseNegative(where, img);
    if (channels == 0) {
        channels = img.channels >= 3 ? 3 : 1;
        checkGrid(where, width, height, channels);
    }
    if (img.width == width && img.height == height) {
        // Already on the texel grid: convert channels only.
        EnvMap env = EnvMap::constant(width, height, 0.0f, channels);
        for (size_t p = 0; p < img.pixelCount(); ++p) {
            double v[3];
            convertPixel(img, img.data.data() + p * static_cast<size_t>(img.channels), channels, v);
            for (int c = 0; c < channels; ++c)
                env.texels[p * static_cast<size_t>(channels) + static_cast<size_t>(c)] =
                    static_cast<float>(v[c]);
        }
        return env;
    }
    return resampleEquirect(img, width, height, channels, where);
}

std::vector<double> envCellSolidAngles(int width, int height) {
    checkGrid("envCellSolidAngles", width, height, 1);
    std::vector<double> sa(static_cast<size_t>(width) * static_cast<size_t>(height));
    for (int j = 0; j < height; ++j) {
        const double a = 2.0 * kPi / width * cellCosDiff(j, height);
        std::fill_n(sa.begin() + static_cast<std::ptrdiff_t>(j) * width, width, a);
    }
    return sa;
}

void writeEnvMap(const std::filesystem::path& file, const EnvMap& env) {
    const std::string where = file.string();
    checkGrid(where, env.width, env.height, env.channels);
    if (env.texels.size() != env.texelCount() * static_cast<size_t>(env.channels))
        throw inputError(where, "internal error: env map texel count does not match its size");
    writeExr(file, env.toImage());
}

Image envMapPreview(const EnvMap& env, int scale) {
    if (scale < 1)
        throw inputError("envMapPreview", "scale " + std::to_string(scale) + " is invalid",
                         "Use a scale >= 1");
    if (env.texels.size() != env.texelCount() * static_cast<size_t>(env.channels))
        throw inputError("envMapPreview", "internal error: texel count does not match the size");
    Image img(env.width * scale, env.height * scale, env.channels);
    const size_t C = static_cast<size_t>(env.channels);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            const size_t s = (static_cast<size_t>(y / scale) * env.width + x / scale) * C;
            const size_t d = (static_cast<size_t>(y) * img.width + x) * C;
            for (size_t c = 0; c < C; ++c) img.data[d + c] = env.texels[s + c];
        }
    return img;
}

std::string lightSpecForms() {
    std::string s = "FILE (EXR/HDR/PNG/JPEG, equirectangular) | const:V (V >= 0)";
    for (const std::string& n : presetNames()) s += " | " + n;
    return s;
}

EnvMap lightFromSpec(const std::string& spec, int w, int h, int channels,
                     const std::string& where) {
    if (spec.rfind("const:", 0) == 0) {
        const std::string v = spec.substr(6);
        double value = -1;
        try {
            size_t used = 0;
            value = std::stod(v, &used);
            if (used != v.size()) value = -1;
        } catch (const std::exception&) {
        }
        if (!(value >= 0) || !std::isfinite(value))
            throw inputError(where + " " + spec, "'" + v + "' is not a number >= 0",
                             "use " + lightSpecForms());
        if (value > kMaxRadiance)  // scene/EnvMap.h
            throw inputError(where + " " + spec,
                             "'" + v + "' is more than " + formatNumber(kMaxRadiance),
                             "give a radiance in [0, " + formatNumber(kMaxRadiance) +
                                 "] (1 is the optimizer's brightest)");
        return EnvMap::constant(w, h, static_cast<float>(value), channels == 3 ? 3 : 1);
    }
    if (spec.rfind("envmap:", 0) == 0) return loadEnvMap(spec.substr(7), w, h, channels);
    const auto& presets = presetNames();
    if (std::find(presets.begin(), presets.end(), spec) != presets.end() &&
        !std::filesystem::exists(spec)) {
        EnvMap m = presetEnvMap(spec, w, h);
        if (channels != 3 || m.channels != 1) return m;
        EnvMap rgb = EnvMap::constant(w, h, 0.0f, 3);
        for (size_t t = 0; t < m.texelCount(); ++t)
            for (int k = 0; k < 3; ++k) rgb.texels[3 * t + k] = m.texels[t];
        return rgb;
    }
    // Neither a light name nor a file there: say both, and where a relative path was looked for
    // (the working directory; a scene file's own envmap.path is resolved by the scene parser).
    std::error_code ec;
    if (!spec.empty() && !std::filesystem::exists(spec, ec)) {
        const std::string nearest = nearestName(spec, presets);
        throw inputError(where + " '" + spec + "'",
                         "is neither a light name nor a file (looked for " +
                             std::filesystem::absolute(spec, ec).string() +
                             "; a relative path is resolved against the working directory)",
                         (nearest.empty() ? std::string() : "Did you mean '" + nearest + "'? ") +
                             "Give one of " + lightSpecForms());
    }
    return loadEnvMap(spec, w, h, channels);
}

}  // namespace sl
