// One search for E* on transport matrices: which objective, which optimizer, on how many
// independent estimates of T, from which starts, through which λ continuation. `optimize`
// runs one search per λ; `bench race` runs many and the judge scores them.
//
//   estimates     K ≥ 1 independent estimates of T (app/pipeline/Transport.h
//                 transportSetForScene). With K > 1 every gradient evaluation uses the next
//                 estimate (objective/TransportLoss.h CyclingLoss): a fresh sample set per
//                 step, as the paper's loop.
//   starts        every start is optimized in turn and the lowest training loss wins
//                 (multistart); the specs of app/pipeline/InitialState.h.
//   continuation  λ factors run in turn before λ itself, each stage starting where the last
//                 ended (e.g. {4, 2}: λ·4, then λ·2, then λ).
//   light grid    the light's degrees of freedom: one value per texel, or a coarser grid of
//                 nodes interpolated onto the env map (objective/CoarseLight.h); every start
//                 is projected onto it, and E* is the interpolated light.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "app/pipeline/InitialState.h"
#include "core/Communicator.h"
#include "objective/CoarseLight.h"
#include "objective/HalfImageObjective.h"
#include "objective/Objective.h"
#include "objective/ObjectiveKind.h"
#include "objective/TransportLoss.h"
#include "optimize/Optimizer.h"
#include "transport/TransportMatrix.h"

namespace sl {

struct Scene;

struct SearchOptions {
    ObjectiveKind objective = ObjectiveKind::Paper;
    OptimizerOptions optimizer;  // method, budget, Adam's step (callback: see SearchInputs)
    int estimates = 1;
    std::vector<InitialState> starts{InitialState{}};  // default: const:0.5
    std::vector<double> continuation;
    /// The grid the light is searched on (objective/CoarseLight.h); default: one value per
    /// texel.
    LightGrid lightGrid;
};

struct SearchInputs {
    /// The estimates of T (at least options.estimates; set[0] is the main T). The unbiased
    /// objective needs two planes in each.
    std::vector<const TransportMatrix*> set;
    std::vector<uint8_t> mask;   // the loss mask (image space, nonzero inside)
    ObjectiveOptions objective;  // λ and the regulariser
    /// The defects objective's regions (image space, nonzero inside): the defects and the
    /// reference (empty: the defect-free part, objective/DefectObjective.h).
    std::vector<uint8_t> defects, reference;
    bool rgb = false;              // E has 3 values per texel
    const Scene* scene = nullptr;  // the `specular` start needs it
    int maxDepth = 0;              // ... and the path length of T
    /// E0 of every start in options.starts' order, when the caller has them already (empty:
    /// resolved here from the specs).
    std::vector<std::vector<double>> startValues;
    /// Sees every iteration of every start and stage (IterationRecord::iteration counts on
    /// across them); returning false stops the search.
    std::function<bool(const IterationRecord&, std::span<const double> x)> callback;
    /// Over MPI ranks: the rows of every T in `set` this rank holds (TransportLoss::distribute);
    /// default: one process, the whole T here. Every rank runs the same search in step.
    RowShard shard;
    /// Where set[0]'s Gram matrices are kept between runs, and set[0]'s fingerprint (its
    /// provenance's): a search whose objective reads them (TransportLoss::gramPays) reads them
    /// from there, or builds them before its first evaluation and stores them
    /// (app/pipeline/Cache.h cachedGram). Either empty: built by the loss as it goes, not kept.
    std::filesystem::path gramCache;
    std::string fingerprint;
};

struct SearchResult {
    std::vector<double> e;       // E* (the best start's)
    OptimizerSummary optimizer;  // the best start's last stage; iterations and evaluations
                                 // summed over every start and stage, seconds the whole search
    std::string start;           // the best start
    LossParts training;          // loss of E* on the training estimate(s) (mean over K)
    std::vector<std::pair<std::string, double>> startLosses;  // every start's training loss
    std::vector<std::vector<double>> startResults;  // every start's optimized E, in start order
};

SearchResult search(const SearchInputs& inputs, const SearchOptions& options);

/// The user's lamp when none is given (optimize's comparison, the `both` measure's anchor): the
/// studio preset on the env-map grid envWidth × envHeight, as E (with `rgb`, three values per
/// texel) as the judge reads a light.
std::vector<double> defaultLampE(int envWidth, int envHeight, bool rgb);

/// One objective of `kind` on one estimate of T and its loss through T (the objective must
/// outlive the loss: both are owned here). inputs: the mask, rgb and the defects' regions.
struct ObjectiveOnT {
    std::unique_ptr<ImageObjective> paper;       // paper
    std::unique_ptr<HalfImageObjective> halves;  // unbiased, defects
    std::unique_ptr<TransportLoss> loss;
};
ObjectiveOnT objectiveOnT(ObjectiveKind kind, const TransportMatrix& t, const SearchInputs& inputs,
                          const ObjectiveOptions& objective);

}  // namespace sl
