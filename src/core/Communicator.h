// Communicator: the collectives a computation split over processes needs (MPI ranks, each
// holding one row shard of T: objective/TransportLoss.h, docs/CLUSTER.md). Only app/host/Mpi.cpp
// knows MPI; everything else sees this interface, and one process alone is a
// SerialCommunicator, whose collectives do nothing.
//
// Every rank must make the same calls in the same order (the optimizers are deterministic, so
// ranks that see the same values take the same path); a rank that stops calling hangs the rest,
// so an error on any rank ends all of them (abort).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <span>
#include <vector>

namespace sl {

class Communicator {
  public:
    virtual ~Communicator() = default;
    virtual int rank() const = 0;
    virtual int size() const = 0;
    bool root() const { return rank() == 0; }
    bool distributed() const { return size() > 1; }

    /// values ← their element-wise sum over the ranks, the same bits on every rank (summed in
    /// one place, then sent to all), so ranks that go on from it stay in step.
    virtual void sum(std::span<double> values) const = 0;
    /// values ← their element-wise sum over the ranks, where every element is non-zero on at
    /// most one rank (an image whose rows the ranks split): x + 0 is exact, so the result is
    /// the same on every rank in any order of summation, at the cost of one all-reduce.
    virtual void combine(std::span<double> values) const = 0;
    /// values ← every rank's block: this rank's [begin, end) goes to every rank. The ranks'
    /// blocks must not overlap; elements outside every block keep their value. Half the
    /// traffic of combine for an image whose rows the ranks split.
    virtual void gather(std::span<double> values, size_t begin, size_t end) const = 0;
    /// Ends every rank with exit code `code` (an error on one rank must not leave the others
    /// waiting in a collective).
    [[noreturn]] virtual void abort(int code) const = 0;
    /// Wall-clock seconds this rank has spent inside sum and combine (the transfers and the
    /// waiting for slower ranks).
    virtual double secondsInCollectives() const { return 0; }
};

/// One process alone: rank 0 of 1; the collectives leave the values as they are.
class SerialCommunicator final : public Communicator {
  public:
    int rank() const override { return 0; }
    int size() const override { return 1; }
    void sum(std::span<double>) const override {}
    void combine(std::span<double>) const override {}
    void gather(std::span<double>, size_t, size_t) const override {}
    [[noreturn]] void abort(int code) const override { std::exit(code); }
};

/// The image rows [rowBegin, rowEnd) this rank holds among ranks that split T by rows (its
/// shard, io/TransportFile.h SHARDS): a product of its shard fills only them, and gatherImage
/// puts every rank's rows together. `ranks` null: one process, which holds every row.
struct RowShard {
    const Communicator* ranks = nullptr;
    size_t rowBegin = 0, rowEnd = 0;
    bool distributed() const { return ranks && ranks->distributed(); }
    /// image: rows of `width` pixels of `perPixel` values each.
    void gatherImage(std::span<double> image, size_t width, size_t perPixel = 1) const {
        if (distributed())
            ranks->gather(image, rowBegin * width * perPixel, rowEnd * width * perPixel);
    }
};

/// Every rank's `mine` (the same count on every rank), side by side in rank order, on every
/// rank. Values travel as doubles: integers up to 2^53 are exact.
inline std::vector<double> allGather(const Communicator& c, std::span<const double> mine) {
    std::vector<double> all(mine.size() * static_cast<size_t>(c.size()), 0.0);
    std::copy(
        mine.begin(), mine.end(),
        all.begin() + static_cast<std::ptrdiff_t>(mine.size() * static_cast<size_t>(c.rank())));
    c.combine(all);
    return all;
}

}  // namespace sl
