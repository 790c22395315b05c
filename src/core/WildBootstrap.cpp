#include "core/WildBootstrap.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "core/Rng.h"

namespace sl {

double robustSpread(std::vector<double> v, int replicates) {
    std::erase_if(v, [](double x) { return !std::isfinite(x); });
    if (v.size() < 2 || 2 * v.size() < static_cast<size_t>(std::max(replicates, 0)))
        return std::numeric_limits<double>::quiet_NaN();
    auto median = [](std::vector<double>& x) {
        std::sort(x.begin(), x.end());
        const size_t m = x.size();
        return m % 2 ? x[m / 2] : 0.5 * (x[m / 2 - 1] + x[m / 2]);
    };
    const double m = median(v);
    for (double& x : v) x = std::abs(x - m);
    return 1.4826 * median(v);
}

std::vector<double> wildBootstrapErrors(std::span<const HalfImages> images, uint64_t seed,
                                        int replicates, const ReplicateScores& scores,
                                        int threads) {
    if (images.empty()) throw std::invalid_argument("wildBootstrapErrors: no image");
    const size_t n = images.front().a.size();
    for (const HalfImages& h : images)
        if (h.a.size() != n || h.b.size() != n)
            throw std::invalid_argument("wildBootstrapErrors: images of different sizes");
    // d_p/√2 per image and pixel.
    std::vector<std::vector<double>> d(images.size(), std::vector<double>(n));
    for (size_t k = 0; k < images.size(); ++k)
        for (size_t p = 0; p < n; ++p) d[k][p] = (images[k].a[p] - images[k].b[p]) * std::sqrt(0.5);
    const int count = std::max(replicates, 0);
    std::vector<std::vector<double>> byReplicate(static_cast<size_t>(count));  // [rep][score]
    // Replicate `rep` into the worker's own images `r`, then its scores. A block of pixels at a
    // time: its Rademacher weights drawn first, pixel by pixel, then each image's block perturbed
    // in a pass the compiler vectorizes (the same values as perturbing pixel by pixel).
    constexpr size_t kBlock = 1024;
    constexpr uint64_t kOne = 0x3ff0000000000000ULL;  // 1.0
    auto one = [&](int rep, std::vector<HalfImages>& r) {
        Pcg32 rng(mix64(seed ^ 0x5345ULL), static_cast<uint64_t>(rep));
        std::array<double, kBlock> wa{}, wb{};
        std::array<uint32_t, kBlock> draws{};
        for (size_t p0 = 0; p0 < n; p0 += kBlock) {
            const size_t m = std::min(kBlock, n - p0);
            // ±1.0 from the bit without a branch (a branch on a random bit is mispredicted half
            // the time): 1.0's bits with the sign bit set where the bit is clear.
            rng.nextU32s(draws.data(), m);
            for (size_t i = 0; i < m; ++i) {
                const uint64_t bits = draws[i];
                wa[i] = std::bit_cast<double>(kOne | (~bits & 1u) << 63);
                wb[i] = std::bit_cast<double>(kOne | (~bits >> 1 & 1u) << 63);
            }
            for (size_t k = 0; k < images.size(); ++k) {
                const double* a = images[k].a.data() + p0;
                const double* b = images[k].b.data() + p0;
                const double* dk = d[k].data() + p0;
                double* ra = r[k].a.data() + p0;
                double* rb = r[k].b.data() + p0;
                for (size_t i = 0; i < m; ++i) ra[i] = a[i] + wa[i] * dk[i];
                for (size_t i = 0; i < m; ++i) rb[i] = b[i] + wb[i] * dk[i];
            }
        }
        byReplicate[static_cast<size_t>(rep)] = scores(r);
    };
    const int workers = std::clamp(
        threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())),
        1, std::max(count, 1));
    std::atomic<int> next{0};
    std::exception_ptr failure;
    std::mutex failureMutex;
    auto work = [&] {
        std::vector<HalfImages> r(images.size(),
                                  HalfImages{std::vector<double>(n), std::vector<double>(n)});
        for (int rep; (rep = next.fetch_add(1)) < count;) {
            try {
                one(rep, r);
            } catch (...) {
                const std::lock_guard<std::mutex> lock(failureMutex);
                if (!failure) failure = std::current_exception();
                next = count;  // the others stop after their replicate
            }
        }
    };
    std::vector<std::thread> pool;
    for (int w = 1; w < workers; ++w) pool.emplace_back(work);
    work();
    for (std::thread& t : pool) t.join();
    if (failure) std::rethrow_exception(failure);
    std::vector<std::vector<double>> values;  // [score][replicate]
    for (const std::vector<double>& s : byReplicate) {
        if (values.empty()) values.resize(s.size());
        if (s.size() != values.size())
            throw std::invalid_argument("wildBootstrapErrors: a replicate gave another count");
        for (size_t j = 0; j < s.size(); ++j) values[j].push_back(s[j]);
    }
    std::vector<double> se;
    se.reserve(values.size());
    for (std::vector<double>& v : values) se.push_back(robustSpread(std::move(v), replicates));
    return se;
}

}  // namespace sl
