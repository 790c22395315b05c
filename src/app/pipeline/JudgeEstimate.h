// The judge's estimate of T for a training T: the judge's seed and spp (app/pipeline/Judge.h)
// applied to obtaining T (app/pipeline/Transport.h). Its own file so that Transport needs nothing
// of the judge and the judge's header alone includes Transport.
#pragma once

#include <filesystem>

#include "app/pipeline/Transport.h"

namespace sl {

/// The judge's estimate (app/pipeline/Judge.h) for a training T of `scene`: the same scene and path
/// length traced with the judge's seed, two sample sets, `spp` samples (0: the judge's
/// default), cached like transportForScene. The scene's inputs must match the training T's
/// apart from the sampling.
TransportSource judgeEstimateFor(const TransportFile& training, const Scene& scene, int spp,
                                 const std::filesystem::path& cacheDir);

}  // namespace sl
