// Conductor BSDFs, Mitsuba-3-compatible: `conductor` (smooth, Dirac mirror) and
// `roughconductor` (GGX / Beckmann microfacets, isotropic or anisotropic alpha, visible-normal
// sampling), with the exact unpolarized conductor Fresnel term per linear-RGB channel.
//
// Reference (read, not copied): Mitsuba 3 src/bsdfs/conductor.cpp, src/bsdfs/roughconductor.cpp,
// include/mitsuba/render/microfacet.h and include/mitsuba/render/fresnel.h
// (github.com/mitsuba-renderer/mitsuba3). A scene we export is re-rendered by Mitsuba 3, so every
// formula below follows that code, including its quirks:
//   * roughconductor always uses sample_visible = true (Mitsuba's default): microfacet normals are
//     drawn from the distribution of visible normals D_wi(m) = G1(wi,m) max(0, wi.m) D(m) / wi.z
//     (Heitz & d'Eon 2014; GGX via Heitz 2017 "A Simpler and Exact Sampling Routine for the GGX
//     Distribution of Visible Normals"; Beckmann via Jakob's numerical inversion, 3 Newton steps).
//   * sample weight = F(wi.m) * G1(wo,m) * specular_reflectance  (= eval / pdf),
//     eval = F(wi.h) D(h) G1(wi,h) G1(wo,h) / (4 cos_i) (BSDF times cos_o; separable Smith G),
//     pdf  = D(h) G1(wi,h) / (4 cos_i).
//   * Beckmann G1 is Mitsuba's rational approximation (< 0.35 % error), GGX G1 is exact.
//   * alpha is clamped to >= 1e-4 (Mitsuba's MicrofacetDistribution::configure()).
//   * D(m) is forced to 0 where D(m) cos(theta_m) <= 1e-20 (Mitsuba's guard).
//
// CONVENTION (shading frame): directions are in the local frame of sl::Frame (s, t, n) with local
// z = n. alpha_u acts along local x (s), alpha_v along local y (t), as in Mitsuba. wi points toward
// the viewer (Mitsuba's si.wi), wo toward the light / next vertex. The surface is one-sided:
// wi.z <= 0 or wo.z <= 0 gives no scattering (Mitsuba's conductors are one-sided too).
//
// ConductorParams, Mitsuba plugin parameter by parameter:
//   smooth               true: `conductor`; false: `roughconductor`
//   distribution         roughconductor `distribution` ("ggx" | "beckmann"). NOTE: Mitsuba's
//                        default is beckmann; ours is GGX, so an exporter must always write it.
//   alphaU, alphaV       `alpha_u`, `alpha_v` (or `alpha` when equal). NOTE: ours default to
//                        kDefaultAlpha = 0.05 (the scene file's default), Mitsuba's to 0.1, so
//                        an exporter must always write them.
//   ior                  `eta`, `k` (RGB, relative to the outside medium); default eta 0, k 1 =
//                        Mitsuba's material "none", a perfect mirror (F == 1 exactly)
//   specularReflectance  `specular_reflectance`, default 1
#pragma once

#include <string>

#include "core/Vec3.h"

namespace sl {

/// Complex index of refraction eta + i k, per linear-RGB channel (Mitsuba's eta and k textures).
struct ComplexIor {
    Rgb eta{0.f}, k{1.f};
};

/// Exact unpolarized Fresnel reflectance of a conductor (complex IOR eta + i k) for light arriving
/// at cos(theta_i) = cosThetaI >= 0; as Mitsuba's fresnel_conductor() (after K. D. Moeller,
/// "Optics", 1988). eta = 0, k = 1 gives exactly 1 at every angle; k = 0 gives the dielectric term.
float fresnelConductor(float cosThetaI, float eta, float k);
/// Per-channel version.
Rgb fresnelConductor(float cosThetaI, const Rgb& eta, const Rgb& k);

enum class Microfacet { GGX, Beckmann };

/// "ggx" / "beckmann", the spelling of Mitsuba's `distribution` parameter.
const char* microfacetName(Microfacet type);

/// Anisotropic microfacet normal distribution with Smith shadowing and visible-normal sampling,
/// as Mitsuba 3's MicrofacetDistribution with sample_visible = true. All vectors in the local
/// shading frame (z = macro-surface normal).
class MicrofacetDistribution {
  public:
    static constexpr float kMinAlpha = 1e-4f;  // Mitsuba clamps alpha_u/alpha_v to this

