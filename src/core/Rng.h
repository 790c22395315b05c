// Random numbers. CONVENTION (seeding): every pixel sample draws from its own PCG32
// stream, seeded by (seed, pixel index, sample index) — never by thread — so renders
// are bit-identical for any thread count.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sl {

/// PCG32 (O'Neill, pcg-random.org; the generator Mitsuba 3 uses), XSH-RR output.
class Pcg32 {
  public:
    Pcg32(uint64_t initState, uint64_t initSeq) { seed(initState, initSeq); }

    void seed(uint64_t initState, uint64_t initSeq) {
        state_ = 0;
        inc_ = (initSeq << 1u) | 1u;
        nextU32();
        state_ += initState;
        nextU32();
    }
    uint32_t nextU32() {
        uint64_t old = state_;
        state_ = old * kMultiplier + inc_;
        return output(old);
    }
    /// The next `n` draws into `out`: the same values as `n` calls of nextU32, four states in
    /// flight (the stream jumped four steps at a time: s + 4 = a⁴·s + (a³ + a² + a + 1)·inc), so
    /// the multiplications do not wait on each other.
    void nextU32s(uint32_t* out, size_t n) {
        constexpr uint64_t a = kMultiplier, a2 = a * a, a4 = a2 * a2;
        const uint64_t c = inc_, c2 = a * c + c, c4 = a2 * c2 + c2;
        uint64_t s0 = state_, s1 = s0 * a + c, s2 = s1 * a + c, s3 = s2 * a + c;
        size_t i = 0;
        for (; i + 4 <= n; i += 4) {
            out[i] = output(s0);
            out[i + 1] = output(s1);
            out[i + 2] = output(s2);
            out[i + 3] = output(s3);
            s0 = s0 * a4 + c4;
            s1 = s1 * a4 + c4;
            s2 = s2 * a4 + c4;
            s3 = s3 * a4 + c4;
        }
        state_ = s0;
        for (; i < n; ++i) out[i] = nextU32();
    }
    /// Uniform float in [0, 1): 24 random mantissa bits, never returns 1.
    float nextFloat() { return static_cast<float>(nextU32() >> 8) * 0x1p-24f; }
    double nextDouble() {
        uint64_t hi = nextU32() >> 5, lo = nextU32() >> 6;  // 53 bits
        return static_cast<double>((hi << 26) | lo) * 0x1p-53;
    }

  private:
    static constexpr uint64_t kMultiplier = 6364136223846793005ULL;
    static uint32_t output(uint64_t old) {
        auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        auto rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
    }
    uint64_t state_ = 0, inc_ = 0;
};

/// SplitMix64 finaliser: decorrelates structured keys before they seed PCG32.
constexpr uint64_t mix64(uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// The one place that turns (seed, pixel, sample) into a stream (see CONVENTION above).
inline Pcg32 sampleRng(uint64_t seed, uint64_t pixel, uint64_t sample) {
    return Pcg32(mix64(seed ^ mix64(pixel)), mix64(sample + 0x632be59bd9b4e019ULL * (seed + 1)));
}

}  // namespace sl
