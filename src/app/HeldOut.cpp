#include "app/HeldOut.h"

#include <stdexcept>

#include "objective/TransportLoss.h"

namespace sl {

HeldOutScorer::HeldOutScorer(const TransportMatrix& heldOut,
                             const std::vector<uint8_t>& trainingMask,
                             const ObjectiveOptions& options, bool unbiased, bool rgb)
    : unbiased_(unbiased) {
    if (heldOut.planes != 2)
        throw std::invalid_argument("held-out transport matrix needs two sample sets");
    std::vector<uint8_t> mask = intersectMasks(trainingMask, heldOut.objectMask);
    paper_ = std::make_unique<ImageObjective>(heldOut.width, heldOut.height, mask, options);
    unb_ = std::make_unique<UnbiasedObjective>(heldOut.width, heldOut.height, mask, options);
    paperLoss_ = std::make_unique<TransportLoss>(heldOut, *paper_, rgb);
    unbLoss_ = std::make_unique<TransportLoss>(heldOut, *unb_, rgb);
}

HeldOutScorer::~HeldOutScorer() = default;

HeldOutScore HeldOutScorer::score(std::span<const double> E) const {
    HeldOutScore s;
    s.paper = paperLoss_->evaluate(E, {});
    LossParts unb = unbLoss_->evaluate(E, {});
    s.own = unbiased_ ? unb : s.paper;
    return s;
}

}  // namespace sl
