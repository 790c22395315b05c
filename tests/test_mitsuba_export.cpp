// export-mitsuba: the XML (camera, film, integrator, material, emitter), the PLY height field
// (vertex/face counts, the height-map convention, Embree's triangle split and +Y winding) and
// the env-map EXR, on small maps made here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "TestUtil.h"
#include "core/Vec3.h"
#include "io/ImageIO.h"
#include "io/MitsubaExport.h"
#include "io/SceneFile.h"
#include "scene/Scene.h"

namespace sl {
namespace {

struct Ply {
    size_t vertices = 0, faces = 0;
    std::vector<float> v;  // x, y, z, u, v per vertex
    std::vector<std::array<int32_t, 3>> f;
    std::string header;
};

Ply readPly(const std::filesystem::path& file) {
    std::ifstream is(file, std::ios::binary);
    Ply p;
    std::string line;
    while (std::getline(is, line)) {
        p.header += line + "\n";
        std::istringstream ls(line);
        std::string a, b;
        ls >> a >> b;
        if (a == "element" && b == "vertex") ls >> p.vertices;
        if (a == "element" && b == "face") ls >> p.faces;
        if (a == "end_header") break;
    }
    p.v.resize(p.vertices * 5);
    is.read(reinterpret_cast<char*>(p.v.data()),
            static_cast<std::streamsize>(p.v.size() * sizeof(float)));
    for (size_t k = 0; k < p.faces; ++k) {
        uint8_t n = 0;
        is.read(reinterpret_cast<char*>(&n), 1);
        EXPECT_EQ(n, 3);
        std::array<int32_t, 3> t{};
        is.read(reinterpret_cast<char*>(t.data()), sizeof t);
        p.f.push_back(t);
    }
    EXPECT_TRUE(is.good());
    EXPECT_EQ(is.peek(), std::char_traits<char>::eof());  // nothing after the last face
    return p;
}

Vec3d vertex(const Ply& p, int32_t k) {
    return {p.v[k * 5], p.v[k * 5 + 1], p.v[k * 5 + 2]};
}

std::unique_ptr<Scene> makeScene(const test::TempDir& dir, int w, int h,
                                 const std::vector<float>& heights, const std::string& extra) {
    test::writeNpyF32(dir / "h.npy", h, w, heights);
    const std::string json = R"({"heightmap": {"path": "h.npy", "pixel_pitch": 0.02},
        "camera": {"origin": [1, 5, 4], "target": [0, 0, 0.1], "up": [0, 1, 0], "fov": 28,
                   "width": 40, "height": 30},
        "render": {"spp": 12, "max_depth": 3, "seed": 5})" +
                             extra + "}";
    return loadScene(parseScene(json, dir.path(), "test scene"));
}

bool contains(const std::string& s, const std::string& what) {
    return s.find(what) != std::string::npos;
}

TEST(MitsubaExport, FlatMapPlyFollowsTheConventionAndFacesUp) {
    test::TempDir dir("mitsuba");
    const int W = 5, H = 4;
    auto scene = makeScene(dir, W, H, std::vector<float>(W * H, 0.25f),
                           R"(, "material": {"alpha_u": 0.05, "alpha_v": 0.2, "material": "Cu"})");
    const EnvMap env = EnvMap::constant(50, 25, 0.5f);
    const MitsubaExport e = exportMitsuba(*scene, env, dir / "out");
    const Ply p = readPly(e.ply);
    EXPECT_TRUE(contains(p.header, "format binary_little_endian 1.0"));
    EXPECT_TRUE(contains(p.header, "property list uchar int vertex_indices"));
    ASSERT_EQ(p.vertices, static_cast<size_t>(W * H));
    ASSERT_EQ(p.faces, static_cast<size_t>(2 * (W - 1) * (H - 1)));
    // Sample (row j, col i) at x = (i − (W−1)/2)·p, y = h, z = (j − (H−1)/2)·p, u = i/(W−1),
    // v = j/(H−1).
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const size_t k = static_cast<size_t>(j * W + i) * 5;
            EXPECT_FLOAT_EQ(p.v[k], static_cast<float>((i - 2.0) * 0.02));
            EXPECT_FLOAT_EQ(p.v[k + 1], 0.25f);
            EXPECT_FLOAT_EQ(p.v[k + 2], static_cast<float>((j - 1.5) * 0.02));
            EXPECT_FLOAT_EQ(p.v[k + 3], static_cast<float>(i / 4.0));
            EXPECT_FLOAT_EQ(p.v[k + 4], static_cast<float>(j / 3.0));
        }
    // Row 0 is at −z.
    EXPECT_LT(p.v[2], 0.0f);
    // Cell (i, j) = (1, 2): v0=(1,2), v1=(2,2), v2=(2,3), v3=(1,3); Embree's split
    // {v0,v1,v3}, {v2,v3,v1}, wound (v0,v3,v1), (v2,v1,v3).
    const int cell = 2 * (W - 1) + 1;
    const int32_t v0 = 2 * W + 1, v1 = 2 * W + 2, v2 = 3 * W + 2, v3 = 3 * W + 1;
    EXPECT_EQ(p.f[2 * cell], (std::array<int32_t, 3>{v0, v3, v1}));
    EXPECT_EQ(p.f[2 * cell + 1], (std::array<int32_t, 3>{v2, v1, v3}));
    // Mitsuba's face normal normalize(cross(p1 − p0, p2 − p0)) is +Y for every face.
    for (const auto& t : p.f) {
        const Vec3d n =
            normalize(cross(vertex(p, t[1]) - vertex(p, t[0]), vertex(p, t[2]) - vertex(p, t[0])));
        EXPECT_NEAR(n.y, 1.0, 1e-12);
    }
    // The EXR is the texel grid, RGB.
    const Image img = readImage(e.envmap);
    EXPECT_EQ(img.width, 50);
    EXPECT_EQ(img.height, 25);
    EXPECT_EQ(img.channels, 3);
    EXPECT_FLOAT_EQ(img.at(7, 3, 2), 0.5f);
}

