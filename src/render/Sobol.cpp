// Sobol' points: see Sobol.h for the direction numbers and the recurrence.
#include "render/Sobol.h"

#include <array>
#include <cstddef>

namespace sl {

namespace {

/// Sobol' generator matrices of dimensions 0..5: dimension 0 is van der Corput's, 1..5 use the
/// direction numbers of S. Joe and F. Kuo (new-joe-kuo-6.21201: degree s, coefficients a,
/// initial m_1..m_s), expanded with Bratley and Fox's recurrence.
struct SobolMatrices {
    std::array<std::array<uint32_t, 32>, 6> v{};
};

const SobolMatrices& sobolMatrices() {
    static const SobolMatrices matrices = [] {
        SobolMatrices r;
        for (int i = 0; i < 32; ++i) r.v[0][i] = 1u << (31 - i);
        struct Poly {
            int s;
            uint32_t a;
            std::array<uint32_t, 4> m;
        };
        const std::array<Poly, 5> polys{{{1, 0, {1, 0, 0, 0}},
                                         {2, 1, {1, 3, 0, 0}},
                                         {3, 1, {1, 3, 1, 0}},
                                         {3, 2, {1, 1, 1, 0}},
                                         {4, 1, {1, 1, 3, 3}}}};
        for (int d = 1; d < 6; ++d) {
            const Poly& p = polys[static_cast<size_t>(d - 1)];
            auto& v = r.v[static_cast<size_t>(d)];
            for (int i = 0; i < p.s; ++i) v[i] = p.m[i] << (31 - i);
            for (int i = p.s; i < 32; ++i) {
                v[i] = v[i - p.s] ^ (v[i - p.s] >> p.s);
                for (int k = 1; k < p.s; ++k)
                    if ((p.a >> (p.s - 1 - k)) & 1u) v[i] ^= v[i - k];
            }
        }
        return r;
    }();
    return matrices;
}

}  // namespace

uint32_t sobol(uint32_t index, int dim) {
    const auto& v = sobolMatrices().v[static_cast<size_t>(dim)];
    uint32_t x = 0;
    for (size_t i = 0; index; ++i, index >>= 1)
        if (index & 1u) x ^= v[i];
    return x;
}

}  // namespace sl
