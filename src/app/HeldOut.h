// Held-out scoring (DESIGN.md "Noise is the trap"): every optimization is also scored on an
// independent estimate — a second transport matrix from disjoint samples (another seed), traced
// with two sample sets so that both the paper's eq. 2 and the noise-unbiased objective can be
// evaluated on it.
//
// CONVENTION: the held-out seed is the training seed + kHeldOutSeedOffset; its spp defaults to
// the training spp. The held-out objectives use the training mask intersected with the
// held-out T's object mask.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "objective/Objective.h"
#include "objective/UnbiasedObjective.h"
#include "transport/TransportMatrix.h"

namespace sl {

class TransportLoss;

inline constexpr uint64_t kHeldOutSeedOffset = 0x9E3779B97F4A7C15ULL;

struct HeldOutScore {
    LossParts own;    // the objective that was optimized
    LossParts paper;  // the paper's eq. 2 (the common yardstick), on T = (T_a + T_b)/2
};

class HeldOutScorer {
  public:
    /// heldOut must have two planes. unbiased: the optimized objective is the unbiased one.
    /// rgb: E has 3 values per texel.
    HeldOutScorer(const TransportMatrix& heldOut, const std::vector<uint8_t>& trainingMask,
                  const ObjectiveOptions& options, bool unbiased, bool rgb);
    ~HeldOutScorer();
    HeldOutScore score(std::span<const double> E) const;

  private:
    bool unbiased_;
    std::unique_ptr<ImageObjective> paper_;
    std::unique_ptr<UnbiasedObjective> unb_;
    std::unique_ptr<TransportLoss> paperLoss_, unbLoss_;  // built once, reused by score()
};

}  // namespace sl
