#include "app/pipeline/HeldOut.h"

#include <stdexcept>

#include "app/pipeline/Search.h"
#include "core/Error.h"
#include "core/Registry.h"
#include "objective/TransportLoss.h"

namespace sl {

namespace {

constexpr HeldOutModeRow kModes[] = {
    {HeldOutMode::Judge, "judge",
     "the judge's estimate, traced from the scene with its own seed and cached (default)"},
    {HeldOutMode::File, "FILE.tm", "a transport matrix with two halves that fits the training T"},
    {HeldOutMode::None, "none", "no held-out scores"},
};

}  // namespace

std::span<const HeldOutModeRow> heldOutModeTable() {
    return kModes;
}

HeldOutSource parseHeldOutSource(std::string_view text, const std::string& where) {
    HeldOutSource s;
    if (const HeldOutModeRow* r = findRegistryRow(heldOutModeTable(), text);
        r && r->value != HeldOutMode::File) {
        s.mode = r->value;
        return s;
    }
    const std::filesystem::path p{std::string(text)};
    if (p.extension() != ".tm")
        throw inputError(where, "'" + std::string(text) + "' is not a .tm file",
                         "give judge, none, or a .tm file with two halves");
    s.mode = HeldOutMode::File;
    s.file = p;
    return s;
}

HeldOutScorer::HeldOutScorer(const TransportMatrix& heldOut,
                             const std::vector<uint8_t>& trainingMask,
                             const ObjectiveOptions& options, ObjectiveKind kind, bool rgb,
                             std::vector<uint8_t> defects, std::vector<uint8_t> reference)
    : kind_(kind) {
    if (heldOut.planes != 2)
        throw std::invalid_argument("held-out transport matrix needs two sample sets");
    std::vector<uint8_t> mask = intersectMasks(trainingMask, heldOut.objectMask);
    paper_ = std::make_unique<ImageObjective>(heldOut.width, heldOut.height, mask, options);
    unb_ = std::make_unique<UnbiasedObjective>(heldOut.width, heldOut.height, mask, options);
    paperLoss_ = std::make_unique<TransportLoss>(heldOut, *paper_, rgb);
    unbLoss_ = std::make_unique<TransportLoss>(heldOut, *unb_, rgb);
    if (kind == ObjectiveKind::Defects) {
        SearchInputs in;
        in.mask = mask;
        in.rgb = rgb;
        in.defects = std::move(defects);
        in.reference = std::move(reference);
        defects_ = std::make_unique<ObjectiveOnT>(objectiveOnT(kind, heldOut, in, options));
    }
    // T's own arrays, nothing built: the scorer is asked for a few values (one per heldOutEvery
    // iterations, no gradient), where Auto's rules assume a search's hundreds of evaluations and
    // at its 17th built the held-out T's Gram (the periodic lines at 512²: ~4.5 s of CPU for
    // the two scores after it).
    for (TransportLoss* l :
         {paperLoss_.get(), unbLoss_.get(), defects_ ? defects_->loss.get() : nullptr})
        if (l) l->setLayout(TransportLayout::Csr);
}

const TransportLoss& HeldOutScorer::unbiasedLoss() const {
    return *unbLoss_;
}

HeldOutScorer::~HeldOutScorer() = default;

HeldOutScore HeldOutScorer::score(std::span<const double> E) const {
    HeldOutScore s;
    s.paper = paperLoss_->evaluate(E, {});
    s.unbiased = unbLoss_->evaluate(E, {});
    switch (kind_) {
        case ObjectiveKind::Paper:
            s.own = s.paper;
            break;
        case ObjectiveKind::Unbiased:
            s.own = s.unbiased;
            break;
        case ObjectiveKind::Defects:
            s.own = defects_->loss->evaluate(E, {});
            break;
    }
    return s;
}

}  // namespace sl
