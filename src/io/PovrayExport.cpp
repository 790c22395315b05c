#include "io/PovrayExport.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include "core/Error.h"
#include "core/Rng.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "scene/EnvMapBasis.h"
#include "scene/Scene.h"

namespace sl {

namespace {

std::string num(double v) {
    return formatNumber(v, 10);
}

std::string vec(const Vec3d& v) {
    std::string s = "<";
    s += num(v.x);
    s += ", ";
    s += num(v.y);
    s += ", ";
    s += num(v.z);
    s += ">";
    return s;
}

}  // namespace

std::string povraySceneText(const Scene& scene, const PovraySettings& st, uint64_t seed,
                            const std::string& heightfieldName, const std::string& envmapName) {
    const CameraDesc& cam = scene.camera.desc();
    const Vec3d f = normalize(cam.target - cam.origin);
    const Vec3d left = normalize(cross(cam.up, f));
    const Vec3d up = cross(f, left);
    const double aspect = static_cast<double>(cam.width) / cam.height;
    const bool ortho = cam.type == CameraDesc::Type::Orthographic;
    const double span = ortho ? cam.widthMm : 2.0 * std::tan(cam.fovDeg * std::numbers::pi / 360.0);
    const Heightfield& hf = *scene.surface;
    const double ex = hf.extentX(), ez = hf.extentZ();
    const double hmin = hf.minHeight(), hmax = hf.maxHeight();
    const double range = hmax > hmin ? hmax - hmin : 1.0;
    const double size =
        length(cam.origin) + length(cam.target) + ex + ez + std::abs(hmin) + std::abs(hmax) + 1.0;
    const ConductorParams& m = scene.bsdf.params();
    const double cosView =
        std::clamp(dot(normalize(cam.origin - cam.target), Vec3d{0, 1, 0}), 0.0, 1.0);
    const Rgb fr = fresnelConductor(static_cast<float>(cosView), m.ior.eta, m.ior.k);
    const Rgb F{fr.x * m.specularReflectance.x, fr.y * m.specularReflectance.y,
                fr.z * m.specularReflectance.z};
    const double alpha = m.smooth ? 0.0 : std::sqrt(static_cast<double>(m.alphaU) * m.alphaV);

    std::ostringstream x;
    x << "// Exported by scratchlight (src/io/PovrayExport.h has the conventions).\n"
      << "#version 3.7;\n"
      << "global_settings { assumed_gamma 1.0 max_trace_level "
      << std::max(1, scene.desc.render.maxDepth) << " adc_bailout 0 ambient_light 0 }\n"
      << "background { rgb 0 }\n"
      << "camera { " << (ortho ? "orthographic" : "perspective") << "\n"
      << "  location " << vec(cam.origin) << "\n"
      << "  direction " << vec(f) << "\n"
      << "  right " << vec(-left * span) << "\n"
      << "  up " << vec(up * (span / aspect)) << "\n}\n";
    x << "sphere { <0, 0, 0>, " << num(1e4 * size) << " hollow no_image no_shadow\n"
      << "  texture { pigment { image_map { exr \"" << envmapName << "\" map_type 1 } }\n"
      << "            finish { emission 1 ambient 0 diffuse 0 specular 0 } }\n}\n";
    x << "height_field { png \"" << heightfieldName << "\"\n"
      << "  scale <" << num(ex) << ", " << num(range) << ", " << num(ez) << ">\n"
      << "  translate <" << num(-0.5 * ex) << ", " << num(hmin) << ", " << num(-0.5 * ez) << ">\n";
    const std::string finish = "finish { ambient 0 diffuse 0 specular 0 reflection { rgb <" +
                               num(F.x) + ", " + num(F.y) + ", " + num(F.z) + "> } }";
    if (alpha <= 0 || st.roughSamples <= 1) {
        x << "  texture { pigment { rgb 0 } " << finish << " }\n";
    } else {
        const double pitch = hf.pitch();
        x << "  texture { average texture_map {\n";
        Pcg32 rng(mix64(seed), 0x5eedULL);
        for (int k = 0; k < st.roughSamples; ++k) {
            const Vec3d t{1e3 * rng.nextFloat(), 1e3 * rng.nextFloat(), 1e3 * rng.nextFloat()};
            x << "    [1 pigment { rgb 0 } normal { bumps " << num(alpha * st.bumpsPerAlpha)
              << " translate " << vec(t) << " scale " << num(pitch) << " } " << finish << "]\n";
        }
        x << "  } }\n";
    }
    x << "}\n";
    return x.str();
}

void writePovrayHeightfield(const std::filesystem::path& file, const Scene& scene) {
    const int W = scene.mapWidth, H = scene.mapHeight;
    const double hmin = scene.surface->minHeight(), hmax = scene.surface->maxHeight();
    const double range = hmax > hmin ? hmax - hmin : 1.0;
    Image img(W, H, 1);
    for (int r = 0; r < H; ++r) {
        const int j = H - 1 - r;  // PNG rows bottom-up (see the header comment)
        for (int i = 0; i < W; ++i)
            img.at(i, r) =
                static_cast<float>((scene.heights[static_cast<size_t>(j) * W + i] - hmin) / range);
    }
    writePng16(file, img);
}

void writePovrayEnvMap(const std::filesystem::path& file, const EnvMap& env,
                       const EnvMapBasis& basis, int envScale) {
    if (env.width != basis.width() || env.height != basis.height() ||
        (env.channels != 1 && env.channels != 3) ||
        env.texels.size() != env.texelCount() * env.channels)
        throw inputError("POV-Ray env map", "not on the scene's grid",
                         "pass an env map of the scene's envmap size");
    if (envScale < 1) throw inputError("POV-Ray option 'envScale'", "must be >= 1", "use 16");
    const int W = env.width * envScale, H = env.height * envScale;
    Image img(W, H, 3);
    const double pi = std::numbers::pi;
    for (int r = 0; r < H; ++r) {
        const double v = (r + 0.5) / H;  // acos(d.y)/π
        const double st = std::sin(pi * v), ct = std::cos(pi * v);
        for (int c = 0; c < W; ++c) {
            const double up = 2.0 * pi * (c + 0.5) / W;  // POV-Ray's angle from +x toward +z
            const Vec3f d{static_cast<float>(st * std::cos(up)), static_cast<float>(ct),
                          static_cast<float>(st * std::sin(up))};
            const TexelWeights w = basis.weights(d);
            for (int ch = 0; ch < 3; ++ch) {
                double s = 0;
                for (int k = 0; k < 4; ++k) {
                    const size_t t = w.index[k];
                    s += w.weight[k] * env.texels[env.channels == 3 ? 3 * t + ch : t];
                }
                img.at(c, r, ch) = static_cast<float>(s);
            }
        }
    }
    writeExr(file, img);
}

PovrayFiles exportPovray(const Scene& scene, const EnvMap& env, const PovraySettings& settings,
                         uint64_t seed, const std::filesystem::path& dir) {
    PovrayFiles f{dir / "scene.pov", dir / "heightfield.png", dir / "envmap.exr"};
    writePovrayHeightfield(f.heightfield, scene);
    writePovrayEnvMap(f.envmap, env, scene.basis, settings.envScale);
    const std::string text =
        povraySceneText(scene, settings, seed, "heightfield.png", "envmap.exr");
    writeAtomically(f.scene, [&](const std::filesystem::path& tmp) {
        std::ofstream os(tmp);
        os << text;
        os.close();
        if (!os) throw inputError(f.scene.string(), "write failed", "check the disk space");
    });
    return f;
}

std::vector<std::string> povrayArguments(const Scene& scene, const PovraySettings& st,
                                         const std::string& sceneName,
                                         const std::string& outputName, int threads) {
    const int s = std::max(1, st.supersample);
    std::vector<std::string> a = {"+I" + sceneName,
                                  "+O" + outputName,
                                  "+FE",
                                  "+W" + std::to_string(scene.camera.width() * s),
                                  "+H" + std::to_string(scene.camera.height() * s),
                                  "-A",
                                  "-J",
                                  "-D",
                                  "-P",
                                  "-V",
                                  "-GA",
                                  "+GF",
                                  "-UA",
                                  "File_Gamma=1.0",
                                  "Display_Gamma=1.0"};
    if (threads > 0) a.push_back("+WT" + std::to_string(threads));
    return a;
}

Image povrayDownsample(const Image& img, int factor) {
    if (factor < 1 || img.width % factor || img.height % factor || img.channels < 1)
        throw std::runtime_error("povrayDownsample: a " + std::to_string(img.width) + "x" +
                                 std::to_string(img.height) + " image is not a multiple of " +
                                 std::to_string(factor));
    const int W = img.width / factor, H = img.height / factor;
    Image out(W, H, 3);
    const double inv = 1.0 / (static_cast<double>(factor) * factor);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) {
                const int ic = img.channels >= 3 ? c : 0;
                double s = 0;
                for (int b = 0; b < factor; ++b)
                    for (int a = 0; a < factor; ++a)
                        s += img.at(x * factor + a, y * factor + b, ic);
                out.at(x, y, c) = static_cast<float>(s * inv);
            }
    return out;
}

}  // namespace sl
