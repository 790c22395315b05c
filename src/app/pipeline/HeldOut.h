// Held-out scoring (docs/DESIGN.md "Noise is the trap"): every optimization is also scored on
// an independent estimate — for `optimize`, the judge's (app/pipeline/Judge.h: its own seed, its
// first round's spp, two sample sets), so that both the paper's eq. 2 and the noise-unbiased
// objective can be evaluated on it. The held-out objectives use the training mask intersected with
// the held-out T's object mask (the judge's own scores use the part mask). The held-out figure of a
// run is the objective it optimized (`own`: eq. 2, U, or the defects loss on the same regions),
// so the training and held-out curves are one quantity; U and eq. 2 are kept beside it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "objective/UnbiasedObjective.h"
#include "transport/TransportMatrix.h"

namespace sl {

class TransportLoss;
struct ObjectiveOnT;

/// Where the held-out estimate comes from: one table (core/Registry.h) of the choices.
enum class HeldOutMode {
    Judge,  // the judge's estimate, traced from the scene with its own seed and cached
    File,   // a .tm with two halves, fitting the training T
    None    // no held-out scores
};
struct HeldOutModeRow {
    HeldOutMode value;
    const char* name;  // what the option takes ("FILE.tm": a path)
    const char* help;
};
std::span<const HeldOutModeRow> heldOutModeTable();

struct HeldOutSource {
    HeldOutMode mode = HeldOutMode::Judge;
    std::filesystem::path file;  // File
};
/// "judge", "none" or a path ending in .tm; InputError naming `where` otherwise.
HeldOutSource parseHeldOutSource(std::string_view text, const std::string& where);

struct HeldOutScore {
    LossParts own;       // the objective that was optimized
    LossParts unbiased;  // U (the noise-unbiased objective), whatever was optimized
    LossParts paper;     // the paper's eq. 2 (the common yardstick), on T = (T_a + T_b)/2
};

class HeldOutScorer {
  public:
    /// heldOut must have two planes. kind: the optimized objective; defects and reference: its
    /// regions (image space, the defects objective's; app/pipeline/Search.h SearchInputs). rgb: E
    /// has 3 values per texel.
    HeldOutScorer(const TransportMatrix& heldOut, const std::vector<uint8_t>& trainingMask,
                  const ObjectiveOptions& options, ObjectiveKind kind, bool rgb,
                  std::vector<uint8_t> defects = {}, std::vector<uint8_t> reference = {});
    ~HeldOutScorer();
    /// The scores of E on heldOut, through its own arrays (TransportLayout::Csr: no slices,
    /// no Gram built for a few evaluations).
    HeldOutScore score(std::span<const double> E) const;
    /// The loss U is scored through (for tests: its layout, and that no Gram was built).
    const TransportLoss& unbiasedLoss() const;

  private:
    ObjectiveKind kind_;
    std::unique_ptr<ObjectiveOnT> defects_;  // the defects objective on heldOut (Defects only)
    std::unique_ptr<ImageObjective> paper_;
    std::unique_ptr<UnbiasedObjective> unb_;
    std::unique_ptr<TransportLoss> paperLoss_, unbLoss_;  // built once, reused by score()
};

}  // namespace sl