    MicrofacetDistribution(Microfacet type, float alphaU, float alphaV);

    Microfacet type() const { return type_; }
    float alphaU() const { return alphaU_; }
    float alphaV() const { return alphaV_; }

    /// D(m): normal distribution, normalised so that integral D(m) cos(theta_m) dm = 1.
    float D(const Vec3f& m) const;
    /// Smith's masking function G1(v, m) for one direction (0 if v sees the back of m).
    float smithG1(const Vec3f& v, const Vec3f& m) const;
    /// Separable Smith shadowing-masking G1(wi, m) G1(wo, m).
    float G(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const {
        return smithG1(wi, m) * smithG1(wo, m);
    }
    /// Draws a visible microfacet normal for wi (wi.z > 0) from two uniform numbers in [0, 1).
    Vec3f sampleVisible(const Vec3f& wi, float u1, float u2) const;
    /// Density of sampleVisible() w.r.t. solid angle of m: D(m) G1(wi,m) |wi.m| / wi.z.
    float pdfVisible(const Vec3f& wi, const Vec3f& m) const;

  private:
    struct Slope {
        float x, y;
    };
    Slope sampleVisible11(float cosThetaI, float u1, float u2) const;

    Microfacet type_;
    float alphaU_, alphaV_;
};

/// Default roughness α (both directions): the scene file's `material.alpha` default.
inline constexpr float kDefaultAlpha = 0.05f;

struct ConductorParams {
    bool smooth = false;  // true: Mitsuba `conductor` (Dirac mirror)
    Microfacet distribution = Microfacet::GGX;
    float alphaU = kDefaultAlpha, alphaV = kDefaultAlpha;  // along local x (s) and local y (t)
    ComplexIor ior;                // default = "none": eta 0, k 1 -> perfect mirror (F == 1)
    Rgb specularReflectance{1.f};  // Mitsuba's specular_reflectance multiplier, default 1
};

/// One BSDF sample. weight = f * cos(theta_o) / pdf, as Mitsuba's BSDF::sample() returns it.
struct BsdfSample {
    Vec3f wo;
    Rgb weight{0.f};
    bool valid = false;
    float pdf = 0.f;  // solid-angle density of wo; 1 for the smooth mirror (Mitsuba's convention)
    bool delta = false;  // true for the smooth conductor (Dirac lobe: eval and pdf are 0)
};

class ConductorBsdf {
  public:
    /// Validates the parameters and throws InputError (naming the field and the fix) if they are
    /// unusable: alpha must be finite and > 0 (values below 1e-4 act as 1e-4, as in Mitsuba; use
    /// the smooth conductor for a perfect mirror), eta and k finite and >= 0 and not both 0,
    /// specular reflectance finite and >= 0.
    explicit ConductorBsdf(const ConductorParams& p);

    /// Samples wo for wi (unit, local frame, toward the viewer). u1 is unused (Mitsuba's sample1);
    /// (u2a, u2b) is the 2D sample, each uniform in [0, 1). Returns an invalid sample when
    /// wi.z <= 0 or the sampled wo.z <= 0.
    BsdfSample sample(const Vec3f& wi, float u1, float u2a, float u2b) const;
    /// f(wi, wo) * cos(theta_o); 0 for the smooth conductor and outside the upper hemisphere.
    Rgb eval(const Vec3f& wi, const Vec3f& wo) const;
    /// Solid-angle density with which sample() produces wo; 0 for the smooth conductor.
    float pdf(const Vec3f& wi, const Vec3f& wo) const;

    const ConductorParams& params() const { return params_; }
    const MicrofacetDistribution& distribution() const { return distr_; }

  private:
    Rgb fresnel(float cosThetaI) const;

    ConductorParams params_;
    MicrofacetDistribution distr_;
    bool perfectMirrorIor_ = false;  // eta == 0 and k == 1 in every channel: F == 1 exactly
};

/// Human-readable one-line summary, e.g. "roughconductor ggx alpha_u=0.1 alpha_v=0.1 ...".
std::string describe(const ConductorParams& p);

}  // namespace sl
