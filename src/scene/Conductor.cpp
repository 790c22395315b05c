// Conductor BSDFs, see Conductor.h for the conventions and the Mitsuba 3 files they follow.
#include "scene/Conductor.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/Error.h"

namespace sl {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvSqrtPi = 0.56418958354775628695f;
// Mitsuba's guard in Frame3f::sincos_phi(): 4 * dr::Epsilon<float> (= 4 * 2^-24).
constexpr float kSinTheta2Eps = 4.0f * 0x1p-24f;

inline float sqr(float x) {
    return x * x;
}
inline float safeSqrt(float x) {
    return std::sqrt(std::max(x, 0.0f));
}
inline bool isFinite(const Vec3f& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Inverse error function, single precision: M. Giles, "Approximating the erfinv function",
/// GPU Computing Gems Jade Edition (2011) -- the approximation Dr.Jit's erfinv() uses.
float erfinv(float x) {
    float w = -std::log((1.0f - x) * (1.0f + x));
    float p;
    if (w < 5.0f) {
        w = w - 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w;
        p = -3.5233877e-06f + p * w;
        p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w;
        p = -0.00125372503f + p * w;
        p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w;
        p = 1.50140941f + p * w;
    } else {
        w = std::sqrt(w) - 3.0f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w;
        p = 0.00134934322f + p * w;
        p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w;
        p = -0.0076224613f + p * w;
        p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w;
        p = 2.83297682f + p * w;
    }
    return p * x;
}

/// Shirley-Chiu concentric map of [0,1)^2 onto the unit disk (Mitsuba's
/// warp::square_to_uniform_disk_concentric).
inline void squareToDiskConcentric(float u1, float u2, float& px, float& py) {
    const float x = 2.0f * u1 - 1.0f, y = 2.0f * u2 - 1.0f;
    if (x == 0.0f && y == 0.0f) {
        px = py = 0.0f;
        return;
    }
    float r, phi;
    if (std::abs(x) < std::abs(y)) {
        r = y;
        phi = 0.5f * kPi - 0.25f * kPi * (x / y);
    } else {
        r = x;
        phi = 0.25f * kPi * (y / x);
    }
    px = r * std::cos(phi);
    py = r * std::sin(phi);
}

void checkFiniteNonNegative(const Rgb& v, const char* field, const char* fix) {
    for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(v[c]) || v[c] < 0.0f) {
            std::ostringstream os;
            os << "must be finite and >= 0 in every channel, got (" << v.x << ", " << v.y << ", "
               << v.z << ")";
            throw inputError(std::string("material.") + field, os.str(), fix);
        }
    }
}

void checkAlpha(float a, const char* field) {
    if (!std::isfinite(a) || !(a > 0.0f)) {
        std::ostringstream os;
        os << "must be a finite roughness > 0, got " << a;
        throw inputError(std::string("material.") + field, os.str(),
                         "use e.g. 0.05 (values below 1e-4 act as 1e-4, as in Mitsuba); for a "
                         "perfect mirror use type \"conductor\"");
    }
}

const ConductorParams& validated(const ConductorParams& p) {
    if (!p.smooth) {
        checkAlpha(p.alphaU, "alpha_u");
        checkAlpha(p.alphaV, "alpha_v");
    }
    checkFiniteNonNegative(p.ior.eta, "eta", "give the real part of the complex IOR, e.g. 1.66");
    checkFiniteNonNegative(p.ior.k, "k", "give the extinction coefficient, e.g. 9.22");
    for (int c = 0; c < 3; ++c) {
        if (p.ior.eta[c] == 0.0f && p.ior.k[c] == 0.0f)
            throw inputError(
                "material.eta/k",
                "eta and k are both 0 in channel " + std::to_string(c) + " (no such material)",
                "for a perfect mirror use eta 0 and k 1 (material \"none\")");
    }
    checkFiniteNonNegative(p.specularReflectance, "specular_reflectance",
                           "use 1 (the physically meaningful value) or a factor in [0, 1]");
    if (p.distribution != Microfacet::GGX && p.distribution != Microfacet::Beckmann)
        throw inputError("material.distribution", "unknown microfacet distribution",
                         "use \"ggx\" or \"beckmann\"");
    return p;
}

