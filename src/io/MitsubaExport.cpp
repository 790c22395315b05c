#include "io/MitsubaExport.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/Error.h"
#include "core/Text.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "scene/Materials.h"
#include "scene/Scene.h"

namespace sl {

static_assert(std::endian::native == std::endian::little,
              "writeHeightfieldPly writes host-order floats as binary_little_endian");

namespace {

/// Numbers in the XML: nine significant digits, so floats round-trip.
std::string num(double v) {
    return formatNumber(v, 9);
}

std::string triple(double a, double b, double c) {
    return num(a) + ", " + num(b) + ", " + num(c);
}

/// Text inside an XML comment: escaped, and without "--" (not allowed there).
std::string xmlComment(const std::string& s) {
    std::string out = escapeXml(s);
    for (size_t p; (p = out.find("--")) != std::string::npos;) out.replace(p, 2, "- -");
    return out;
}

}  // namespace

void writeHeightfieldPly(const std::filesystem::path& file, int W, int H, double pitch,
                         std::span<const float> heights) {
    if (W < 2 || H < 2 || heights.size() != static_cast<size_t>(W) * H)
        throw inputError(file.string(),
                         "height field " + std::to_string(W) + "x" + std::to_string(H) + " with " +
                             std::to_string(heights.size()) + " samples",
                         "need at least 2x2 samples, W*H values");
    const uint64_t vertices = static_cast<uint64_t>(W) * H;
    const uint64_t faces = 2ull * (W - 1) * (H - 1);
    if (vertices > 0x7fffffffull)
        throw inputError(file.string(), "too many vertices for 32-bit PLY indices",
                         "downsample the height map");
    writeAtomically(file, [&](const std::filesystem::path& tmp) {
        std::ofstream os(tmp, std::ios::binary);
        os << "ply\nformat binary_little_endian 1.0\n"
           << "comment scratchlight height field: sample (row j, col i) at x = (i-(W-1)/2)*p, "
              "y = h, z = (j-(H-1)/2)*p; u = i/(W-1), v = j/(H-1)\n"
           << "comment W " << W << " H " << H << " pitch " << num(pitch) << "\n"
           << "element vertex " << vertices << "\n"
           << "property float x\nproperty float y\nproperty float z\n"
           << "property float u\nproperty float v\n"
           << "element face " << faces << "\n"
           << "property list uchar int vertex_indices\n"
           << "end_header\n";
        std::vector<char> buf;
        buf.reserve(1 << 20);
        auto flush = [&] {
            os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
            buf.clear();
        };
        auto put = [&](const void* p, size_t n) {
            const char* c = static_cast<const char*>(p);
            buf.insert(buf.end(), c, c + n);
            if (buf.size() >= (1u << 20)) flush();
        };
        const double cx = 0.5 * (W - 1), cz = 0.5 * (H - 1);
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const float v[5] = {static_cast<float>((i - cx) * pitch),
                                    heights[static_cast<size_t>(j) * W + i],
                                    static_cast<float>((j - cz) * pitch),
                                    static_cast<float>(static_cast<double>(i) / (W - 1)),
                                    static_cast<float>(static_cast<double>(j) / (H - 1))};
                put(v, sizeof v);
            }
        auto id = [W](int i, int j) { return static_cast<int32_t>(j * W + i); };
        for (int j = 0; j + 1 < H; ++j)
            for (int i = 0; i + 1 < W; ++i) {
                const int32_t v0 = id(i, j), v1 = id(i + 1, j), v2 = id(i + 1, j + 1),
                              v3 = id(i, j + 1);
                // Embree's split {v0,v1,v3}, {v2,v3,v1}, wound so the normal points to +Y.
                const int32_t t[2][3] = {{v0, v3, v1}, {v2, v1, v3}};
                for (const auto& tri : t) {
                    const uint8_t n = 3;
                    put(&n, 1);
                    put(tri, sizeof tri);
                }
            }
        flush();
        os.close();  // flushes; a failed flush or close sets failbit
        if (!os) throw inputError(file.string(), "write failed", "check the disk space");
    });
}

