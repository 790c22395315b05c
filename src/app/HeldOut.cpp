#include "app/HeldOut.h"

#include <stdexcept>

#include "objective/TransportLoss.h"

namespace sl {

HeldOutScorer::HeldOutScorer(const TransportMatrix& heldOut,
                             const std::vector<uint8_t>& trainingMask,
                             const ObjectiveOptions& options, bool unbiased)
    : t_(heldOut), unbiased_(unbiased) {
    if (heldOut.planes != 2)
        throw std::invalid_argument("held-out transport matrix needs two sample sets");
    std::vector<uint8_t> mask = intersectMasks(trainingMask, heldOut.objectMask);
    paper_ = std::make_unique<ImageObjective>(heldOut.width, heldOut.height, mask, options);
    unb_ = std::make_unique<UnbiasedObjective>(heldOut.width, heldOut.height, mask, options);
}

HeldOutScore HeldOutScorer::score(std::span<const double> E) const {
    const bool rgb = E.size() == 3 * t_.cols();
    HeldOutScore s;
    s.paper = TransportLoss(t_, *paper_, rgb).evaluate(E, {});
    LossParts unb = TransportLoss(t_, *unb_, rgb).evaluate(E, {});
    s.own = unbiased_ ? unb : s.paper;
    return s;
}

}  // namespace sl