TEST(MitsubaExport, BumpyMapWindingStaysOutward) {
    test::TempDir dir("mitsuba");
    const int W = 9, H = 7;
    std::vector<float> h(W * H);
    for (int k = 0; k < W * H; ++k) h[k] = 0.01f * std::sin(1.7f * static_cast<float>(k));
    auto scene = makeScene(dir, W, H, h, "");
    const MitsubaExport e = exportMitsuba(*scene, EnvMap::constant(50, 25, 1.0f), dir / "out");
    const Ply p = readPly(e.ply);
    ASSERT_EQ(p.faces, static_cast<size_t>(2 * (W - 1) * (H - 1)));
    for (const auto& t : p.f) {
        const Vec3d n = cross(vertex(p, t[1]) - vertex(p, t[0]), vertex(p, t[2]) - vertex(p, t[0]));
        EXPECT_GT(n.y, 0.0);
    }
    EXPECT_FLOAT_EQ(p.v[(3 * W + 4) * 5 + 1], h[3 * W + 4]);
}

TEST(MitsubaExport, XmlHasTheSameCameraFilmIntegratorAndMaterial) {
    test::TempDir dir("mitsuba");
    auto scene = makeScene(dir, 4, 4, std::vector<float>(16, 0.0f),
                           R"(, "material": {"type": "roughconductor", "distribution": "beckmann",
                                "alpha_u": 0.05, "alpha_v": 0.2, "material": "Fe"})");
    const MitsubaExport e = exportMitsuba(*scene, EnvMap::constant(50, 25, 0.5f), dir / "out");
    std::ifstream is(e.xml);
    std::stringstream ss;
    ss << is.rdbuf();
    const std::string x = ss.str();
    for (const char* s : {"<scene version=\"3.0.0\">",
                          "<integrator type=\"path\">",
                          "<integer name=\"max_depth\" value=\"3\"/>",
                          "<boolean name=\"hide_emitters\" value=\"true\"/>",
                          "<sensor type=\"perspective\">",
                          "<string name=\"fov_axis\" value=\"x\"/>",
                          "<float name=\"fov\" value=\"28\"/>",
                          "<lookat origin=\"1, 5, 4\" target=\"0, 0, 0.1\" up=\"0, 1, 0\"/>",
                          "<sampler type=\"independent\">",
                          "<integer name=\"sample_count\" value=\"12\"/>",
                          "<film type=\"hdrfilm\">",
                          "<integer name=\"width\" value=\"40\"/>",
                          "<integer name=\"height\" value=\"30\"/>",
                          "<rfilter type=\"box\"/>",
                          "<emitter type=\"envmap\">",
                          "<string name=\"filename\" value=\"envmap.exr\"/>",
                          "<shape type=\"ply\">",
                          "<string name=\"filename\" value=\"heightfield.ply\"/>",
                          "<boolean name=\"face_normals\" value=\"true\"/>",
                          "<bsdf type=\"roughconductor\">",
                          "<string name=\"distribution\" value=\"beckmann\"/>",
                          "<float name=\"alpha_u\" value=\"0.0500000007\"/>",
                          "<float name=\"alpha_v\" value=\"0.200000003\"/>",
                          "<rgb name=\"eta\" value=\"",
                          "<rgb name=\"k\" value=\""})
        EXPECT_TRUE(contains(x, s)) << s;
    EXPECT_FALSE(contains(x, "name=\"material\""));  // never Mitsuba's named spectra
    // eta/k are ours, written as numbers (Fe's k is > 1).
    const ConductorParams& m = scene->bsdf.params();
    char eta[128];
    std::snprintf(eta, sizeof eta, "<rgb name=\"eta\" value=\"%.9g, %.9g, %.9g\"/>",
                  static_cast<double>(m.ior.eta.x), static_cast<double>(m.ior.eta.y),
                  static_cast<double>(m.ior.eta.z));
    EXPECT_TRUE(contains(x, eta)) << eta;
    EXPECT_GT(m.ior.k.x, 1.0f);
    // Orthographic: to_world = lookat · scale(w/2, w/2, 1), the scale written first.
    auto ortho = makeScene(dir, 4, 4, std::vector<float>(16, 0.0f),
                           R"(, "material": {"type": "conductor"})");
    ortho.reset();
    test::writeNpyF32(dir / "h2.npy", 4, 4, std::vector<float>(16, 0.0f));
    auto o = loadScene(parseScene(R"({"heightmap": {"path": "h2.npy", "pixel_pitch": 0.01},
        "material": {"type": "conductor"},
        "camera": {"type": "orthographic", "width_mm": 0.3, "origin": [0, 2, 0.001],
                   "target": [0, 0, 0], "up": [0, 0, -1], "width": 16, "height": 8}})",
                                  dir.path(), "ortho scene"));
    const std::string ox = mitsubaSceneXml(*o, "a.ply", "b.exr");
    EXPECT_TRUE(contains(ox, "<sensor type=\"orthographic\">"));
    const size_t sc = ox.find("<scale x=\"0.15\" y=\"0.15\"/>"), la = ox.find("<lookat ");
    ASSERT_NE(sc, std::string::npos);
    ASSERT_NE(la, std::string::npos);
    EXPECT_LT(sc, la);
    EXPECT_TRUE(contains(ox, "<bsdf type=\"conductor\">"));
    EXPECT_FALSE(contains(ox, "alpha_u"));
    EXPECT_FALSE(contains(ox, "fov"));
}

}  // namespace
}  // namespace sl