std::string mitsubaSceneXml(const Scene& scene, const std::string& plyName,
                            const std::string& envmapName) {
    const CameraDesc& cam = scene.camera.desc();
    const ConductorParams& m = scene.bsdf.params();
    const RenderDesc& r = scene.desc.render;
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
      << "<!-- Exported by scratchlight export-mitsuba from "
      << xmlComment(scene.desc.file.string()) << ".\n"
      << "     Render with an RGB variant: mitsuba -m scalar_rgb scene.xml\n"
      << "     Conventions: README \"Conventions\"; this export: src/io/MitsubaExport.h. -->\n"
      << "<scene version=\"3.0.0\">\n";
    x << "    <integrator type=\"path\">\n"
      << "        <integer name=\"max_depth\" value=\"" << r.maxDepth << "\"/>\n"
      << "        <integer name=\"rr_depth\" value=\"" << std::max(5, r.maxDepth) << "\"/>\n"
      << "        <boolean name=\"hide_emitters\" value=\"true\"/>\n"
      << "    </integrator>\n";
    const double dist = length(cam.target - cam.origin);
    const bool ortho = cam.type == CameraDesc::Type::Orthographic;
    x << "    <sensor type=\"" << (ortho ? "orthographic" : "perspective") << "\">\n";
    if (!ortho) {
        x << "        <string name=\"fov_axis\" value=\"x\"/>\n"
          << "        <float name=\"fov\" value=\"" << num(cam.fovDeg) << "\"/>\n";
    }
    x << "        <float name=\"near_clip\" value=\"" << num(std::min(0.01, 1e-4 * dist))
      << "\"/>\n"
      << "        <float name=\"far_clip\" value=\"" << num(std::max(1e4, 100.0 * dist)) << "\"/>\n"
      << "        <transform name=\"to_world\">\n";
    if (ortho)
        x << "            <scale x=\"" << num(0.5 * cam.widthMm) << "\" y=\""
          << num(0.5 * cam.widthMm) << "\"/>\n";
    x << "            <lookat origin=\"" << triple(cam.origin.x, cam.origin.y, cam.origin.z)
      << "\" target=\"" << triple(cam.target.x, cam.target.y, cam.target.z) << "\" up=\""
      << triple(cam.up.x, cam.up.y, cam.up.z) << "\"/>\n"
      << "        </transform>\n"
      << "        <sampler type=\"independent\">\n"
      << "            <integer name=\"sample_count\" value=\"" << r.spp << "\"/>\n"
      << "            <integer name=\"seed\" value=\"" << (r.seed & 0x7fffffff) << "\"/>\n"
      << "        </sampler>\n"
      << "        <film type=\"hdrfilm\">\n"
      << "            <integer name=\"width\" value=\"" << cam.width << "\"/>\n"
      << "            <integer name=\"height\" value=\"" << cam.height << "\"/>\n"
      << "            <string name=\"pixel_format\" value=\"rgb\"/>\n"
      << "            <rfilter type=\"box\"/>\n"
      << "        </film>\n"
      << "    </sensor>\n";
    x << "    <emitter type=\"envmap\">\n"
      << "        <string name=\"filename\" value=\"" << escapeXml(envmapName) << "\"/>\n"
      << "    </emitter>\n";
    x << "    <shape type=\"ply\">\n"
      << "        <string name=\"filename\" value=\"" << escapeXml(plyName) << "\"/>\n"
      << "        <boolean name=\"face_normals\" value=\"true\"/>\n";
    const std::string& name = scene.desc.material.name;
    std::string source = name;
    try {
        source = name + ": " + conductorSource(name);
    } catch (const InputError&) {
        // custom eta/k: no named source
    }
    x << "        <!-- material " << xmlComment(source) << " -->\n";
    if (m.smooth) {
        x << "        <bsdf type=\"conductor\">\n";
    } else {
        x << "        <bsdf type=\"roughconductor\">\n"
          << "            <string name=\"distribution\" value=\"" << microfacetName(m.distribution)
          << "\"/>\n"
          << "            <float name=\"alpha_u\" value=\"" << num(m.alphaU) << "\"/>\n"
          << "            <float name=\"alpha_v\" value=\"" << num(m.alphaV) << "\"/>\n";
    }
    x << "            <rgb name=\"eta\" value=\"" << triple(m.ior.eta.x, m.ior.eta.y, m.ior.eta.z)
      << "\"/>\n"
      << "            <rgb name=\"k\" value=\"" << triple(m.ior.k.x, m.ior.k.y, m.ior.k.z)
      << "\"/>\n";
    const Rgb& sr = m.specularReflectance;
    if (sr.x != 1.0f || sr.y != 1.0f || sr.z != 1.0f)
        x << "            <rgb name=\"specular_reflectance\" value=\"" << triple(sr.x, sr.y, sr.z)
          << "\"/>\n";
    x << "        </bsdf>\n"
      << "    </shape>\n"
      << "</scene>\n";
    return x.str();
}

MitsubaExport exportMitsuba(const Scene& scene, const EnvMap& env,
                            const std::filesystem::path& outDir) {
    if (env.width != scene.basis.width() || env.height != scene.basis.height() ||
        (env.channels != 1 && env.channels != 3) ||
        env.texels.size() != env.texelCount() * env.channels)
        throw inputError("export-mitsuba",
                         "the env map is not on the scene's " +
                             std::to_string(scene.basis.width()) + "x" +
                             std::to_string(scene.basis.height()) + " grid",
                         "load it with loadEnvMap on the scene's grid");
    MitsubaExport e;
    e.xml = outDir / "scene.xml";
    e.ply = outDir / "heightfield.ply";
    e.envmap = outDir / "envmap.exr";
    writeHeightfieldPly(e.ply, scene.mapWidth, scene.mapHeight, scene.desc.heightmap.pitch,
                        scene.heights);
    Image rgb(env.width, env.height, 3);
    for (size_t t = 0; t < env.texelCount(); ++t)
        for (int c = 0; c < 3; ++c)
            rgb.data[t * 3 + c] = env.texels[t * env.channels + (env.channels == 3 ? c : 0)];
    writeExr(e.envmap, rgb);
    const std::string xml =
        mitsubaSceneXml(scene, e.ply.filename().string(), e.envmap.filename().string());
    writeTextAtomically(e.xml, xml);
    e.notes.push_back(
        "render with an RGB variant (scalar_rgb, llvm_ad_rgb, cuda_ad_rgb): eta/k are RGB values");
    e.notes.push_back(
        "Mitsuba draws its own random numbers: compare the images' means or at high spp, not "
        "their noise");
    if (scene.desc.material.name == "Fe")
        e.notes.push_back(
            "Fe is not a Mitsuba material: written as explicit eta/k (Johnson & "
            "Christy 1974)");
    return e;
}

}  // namespace sl