/// Alpha for the distribution object: the smooth conductor never uses it, so it may be anything.
float usableAlpha(const ConductorParams& p, float a) {
    return p.smooth && !(std::isfinite(a) && a > 0.0f) ? 0.1f : a;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Fresnel
// ---------------------------------------------------------------------------------------------

float fresnelConductor(float cosThetaI, float eta, float k) {
    // Mitsuba 3 fresnel_conductor() (include/mitsuba/render/fresnel.h), modified from
    // K. D. Moeller, "Optics", University Science Books, 1988.
    const float cos2 = cosThetaI * cosThetaI, sin2 = 1.0f - cos2, sin4 = sin2 * sin2;
    const float temp1 = eta * eta - k * k - sin2;
    const float a2pb2 = safeSqrt(temp1 * temp1 + 4.0f * k * k * eta * eta);
    const float a = safeSqrt(0.5f * (a2pb2 + temp1));
    const float term1 = a2pb2 + cos2, term2 = 2.0f * cosThetaI * a;
    // The denominators vanish only at exact grazing incidence on an index-matched channel
    // (eta 1, k 0), or at normal incidence for eta = k = 0 (rejected by ConductorBsdf); the
    // grazing limit of the reflectance is 1.
    const float rs = term1 + term2 > 0.0f ? (term1 - term2) / (term1 + term2) : 1.0f;
    const float term3 = a2pb2 * cos2 + sin4, term4 = term2 * sin2;
    const float rp = term3 + term4 > 0.0f ? rs * (term3 - term4) / (term3 + term4) : rs;
    return 0.5f * (rs + rp);
}

Rgb fresnelConductor(float cosThetaI, const Rgb& eta, const Rgb& k) {
    return {fresnelConductor(cosThetaI, eta.x, k.x), fresnelConductor(cosThetaI, eta.y, k.y),
            fresnelConductor(cosThetaI, eta.z, k.z)};
}

const char* microfacetName(Microfacet type) {
    return type == Microfacet::Beckmann ? "beckmann" : "ggx";
}

// ---------------------------------------------------------------------------------------------
// MicrofacetDistribution (Mitsuba 3 include/mitsuba/render/microfacet.h, sample_visible = true)
// ---------------------------------------------------------------------------------------------

MicrofacetDistribution::MicrofacetDistribution(Microfacet type, float alphaU, float alphaV)
    : type_(type), alphaU_(std::max(alphaU, kMinAlpha)), alphaV_(std::max(alphaV, kMinAlpha)) {}

float MicrofacetDistribution::D(const Vec3f& m) const {
    const float cosTheta = m.z, cosTheta2 = cosTheta * cosTheta;
    float result;
    if (type_ == Microfacet::Beckmann) {
        result = std::exp(-(sqr(m.x / alphaU_) + sqr(m.y / alphaV_)) / cosTheta2) /
                 (kPi * alphaU_ * alphaV_ * sqr(cosTheta2));
    } else {
        result = 1.0f / (kPi * alphaU_ * alphaV_ *
                         sqr(sqr(m.x / alphaU_) + sqr(m.y / alphaV_) + sqr(m.z)));
    }
    // Mitsuba's guard against numerical issues in later stages (also maps NaN to 0).
    return result * cosTheta > 1e-20f ? result : 0.0f;
}

float MicrofacetDistribution::smithG1(const Vec3f& v, const Vec3f& m) const {
    const float xyAlpha2 = sqr(alphaU_ * v.x) + sqr(alphaV_ * v.y);
    const float tanThetaAlpha2 = xyAlpha2 / sqr(v.z);
    float result;
    if (type_ == Microfacet::Beckmann) {
        // Mitsuba's rational approximation of the Beckmann Smith G1 (< 0.35 % relative error).
        const float a = 1.0f / std::sqrt(tanThetaAlpha2), aSqr = a * a;
        result =
            a >= 1.6f ? 1.0f : (3.535f * a + 2.181f * aSqr) / (1.0f + 2.276f * a + 2.577f * aSqr);
    } else {
        result = 2.0f / (1.0f + std::sqrt(1.0f + tanThetaAlpha2));
    }
    if (xyAlpha2 == 0.0f) result = 1.0f;         // perpendicular incidence
    if (dot(v, m) * v.z <= 0.0f) result = 0.0f;  // back of the microfacet
    return result;
}

MicrofacetDistribution::Slope MicrofacetDistribution::sampleVisible11(float cosThetaI, float u1,
                                                                      float u2) const {
    if (type_ == Microfacet::Beckmann) {
        // W. Jakob, "An Improved Visible Normal Sampling Routine for the Beckmann Distribution":
        // numerical inversion of the CDF in the erf() domain, as Mitsuba does it.
        const float tanThetaI = safeSqrt(1.0f - cosThetaI * cosThetaI) / cosThetaI;
        const float cotThetaI = 1.0f / tanThetaI;
        const float maxval = std::erf(cotThetaI);
        u1 = std::clamp(u1, 1e-6f, 1.0f - 1e-6f);
        u2 = std::clamp(u2, 1e-6f, 1.0f - 1e-6f);
        // Initial guess: the analytic solution for theta_i = pi/2.
        float x = maxval - (maxval + 1.0f) * std::erf(std::sqrt(-std::log(u1)));
        // Normalisation of the CDF. At normal incidence tanThetaI = 0 and exp(-inf) = 0.
        u1 *= 1.0f + maxval + kInvSqrtPi * tanThetaI * std::exp(-sqr(cotThetaI));
        for (int i = 0; i < 3; ++i) {  // three Newton steps
            const float slope = erfinv(x);
            const float value = 1.0f + x + kInvSqrtPi * tanThetaI * std::exp(-sqr(slope)) - u1;
            const float derivative = tanThetaI == 0.0f ? 1.0f : 1.0f - slope * tanThetaI;
            x -= value / derivative;
        }
        return {erfinv(x), erfinv(2.0f * u2 - 1.0f)};
    }
    // GGX: E. Heitz, "A Simpler and Exact Sampling Routine for the GGX Distribution of Visible
    // Normals" (2017), in Mitsuba's form: a disk sample warped onto the projected hemisphere.
    float px, py;
    squareToDiskConcentric(u1, u2, px, py);
    const float s = 0.5f * (1.0f + cosThetaI);
    py = (1.0f - s) * safeSqrt(1.0f - px * px) + s * py;
    const float x = px, y = py, z = safeSqrt(1.0f - x * x - y * y);
    const float sinThetaI = safeSqrt(1.0f - cosThetaI * cosThetaI);
    const float norm = 1.0f / (sinThetaI * y + cosThetaI * z);
    return {(cosThetaI * y - sinThetaI * z) * norm, x * norm};
}

Vec3f MicrofacetDistribution::sampleVisible(const Vec3f& wi, float u1, float u2) const {
    // Step 1: stretch wi to the alpha = 1 configuration.
    const Vec3f wiP = normalize(Vec3f(alphaU_ * wi.x, alphaV_ * wi.y, wi.z));
    // Azimuth of the stretched direction (Mitsuba's Frame3f::sincos_phi).
    float sinPhi = 0.0f, cosPhi = 1.0f;
    const float sinTheta2 = wiP.x * wiP.x + wiP.y * wiP.y;
    if (!(sinTheta2 <= kSinTheta2Eps)) {
        const float inv = 1.0f / std::sqrt(sinTheta2);
        cosPhi = std::clamp(wiP.x * inv, -1.0f, 1.0f);
        sinPhi = std::clamp(wiP.y * inv, -1.0f, 1.0f);
    }
    // Step 2: sample the slopes of the visible normals for alpha = 1.
    const Slope s11 = sampleVisible11(wiP.z, u1, u2);
    // Step 3: rotate back to the azimuth of wi and unstretch.
    const float sx = (cosPhi * s11.x - sinPhi * s11.y) * alphaU_;
    const float sy = (sinPhi * s11.x + cosPhi * s11.y) * alphaV_;
    // Step 4: slope -> normal.
    return normalize(Vec3f(-sx, -sy, 1.0f));
}

float MicrofacetDistribution::pdfVisible(const Vec3f& wi, const Vec3f& m) const {
    return D(m) * smithG1(wi, m) * std::abs(dot(wi, m)) / wi.z;
}

// ---------------------------------------------------------------------------------------------
// ConductorBsdf
// ---------------------------------------------------------------------------------------------

ConductorBsdf::ConductorBsdf(const ConductorParams& p)
    : params_(validated(p)),
      distr_(p.distribution, usableAlpha(p, p.alphaU), usableAlpha(p, p.alphaV)) {
    perfectMirrorIor_ = p.ior.eta == Rgb(0.0f) && p.ior.k == Rgb(1.0f);
}

Rgb ConductorBsdf::fresnel(float cosThetaI) const {
    // For eta = 0, k = 1 fresnelConductor() is exactly 1; skip the arithmetic.
    if (perfectMirrorIor_) return params_.specularReflectance;
    return fresnelConductor(cosThetaI, params_.ior.eta, params_.ior.k) *
           params_.specularReflectance;
}

BsdfSample ConductorBsdf::sample(const Vec3f& wi, [[maybe_unused]] float u1, float u2a,
                                 float u2b) const {
    BsdfSample bs;
    if (!(wi.z > 0.0f)) return bs;

    if (params_.smooth) {  // Mitsuba `conductor`: Dirac reflection about the normal
        bs.wo = Vec3f(-wi.x, -wi.y, wi.z);
        bs.weight = fresnel(wi.z);
        bs.pdf = 1.0f;
        bs.delta = true;
        bs.valid = true;
        return bs;
    }

    // Mitsuba `roughconductor` with sample_visible = true.
    const Vec3f m = distr_.sampleVisible(wi, u2a, u2b);
    const float wiDotM = dot(wi, m);
    const float pdfM = distr_.D(m) * distr_.smithG1(wi, m) * std::abs(wiDotM) / wi.z;
    const Vec3f wo = m * (2.0f * wiDotM) - wi;  // reflect wi about m
    // pdfM > 0 also rejects the (rare, measure-zero) NaN results of the slope inversion.
    if (!(pdfM > 0.0f) || !(wo.z > 0.0f) || !isFinite(wo)) return bs;

    const float woDotM = dot(wo, m);
    bs.wo = wo;
    bs.weight = fresnel(wiDotM) * distr_.smithG1(wo, m);
    bs.pdf = pdfM / (4.0f * woDotM);  // Jacobian of the half-vector mapping
    bs.valid = true;
    return bs;
}

Rgb ConductorBsdf::eval(const Vec3f& wi, const Vec3f& wo) const {
    if (params_.smooth) return Rgb(0.0f);
    const float cosI = wi.z, cosO = wo.z;
    if (!(cosI > 0.0f && cosO > 0.0f)) return Rgb(0.0f);
    const Vec3f h = normalize(wo + wi);
    const float d = distr_.D(h);
    if (d == 0.0f) return Rgb(0.0f);
    const float g = distr_.G(wi, wo, h);
    return fresnel(dot(wi, h)) * (d * g / (4.0f * cosI));
}

float ConductorBsdf::pdf(const Vec3f& wi, const Vec3f& wo) const {
    if (params_.smooth) return 0.0f;
    const float cosI = wi.z, cosO = wo.z;
    if (!(cosI > 0.0f && cosO > 0.0f)) return 0.0f;
    const Vec3f m = normalize(wo + wi);
    // The side tests smithG1() applies in eval()/sample(), replicated as Mitsuba does.
    if (!(dot(wi, m) > 0.0f && dot(wo, m) > 0.0f)) return 0.0f;
    return distr_.D(m) * distr_.smithG1(wi, m) / (4.0f * cosI);
}

std::string describe(const ConductorParams& p) {
    std::ostringstream os;
    if (p.smooth) {
        os << "conductor";
    } else {
        os << "roughconductor " << microfacetName(p.distribution) << " alpha_u=" << p.alphaU
           << " alpha_v=" << p.alphaV;
    }
    os << " eta=(" << p.ior.eta.x << ", " << p.ior.eta.y << ", " << p.ior.eta.z << ") k=("
       << p.ior.k.x << ", " << p.ior.k.y << ", " << p.ior.k.z << ")";
    if (!(p.specularReflectance == Rgb(1.0f)))
        os << " specular_reflectance=(" << p.specularReflectance.x << ", "
           << p.specularReflectance.y << ", " << p.specularReflectance.z << ")";
    return os.str();
}

}  // namespace sl
