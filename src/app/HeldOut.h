// Held-out scoring (docs/DESIGN.md "Noise is the trap"): every optimization is also scored on
// an independent estimate — for `optimize`, the judge's (app/Judge.h: its own seed, 1024 spp by
// default, two sample sets), so that both the paper's eq. 2 and the noise-unbiased objective
// can be evaluated on it. The held-out objectives use the training mask intersected with the
// held-out T's object mask (the judge's own scores use the part mask).
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "objective/Objective.h"
#include "objective/UnbiasedObjective.h"
#include "transport/TransportMatrix.h"

namespace sl {

class TransportLoss;

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
